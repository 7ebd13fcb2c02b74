// Binary masks as 8-bit single-channel PNG (0 background, 255 foreground),
// the form SAM-style segmenters are exported in.
#pragma once

#include <filesystem>

#include <opencv2/core.hpp>

namespace doasido::recon {

// Writes a CV_8UC1 mask; any non-zero pixel is written as 255. Throws
// Error("bad_array") for another image type, Error("io") naming the file.
void WriteMaskPng(const std::filesystem::path& path, const cv::Mat& mask);

// Reads an 8-bit single-channel PNG and returns CV_8UC1 with 0/255 (any
// non-zero pixel is foreground). Throws Error("bad_bundle") naming the file
// for a colour, 16-bit or undecodable image, Error("io") for a missing file.
cv::Mat ReadMaskPng(const std::filesystem::path& path);

}  // namespace doasido::recon
