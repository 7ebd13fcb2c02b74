#include "hands/hand_intrinsics.h"

#include <cmath>

#include "core/error.h"
#include "core/error_codes.h"

namespace doasido::hands {
namespace {


std::optional<double> Number(const Json& metadata, const char* key, const std::string& clip) {
  if (!metadata.is_object() || !metadata.contains(key)) return std::nullopt;
  const Json& v = metadata.at(key);
  if (v.is_null() || (v.is_string() && v.get<std::string>().empty())) return std::nullopt;
  double value = NAN;
  if (v.is_number()) {
    value = v.get<double>();
  } else if (v.is_string()) {
    try {
      size_t used = 0;
      value = std::stod(v.get<std::string>(), &used);
      if (used != v.get<std::string>().size()) value = NAN;
    } catch (const std::exception&) {
      value = NAN;
    }
  }
  if (!std::isfinite(value)) {
    throw Error(kBadIntrinsics, "not a number: " + v.dump(), {.clip = clip, .field = key});
  }
  return value;
}

void RequirePositive(double value, const char* key, const std::string& clip) {
  if (!(value > 0)) {
    throw Error(kBadIntrinsics, "must be positive, got " + std::to_string(value),
                         {.clip = clip, .field = key});
  }
}

}  // namespace

Mat3 KFromFov(int width, int height, double horizontal_fov_deg) {
  const double f = 0.5 * width / std::tan(0.5 * horizontal_fov_deg * M_PI / 180.0);
  Mat3 K;
  K << f, 0, 0.5 * (width - 1), 0, f, 0.5 * (height - 1), 0, 0, 1;
  return K;
}

std::optional<Intrinsics> IntrinsicsFromList(const Json& metadata, int width, int height,
                                             const std::string& clip) {
  const auto fx = Number(metadata, "fx", clip);
  const auto fov = Number(metadata, "fov", clip);
  if (!fx && !fov) return std::nullopt;
  Intrinsics out{.assumed = false, .source = kIntrinsicsFromList};
  if (fx) {
    RequirePositive(*fx, "fx", clip);
    const double fy = Number(metadata, "fy", clip).value_or(*fx);
    RequirePositive(fy, "fy", clip);
    out.K << *fx, 0, Number(metadata, "cx", clip).value_or(0.5 * (width - 1)), 0, fy,
        Number(metadata, "cy", clip).value_or(0.5 * (height - 1)), 0, 0, 1;
    return out;
  }
  if (!(*fov > 1 && *fov < 179)) {
    throw Error(kBadIntrinsics,
                         "horizontal field of view must be in (1, 179) degrees, got " +
                             std::to_string(*fov),
                         {.clip = clip, .field = "fov"});
  }
  out.K = KFromFov(width, height, *fov);
  return out;
}

Mat3 ScaleK(const Mat3& K, int bundle_width, int bundle_height, int width, int height) {
  if (bundle_width <= 0 || bundle_height <= 0) return K;
  const double sx = static_cast<double>(width) / bundle_width;
  const double sy = static_cast<double>(height) / bundle_height;
  Mat3 out = K;
  out(0, 0) *= sx;
  out(0, 2) = (K(0, 2) + 0.5) * sx - 0.5;
  out(1, 1) *= sy;
  out(1, 2) = (K(1, 2) + 0.5) * sy - 0.5;
  return out;
}

}  // namespace doasido::hands
