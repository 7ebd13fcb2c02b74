// Reconstruct (declared in recon/align/reconstruct.h): alignment, gravity, floor
// and the quality measurements of one bundle.
#include <algorithm>
#include <cmath>
#include <limits>

#include "recon/align/reconstruct.h"

namespace doasido::recon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// 1.4826 * median |log s - median log s| over aligned frames.
double ScaleSpread(const HandObjectAlignment& a) {
  std::vector<double> logs;
  for (const FrameAlignment& f : a.frames) {
    if (f.aligned) logs.push_back(std::log(f.scale));
  }
  const double m = Median(logs);
  for (double& x : logs) x = std::abs(x - m);
  return 1.4826 * Median(logs);
}

// The frame whose pose defines the floor: the first that moves less than
// rest_speed to the next posed frame, else the slowest.
int RestingFrame(const std::vector<Pose>& poses, const std::vector<bool>& valid, double rest_speed) {
  int slowest = -1;
  double slowest_speed = 1e30;
  const int T = static_cast<int>(poses.size());
  for (int t = 0; t < T; ++t) {
    if (!valid[t]) continue;
    if (slowest < 0) slowest = t;
    if (t + 1 >= T || !valid[t + 1]) continue;
    const double speed = (poses[t + 1].t - poses[t].t).norm();
    if (speed < rest_speed) return t;
    if (speed < slowest_speed) {
      slowest_speed = speed;
      slowest = t;
    }
  }
  return slowest;
}

// Distance from the nearest right-hand joint to the nearest posed object point.
double HandObjectDistance(const Joints21& joints, const std::vector<Vec3>& object_points,
                          const Pose& pose) {
  double best = 1e30;
  for (const Vec3& x : object_points) {
    const Vec3 p = pose * x;
    for (int j = 0; j < 21; ++j) best = std::min(best, (joints.row(j).transpose() - p).norm());
  }
  return best;
}

std::vector<Vec3> SubsampledVertices(const TriMesh& mesh, int max_points) {
  std::vector<Vec3> out;
  const int n = mesh.num_vertices();
  const int step = std::max(1, n / max_points);
  for (int v = 0; v < n; v += step) out.push_back(mesh.vertices.row(v));
  return out;
}

void AddQuality(ReconOutput& out, const TriMesh& mesh) {
  const Reconstruction& r = out.reconstruction;
  const std::vector<Vec3> points = SubsampledVertices(mesh, 400);
  std::vector<double> distance(r.frames(), kNaN), jitter;
  for (int t = 0; t < r.frames(); ++t) {
    if (r.right_valid[t] && r.object_valid[t]) {
      distance[t] = HandObjectDistance(r.right_joints[t], points, r.object_poses[t]);
    }
    if (t > 0 && t + 1 < r.frames() && r.object_valid[t - 1] && r.object_valid[t] &&
        r.object_valid[t + 1]) {
      jitter.push_back((r.object_poses[t + 1].t - 2 * r.object_poses[t].t + r.object_poses[t - 1].t).norm());
    }
  }
  Json series = Json::array();
  for (double d : distance) series.push_back(std::isfinite(d) ? Json(d) : Json(nullptr));
  Json& m = out.measurements;
  m[kMeasureHandObjectDistance] = series;
  const double median_distance = Median(distance);
  m[kMeasureHandObjectDistanceMedian] = std::isfinite(median_distance) ? Json(median_distance) : Json(nullptr);
  const double median_jitter = Median(jitter);
  m[kMeasurePoseJitter] = std::isfinite(median_jitter) ? Json(median_jitter) : Json(nullptr);
}

// The object's poses in the gravity-aligned frame (rotation R), valid where
// the alignment found a scale.
void PlaceObject(const HandObjectAlignment& a, const Mat3& R, int T, Reconstruction& r) {
  r.object_valid.assign(T, false);
  r.object_poses.assign(T, Pose::Identity());
  for (int t = 0; t < T; ++t) {
    if (!std::isfinite(a.scale[t])) continue;
    r.object_valid[t] = true;
    r.object_poses[t] = {Quat(R) * a.poses[t].q, R * a.poses[t].t};
  }
}

