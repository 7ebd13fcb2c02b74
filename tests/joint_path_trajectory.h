// A floating-wrist trajectory made from a UR3e joint path, so the arm's
// joints, and hence the speeds a plan must respect, are known exactly
// (deploy_time_scaling_test, cli_deploy_test).
#pragma once

#include <functional>

#include "deploy/plan.h"
#include "deploy/ur3e.h"
#include "robot/embodiment.h"
#include "robot/trajectory/format.h"

namespace doasido::testing {

// `frames` at `fps` whose wrist poses are the flange of q(t), t = frame /
// fps, in the arm's base frame.
inline retarget::HandTrajectory FromJointPath(const std::function<deploy::ArmQ(double)>& q, int frames,
                                              double fps) {
  retarget::HandTrajectory t;
  t.embodiment = "sharpa_right";
  t.fps = fps;
  t.qpos_names = {"doasido_wrist_x",  "doasido_wrist_y",  "doasido_wrist_z",
                  "doasido_wrist_rx", "doasido_wrist_ry", "doasido_wrist_rz"};
  for (int k = 0; k < frames; ++k) {
    const Pose w = deploy::DhForwardPose(q(k / fps));
    const Vec3 e = w.R().eulerAngles(0, 1, 2);  // R = Rx Ry Rz
    Eigen::VectorXd v(6);
    v << w.t, e;
    t.qpos.push_back(v);
    t.valid.push_back(true);
    t.fingertip_error.push_back(0);
  }
  return t;
}

// Planned where the trajectory's world is the base frame, from `home`; the
// IK recovers the path when home = q(0).
inline deploy::Plan PlanInBaseFrame(const retarget::HandTrajectory& t, const deploy::ArmQ& home,
                                    deploy::PlanConfig config = {}) {
  for (int i = 0; i < 6; ++i) config.home[i] = home[i];
  // The exact joint path: these plans measure the re-timing on it, not the
  // wrist smoothing (deploy_wrist_smoothing_test does that).
  config.wrist_smoothing.cutoff_hz = 0;
  deploy::Placement identity;
  identity.world_to_base = Pose::Identity();
  return deploy::MakePlan(t, retarget::FindEmbodiment("sharpa_right", {}), config, &identity);
}

}  // namespace doasido::testing
