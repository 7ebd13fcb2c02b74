#include "recon/bundle/mask_io.h"

#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace doasido::recon {
namespace {

std::string TypeName(const cv::Mat& m) {
  return std::to_string(m.channels()) + "-channel " +
         (m.depth() == CV_8U ? "8-bit" : m.depth() == CV_16U ? "16-bit" : "non-8-bit");
}

}  // namespace

void WriteMaskPng(const std::filesystem::path& path, const cv::Mat& mask) {
  const std::string file = path.string();
  if (mask.type() != CV_8UC1 || mask.empty()) {
    throw Error("bad_array", "mask must be a non-empty CV_8UC1 image, got " + TypeName(mask),
                {.file = file});
  }
  cv::Mat binary;
  cv::threshold(mask, binary, 0, 255, cv::THRESH_BINARY);
  bool ok = false;
  try {
    ok = cv::imwrite(file, binary, {cv::IMWRITE_PNG_COMPRESSION, 3});
  } catch (const cv::Exception& e) {
    throw Error("io", std::string("cannot write PNG: ") + e.what(), {.file = file});
  }
  if (!ok) throw Error("io", "cannot write PNG", {.file = file});
}

cv::Mat ReadMaskPng(const std::filesystem::path& path) {
  const std::string file = path.string();
  if (!std::filesystem::exists(path)) throw Error("io", "file does not exist", {.file = file});
  const cv::Mat raw = cv::imread(file, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw Error("bad_bundle", "cannot decode image", {.file = file});
  if (raw.type() != CV_8UC1) {
    throw Error("bad_bundle", "mask must be 8-bit single-channel, got " + TypeName(raw),
                {.file = file, .field = "mask"});
  }
  cv::Mat binary;
  cv::threshold(raw, binary, 0, 255, cv::THRESH_BINARY);
  return binary;
}

}  // namespace doasido::recon
