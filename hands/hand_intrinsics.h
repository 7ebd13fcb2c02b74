// Where the camera's intrinsics come from, in order: a bundle's K (the list
// names a bundle with K.npz), the list's columns fx, fy, cx, cy (fy defaults
// to fx, cx and cy to the image centre) or fov (horizontal, degrees), else
// the default field of view, recorded as assumed. All in pixels of the video
// as displayed; a bundle's K made for another size is scaled to this one.
#pragma once

#include <optional>
#include <string>

#include "core/config.h"
#include "core/geometry.h"

namespace doasido::hands {

// Where K came from, as recorded in measurements and keypoints.json.
inline constexpr const char* kIntrinsicsFromBundle = "bundle";
inline constexpr const char* kIntrinsicsFromList = "list";
inline constexpr const char* kIntrinsicsFromOption = "option";
inline constexpr const char* kIntrinsicsFromDefault = "default_fov";

struct Intrinsics {
  Mat3 K = Mat3::Identity();
  bool assumed = true;  // the default field of view, not a measurement
  std::string source;   // one of the constants above
};

// fx = fy = (width / 2) / tan(fov / 2), principal point at the centre
// ((width - 1) / 2, (height - 1) / 2: pixel centres are integers).
Mat3 KFromFov(int width, int height, double horizontal_fov_deg);

// From a list row's columns (numbers, or strings holding numbers); nullopt
// when it has neither fx nor fov. Throws Error(kBadIntrinsics) (permanent)
// naming the clip and the column for a value that is not a number or out of
// range (focal length not positive, fov outside (1, 179) degrees).
std::optional<Intrinsics> IntrinsicsFromList(const Json& metadata, int width, int height,
                                             const std::string& clip);

// K of a bundle made at `bundle_width` x `bundle_height`, for frames of
// `width` x `height` (scaled per axis).
Mat3 ScaleK(const Mat3& K, int bundle_width, int bundle_height, int width, int height);

}  // namespace doasido::hands