// The height of the posed mesh's lowest vertex on frame t.
double LowestPoint(const TriMesh& mesh, const Reconstruction& r, int t) {
  double low = 1e30;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    low = std::min(low, (r.object_poses[t] * Vec3(mesh.vertices.row(v).transpose())).z());
  }
  return low;
}

// The floor: the mesh's lowest vertex at the resting frame, lowered to the
// lowest the object gets on any posed frame when that is lower (an object
// never passes through its support; a held cup that pauses in the air
// before it is set down, 02_cups' first second, would otherwise be put on
// the floor there and pushed through it later). 0 without a resting
// frame. `lowest` gets the frame that sets it.
double FloorHeight(const TriMesh& mesh, const Reconstruction& r, int rest, int* lowest) {
  *lowest = rest;
  if (rest < 0) return 0;
  double floor_h = LowestPoint(mesh, r, rest);
  for (int t = 0; t < static_cast<int>(r.object_poses.size()); ++t) {
    if (!r.object_valid[t]) continue;
    const double low = LowestPoint(mesh, r, t);
    if (low < floor_h) floor_h = low, *lowest = t;
  }
  return floor_h;
}

// A hand's joints in the gravity-aligned frame, floor at z = 0.
void PlaceHand(const HandTrack& h, const Mat3& R, double floor_h, int T, std::vector<bool>& valid,
               std::vector<Joints21>& joints) {
  valid.assign(T, false);
  joints.assign(T, Joints21::Zero());
  for (int t = 0; t < T && static_cast<size_t>(t) < h.joints.size(); ++t) {
    valid[t] = static_cast<size_t>(t) < h.valid.size() ? static_cast<bool>(h.valid[t]) : true;
    joints[t] = (h.joints[t] * R.transpose()).eval();
    joints[t].col(2).array() -= floor_h;
  }
}

// Frame counts, the share of posed frames the alignment used, the scale's
// median and spread, and the gravity's source and inliers.
void AddAlignmentMeasurements(ReconOutput& out, const std::vector<bool>& pose_valid, int T) {
  const HandObjectAlignment& a = out.alignment;
  int posed = 0;
  for (int t = 0; t < T; ++t) posed += static_cast<size_t>(t) < pose_valid.size() && pose_valid[t];
  Json& m = out.measurements;
  m[kMeasureFrames] = T;
  m[kMeasurePosedFrames] = posed;
  m[kMeasureAlignedFrames] = a.aligned_frames;
  m[kMeasureEvidenceShare] = posed ? double(a.aligned_frames) / posed : 0.0;
  std::vector<double> raw;
  for (const FrameAlignment& f : a.frames) raw.push_back(f.aligned ? f.scale : kNaN);
  const double median_scale = Median(raw);
  m[kMeasureScaleMedian] = std::isfinite(median_scale) ? Json(median_scale) : Json(nullptr);
  const double spread = ScaleSpread(a);
  m[kMeasureScaleSpread] = std::isfinite(spread) ? Json(spread) : Json(nullptr);
  m[kMeasureGravitySource] = out.gravity.source;
  m[kMeasureGravityInlierShare] =
      std::isfinite(out.gravity.inlier_share) ? Json(out.gravity.inlier_share) : Json(nullptr);
}

