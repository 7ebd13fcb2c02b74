// Single-channel float32 depth images in OpenEXR, the format MoGe-style
// adapters write depth in. Depth is metric (metres, along the camera z axis);
// +inf and 0 mark pixels without a valid depth.
#pragma once

#include <cmath>
#include <filesystem>

#include <opencv2/core.hpp>

namespace doasido::recon {

inline bool IsValidDepth(float z) { return std::isfinite(z) && z > 0.0f; }

// Writes a CV_32FC1 image as one float32 channel named "Z" (lossless ZIP
// compression). Throws Error("io") naming the file, or Error("bad_array")
// for an image of another type.
void WriteDepthExr(const std::filesystem::path& path, const cv::Mat& depth);

// Reads the depth channel: "Z" if present, else "Y", else "R", else the only
// channel of a single-channel file; half and uint channels are converted to
// float. Returns CV_32FC1 of the data window's size. Throws
// Error("bad_bundle") naming the file (and the channel list) when no channel
// qualifies, Error("io") when the file cannot be read.
cv::Mat ReadDepthExr(const std::filesystem::path& path);

// Point maps (camera-frame X, Y, Z per pixel, metres; MoGe's output) as
// three float32 channels "X", "Y", "Z". Non-finite values mark invalid
// pixels. Write takes and read returns CV_32FC3 with channels in X, Y, Z
// order. Read throws Error("bad_bundle") naming the file when a channel is
// missing, Error("io") when the file cannot be read.
void WritePointsExr(const std::filesystem::path& path, const cv::Mat& points);
cv::Mat ReadPointsExr(const std::filesystem::path& path);

}  // namespace doasido::recon
