// Step 4's between-frames check (plan.h PathDeviation): forward kinematics
// of every path command against the wrist path at the command's trajectory
// time. The IK answers only at the frames; this is what the arm does in
// between, at the rate it will be commanded.
#include <algorithm>
#include <cmath>

#include "core/config_check.h"
#include "deploy/plan.h"
#include "deploy/replay_rig.h"
#include "deploy/time_scaling.h"

namespace doasido::deploy {
namespace {

// The largest change of one joint between consecutive frames in [from, to].
double LargestJointStep(const std::vector<ArmQ>& frame_q, int from, int to) {
  double jump = 0;
  for (int f = std::max(from, 0); f < to && f + 1 < static_cast<int>(frame_q.size()); ++f) {
    jump = std::max(jump, (frame_q[f + 1] - frame_q[f]).cwiseAbs().maxCoeff());
  }
  return jump;
}

}  // namespace

void CheckConfig(const PathCheckConfig& c, const std::string& section) {
  RequireInRange(section, "position_tolerance", c.position_tolerance, 1e-4, 1);
  RequireInRange(section, "rotation_tolerance", c.rotation_tolerance, 1e-3, 3.2);
}

JointSpline JointPathThroughFrames(const std::vector<ArmQ>& frame_q, double fps) {
  std::vector<double> knots;
  std::vector<Eigen::VectorXd> values;
  for (size_t f = 0; f < frame_q.size(); ++f) {
    knots.push_back(f / fps);
    values.push_back(frame_q[f]);
  }
  return JointSpline(knots, values);
}

SplineDeviation JointSplineDeviation(const std::vector<ArmQ>& frame_q, const std::vector<Pose>& wrists, double fps,
                                     int samples) {
  SplineDeviation out;
  if (frame_q.size() < 2) return out;
  const JointSpline spline = JointPathThroughFrames(frame_q, fps);
  for (size_t f = 0; f + 1 < frame_q.size(); ++f) {
    for (int i = 1; i < samples; ++i) {
      const double s = (f + double(i) / samples) / fps;
      const Pose flange = DhForwardPose(spline.Value(s)), target = replay::PoseAt(wrists, fps, s);
      out.position = std::max(out.position, (flange.t - target.t).norm());
      out.rotation = std::max(out.rotation, RotationAngle(flange.q, target.q));
    }
  }
  return out;
}

int PathDeviation::OffPathCommands() const {
  int n = 0;
  for (const OffPathSpan& s : off_path) n += s.commands;
  return n;
}

PathDeviation CheckPathDeviation(const Plan& plan, const std::vector<Pose>& wrists, double fps,
                                 const std::vector<ArmQ>& frame_q, const PathCheckConfig& config) {
  PathDeviation out;
  out.checked = true;
  out.position_tolerance = config.position_tolerance;
  out.rotation_tolerance = config.rotation_tolerance;
  const int end = static_cast<int>(plan.arm.size()) - plan.lead_out;
  OffPathSpan* open = nullptr;  // the run the last command extended, if any
  for (int k = plan.lead_in; k < end; ++k) {
    const double s = plan.source_times[k];
    const Pose target = replay::PoseAt(wrists, fps, s);
    const Pose flange = DhForwardPose(plan.arm[k]);
    const double position = (flange.t - target.t).norm(), rotation = RotationAngle(flange.q, target.q);
    if (position > out.position_max) {
      out.position_max = position;
      out.worst_command = k;
    }
    out.rotation_max = std::max(out.rotation_max, rotation);
    if (position <= config.position_tolerance && rotation <= config.rotation_tolerance) {
      open = nullptr;
      continue;
    }
    const int frame = static_cast<int>(std::floor(s * fps));
    if (!open && !out.off_path.empty() && out.off_path.back().to_frame >= frame) open = &out.off_path.back();
    if (!open) {
      out.off_path.push_back({.first_command = k, .start_time = plan.times[k], .from_frame = frame});
      open = &out.off_path.back();
    }
    open->last_command = k;
    ++open->commands;
    open->end_time = plan.times[k];
    open->to_frame = std::min(static_cast<int>(std::ceil(s * fps)), static_cast<int>(wrists.size()) - 1);
    open->to_frame = std::max(open->to_frame, open->from_frame);
    open->position_deviation = std::max(open->position_deviation, position);
    open->rotation_deviation = std::max(open->rotation_deviation, rotation);
  }
  for (OffPathSpan& span : out.off_path) span.joint_jump = LargestJointStep(frame_q, span.from_frame, span.to_frame);
  return out;
}

}  // namespace doasido::deploy