// The reconstruction's `info`: units, world frame, gravity, floor and the
// alignment frame by frame (with the frames it skipped, by why).
Json ReconstructionInfo(const ReconOutput& out, const ReconStageConfig& config, int T, int rest,
                        double floor_h) {
  const HandObjectAlignment& a = out.alignment;
  Json frames = Json::array();
  Json skipped = Json::object();
  for (int t = 0; t < T; ++t) {
    const FrameAlignment& f = a.frames[t];
    frames.push_back({{"fill", a.fill[t]},
                      {"scale", std::isfinite(a.scale[t]) ? Json(a.scale[t]) : Json(nullptr)},
                      {"k", f.aligned ? Json(f.k) : Json(nullptr)},
                      {"hand_hits", f.hand_hits},
                      {"skipped", f.skipped}});
    if (!f.aligned) skipped[f.skipped].push_back(t);
  }
  return {{"units", "m"},
          {"world", "gravity -z, floor z = 0 under the object's resting pose"},
          {"gravity", {{"source", out.gravity.source},
                       {"up_camera", {out.gravity.up.x(), out.gravity.up.y(), out.gravity.up.z()}},
                       {"inlier_share", out.measurements.at(kMeasureGravityInlierShare)},
                       {"fitted_frame", out.gravity.frame},
                       {"spread_deg", out.gravity.spread_deg}}},
          {"floor", {{"resting_frame", rest}, {"camera_frame_height", floor_h}}},
          {"alignment", {{"config", config.alignment},
                         {"aligned_frames", a.aligned_frames},
                         {"skipped_frames", skipped},
                         {"frames", frames}}}};
}

// The alignment of poses that are already metric: every posed frame kept
// with scale 1.
HandObjectAlignment MetricAlignment(const std::vector<Pose>& poses,
                                    const std::vector<bool>& pose_valid, int T) {
  HandObjectAlignment a;
  a.frames.assign(T, FrameAlignment{});
  a.scale.assign(T, kNaN);
  a.fill.assign(T, kFillNone);
  a.poses.assign(T, Pose::Identity());
  for (int t = 0; t < T && static_cast<size_t>(t) < poses.size(); ++t) {
    if (static_cast<size_t>(t) < pose_valid.size() && !pose_valid[t]) {
      a.frames[t].skipped = kSkipNoPose;
      continue;
    }
    a.frames[t].aligned = true;
    a.frames[t].k = a.frames[t].scale = a.scale[t] = 1;
    a.fill[t] = kFillMetric;
    a.poses[t] = poses[t];
    ++a.aligned_frames;
  }
  return a;
}

}  // namespace

bool ObjectPosesAreMetric(const ClipBundle& b) {
  return b.producers.is_object() && b.producers.contains(kObjectScaleProducer);
}

ReconOutput Reconstruct(const ClipBundle& b, const std::vector<Pose>& poses,
                        const std::vector<bool>& pose_valid, const ReconStageConfig& config) {
  ReconOutput out;
  out.alignment = ObjectPosesAreMetric(b) ? MetricAlignment(poses, pose_valid, b.frames)
                                          : AlignHandObject(b, poses, pose_valid, config.alignment);
  out.gravity = EstimateGravity(b, config.gravity);
  const Mat3 R = UpToZ(out.gravity.up);
  out.camera_to_world = R;
  Reconstruction& r = out.reconstruction;
  r.fps = b.fps > 0 ? b.fps : 30.0;
  PlaceObject(out.alignment, R, b.frames, r);
  const int rest = RestingFrame(r.object_poses, r.object_valid, config.rest_speed);
  int lowest = -1;
  const double floor_h = FloorHeight(*b.object_mesh, r, rest, &lowest);
  out.floor_offset = floor_h;
  for (Pose& p : r.object_poses) p.t.z() -= floor_h;
  r.right_valid.assign(b.frames, false);
  r.right_joints.assign(b.frames, Joints21::Zero());
  if (b.hand_right) PlaceHand(*b.hand_right, R, floor_h, b.frames, r.right_valid, r.right_joints);
  if (b.hand_left) PlaceHand(*b.hand_left, R, floor_h, b.frames, r.left_valid, r.left_joints);
  r.floor_z = 0;
  AddAlignmentMeasurements(out, pose_valid, b.frames);
  AddQuality(out, *b.object_mesh);
  r.info = ReconstructionInfo(out, config, b.frames, rest, floor_h);
  r.info["floor"]["lowest_frame"] = lowest;
  return out;
}

}  // namespace doasido::recon
