#include "synth/defects.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "synth/episode.h"

namespace doasido::synth {
namespace {

constexpr const char* kNames[kDefectKindCount] = {
    "clean", "cut",          "fade",       "black",      "pan",   "shake",
    "zoom",  "out_of_frame", "object_out", "no_contact", "static"};

Pose RotateCamera(const Pose& cw, const Mat3& delta) {
  const Quat d(delta);
  return {d * cw.q, d * cw.t};  // rotation about the camera centre
}

}  // namespace

const char* DefectName(DefectKind kind) { return kNames[static_cast<int>(kind)]; }

DefectKind DefectFromName(const std::string& name) {
  for (int i = 0; i < kDefectKindCount; ++i) {
    if (name == kNames[i]) return static_cast<DefectKind>(i);
  }
  throw Error("bad_config",
              "unknown defect '" + name +
                  "' (clean, cut, fade, black, pan, shake, zoom, out_of_frame, object_out, "
                  "no_contact, static)",
              {.field = "mix"});
}

Json ToJson(const DefectRecord& r) {
  return Json{{"kind", r.kind}, {"start", r.start}, {"end", r.end}, {"params", r.params}};
}

CameraTrack StaticCamera(const Camera& camera, const Pose& cw, int frames) {
  CameraTrack t;
  t.camera.assign(frames, camera);
  t.camera_from_world.assign(frames, cw);
  return t;
}

void ApplyPan(CameraTrack& track, int start, int end, double rad_per_frame) {
  const int n = static_cast<int>(track.camera.size());
  for (int t = 0; t < n; ++t) {
    const int steps = std::clamp(t - start + 1, 0, end - start + 1);
    const Mat3 yaw = Eigen::AngleAxisd(rad_per_frame * steps, Vec3::UnitY()).toRotationMatrix();
    track.camera_from_world[t] = RotateCamera(track.camera_from_world[t], yaw);
  }
}

void ApplyShake(CameraTrack& track, int start, int end, double amplitude, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, amplitude);
  double ax = 0, ay = 0;
  for (int t = start; t <= end && t < static_cast<int>(track.camera.size()); ++t) {
    ax = 0.4 * ax + noise(rng);
    ay = 0.4 * ay + noise(rng);
    const Mat3 d = (Eigen::AngleAxisd(ax, Vec3::UnitX()) * Eigen::AngleAxisd(ay, Vec3::UnitY()))
                       .toRotationMatrix();
    track.camera_from_world[t] = RotateCamera(track.camera_from_world[t], d);
  }
}

void ApplyZoom(CameraTrack& track, int start, int end, double factor) {
  const int n = static_cast<int>(track.camera.size());
  for (int t = 0; t < n; ++t) {
    const double s = MinJerk(end > start ? double(t - start) / (end - start) : t >= start);
    const double k = 1 + (factor - 1) * s;
    track.camera[t].fx *= k;
    track.camera[t].fy *= k;
  }
}

Mat3 ViewHomography(const Camera& a, const Pose& a_cw, const Camera& b, const Pose& b_cw) {
  return b.K() * (b_cw.R() * a_cw.R().transpose()) * a.K().inverse();
}

Vec2 Displacement(const Mat3& h, double u, double v) {
  const Vec3 p = h * Vec3(u, v, 1);
  return Vec2(p.x() / p.z() - u, p.y() / p.z() - v);
}

cv::Mat CrossFade(const cv::Mat& a, const cv::Mat& b, double w) {
  cv::Mat out;
  cv::addWeighted(a, 1 - w, b, w, 0.0, out);
  return out;
}

cv::Mat Dim(const cv::Mat& a, double gain) {
  cv::Mat out;
  a.convertTo(out, -1, gain, 0.0);
  return out;
}

}  // namespace doasido::synth
