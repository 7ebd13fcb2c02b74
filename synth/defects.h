// Defects injected into synthetic clips, each with exactly known extent, so
// that filters (shot boundaries, camera motion, out-of-frame, interaction)
// can be scored frame by frame:
//   cut           hard cut to a different scene at frame `start` (= end)
//   fade          cross-fade from scene A to scene B over [start, end]
//   black         fade to black over [start, end] (or from black at the clip start)
//   pan           camera yaws about its own centre over [start, end]
//   shake         small random camera rotations every frame in [start, end]
//   zoom          focal length ramps by a factor over [start, end]
//   out_of_frame  the active hand leaves the view for [start, end]
//   object_out    the object (carried by the hand) leaves the view for [start, end]
//   no_contact    the hand comes near the object but never touches it
//   static        nothing moves for the whole clip
// Camera motion keeps the camera centre fixed, so the image motion of the
// whole static background between frames is exactly the homography
// H = K_t R_t R_{t-1}^T K_{t-1}^-1, recorded per frame.
#pragma once

#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"

namespace doasido::synth {

enum class DefectKind {
  kClean,
  kCut,
  kCrossFade,
  kFadeBlack,
  kPan,
  kShake,
  kZoom,
  kHandOut,
  kObjectOut,
  kNoContact,
  kStatic,
};
constexpr int kDefectKindCount = 11;

// Spec names: clean, cut, fade, black, pan, shake, zoom, out_of_frame,
// object_out, no_contact, static.
const char* DefectName(DefectKind kind);
// Throws Error("bad_config", field "mix") for an unknown name.
DefectKind DefectFromName(const std::string& name);

// A recorded defect: frames [start, end], 0-based inclusive.
struct DefectRecord {
  std::string kind;
  int start = 0;
  int end = 0;
  Json params = Json::object();
};
Json ToJson(const DefectRecord& record);

// Per-frame camera: intrinsics and world -> camera pose.
struct CameraTrack {
  std::vector<Camera> camera;
  std::vector<Pose> camera_from_world;
};
CameraTrack StaticCamera(const Camera& camera, const Pose& camera_from_world, int frames);

// Yaws (about the camera's own y axis) by `rad_per_frame` each frame in
// [start, end] and holds the reached orientation afterwards.
void ApplyPan(CameraTrack& track, int start, int end, double rad_per_frame);
// Random rotations (about camera x and y, smoothed, std `amplitude` rad)
// relative to the base orientation, in [start, end].
void ApplyShake(CameraTrack& track, int start, int end, double amplitude, std::mt19937_64& rng);
// Focal length multiplied by a min-jerk ramp from 1 to `factor` over
// [start, end], held afterwards.
void ApplyZoom(CameraTrack& track, int start, int end, double factor);

// Homography taking pixels of view a to pixels of view b for a camera that
// only rotates and zooms about a fixed centre.
Mat3 ViewHomography(const Camera& a, const Pose& a_cw, const Camera& b, const Pose& b_cw);
// Image displacement of pixel (u, v) under h.
Vec2 Displacement(const Mat3& h, double u, double v);

// (1 - w) a + w b, rounded.
cv::Mat CrossFade(const cv::Mat& a, const cv::Mat& b, double w);
// Multiplies brightness by `gain` in [0, 1].
cv::Mat Dim(const cv::Mat& a, double gain);

}  // namespace doasido::synth
