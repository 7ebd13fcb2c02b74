#include "video/weighed_pixels.h"

#include <algorithm>
#include <cmath>

#include "video/sws_buffer.h"

extern "C" {
#include <libswscale/swscale.h>
}

namespace doasido {

std::vector<int> WeighedTaps(int source, int target) {
  // OpenCV's hal::resize for INTER_LINEAR: the output's centre mapped back
  // in double, rounded to float, its floor the first tap and the rest the
  // second tap's fraction; taps outside the image clamp to its edge.
  const double scale = 1.0 / (static_cast<double>(target) / source);
  std::vector<int> taps;
  for (int d = 0; d < target; ++d) {
    float f = static_cast<float>((d + 0.5) * scale - 0.5);
    const int s = static_cast<int>(std::floor(f));
    f -= static_cast<float>(s);
    taps.push_back(std::clamp(s, 0, source - 1));
    if (f != 0.0f && s >= 0 && s < source - 1) taps.push_back(s + 1);
  }
  std::sort(taps.begin(), taps.end());
  taps.erase(std::unique(taps.begin(), taps.end()), taps.end());
  return taps;
}

WeighedPixels::WeighedPixels(cv::Size full, cv::Size target, int sws_flags)
    : full_(full),
      columns_(WeighedTaps(full.width, target.width)),
      rows_(WeighedTaps(full.height, target.height)) {
  // Two Y columns per weighed pixel, and a width libswscale's vector
  // converters take whole (a multiple of 16).
  small_width_ = (2 * static_cast<int>(columns_.size()) + 15) / 16 * 16;
  const int small_height = 2 * static_cast<int>(rows_.size());
  y_.resize(static_cast<std::size_t>(small_width_ / 2) * small_height);
  u_.resize(static_cast<std::size_t>(small_width_ / 2) * rows_.size());
  v_.resize(u_.size());
  sws_flags_ = sws_flags;
}

WeighedPixels::~WeighedPixels() { sws_freeContext(sws_); }

double WeighedPixels::fraction() const {
  return static_cast<double>(columns_.size()) * rows_.size() /
         (static_cast<double>(full_.width) * full_.height);
}

bool WeighedPixels::Convert(const std::uint8_t* const planes[3], const int strides[3],
                            cv::Mat* full_bgr) {
  const int small_height = 2 * static_cast<int>(rows_.size());
  if (sws_ == nullptr) {
    sws_ = sws_getContext(small_width_, small_height, AV_PIX_FMT_YUV420P, small_width_,
                          small_height, AV_PIX_FMT_BGR24, sws_flags_, nullptr, nullptr, nullptr);
    if (sws_ == nullptr) return false;
  }
  const int columns = static_cast<int>(columns_.size());
  const int half = small_width_ / 2;
  // Each weighed pixel's Y fills its 2x2 block (two 16-bit stores per row);
  // the padding columns keep the zeros they were made with.
  for (std::size_t j = 0; j < rows_.size(); ++j) {
    const int r = rows_[j];
    const std::uint8_t* y = planes[0] + static_cast<std::ptrdiff_t>(r) * strides[0];
    const std::uint8_t* u = planes[1] + static_cast<std::ptrdiff_t>(r / 2) * strides[1];
    const std::uint8_t* v = planes[2] + static_cast<std::ptrdiff_t>(r / 2) * strides[2];
    std::uint16_t* y0 = &y_[2 * j * half];
    std::uint16_t* y1 = y0 + half;
    std::uint8_t* uj = &u_[j * half];
    std::uint8_t* vj = &v_[j * half];
    for (int i = 0; i < columns; ++i) {
      const int c = columns_[i];
      y0[i] = y1[i] = static_cast<std::uint16_t>(y[c] * 0x0101);
      uj[i] = u[c >> 1];
      vj[i] = v[c >> 1];
    }
  }
  EnsureSwsOutput(&small_bgr_, small_height, small_width_);
  const std::uint8_t* const small_planes[3] = {reinterpret_cast<const std::uint8_t*>(y_.data()),
                                               u_.data(), v_.data()};
  const int small_strides[3] = {small_width_, half, half};
  std::uint8_t* out[1] = {small_bgr_.data};
  const int out_strides[1] = {static_cast<int>(small_bgr_.step[0])};
  if (sws_scale(sws_, small_planes, small_strides, 0, small_height, out, out_strides) !=
      small_height) {
    return false;
  }
  for (std::size_t j = 0; j < rows_.size(); ++j) {
    const cv::Vec3b* block = small_bgr_.ptr<cv::Vec3b>(static_cast<int>(2 * j));
    cv::Vec3b* row = full_bgr->ptr<cv::Vec3b>(rows_[j]);
    for (int i = 0; i < columns; ++i) row[columns_[i]] = block[2 * i];
  }
  return true;
}

}  // namespace doasido
