// Checking a hand description against its model (`doasido hand check`):
// the chains the generator finds (hand_description.h), every joint's range
// and actuator, and the problems that would make retargeting or control go
// wrong, each with what to do about it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robot/embodiment.h"
#include "robot/hand_description.h"
#include "robot/mj_model.h"

namespace doasido::retarget {

// Problem codes (HandProblem::code).
inline constexpr const char* kMissingBodyProblem = "missing_body";        // point names no body/site
inline constexpr const char* kUnlimitedJointProblem = "unlimited_joint";  // finger joint without limits
inline constexpr const char* kActuatorRangeProblem = "actuator_out_of_range";  // ctrlrange beyond the joint's
inline constexpr const char* kTipNotDistalProblem = "fingertip_not_distal";     // tip off a chain's end
inline constexpr const char* kThumbMismatchProblem = "thumb_mismatch";  // keypoint 4 not on the opposing chain
inline constexpr const char* kNoChainsProblem = "no_chains";            // fewer than two finger chains

struct HandProblem {
  std::string code;
  std::string message;  // what is wrong, where, and what to change
};

struct JointReport {
  std::string name;
  std::string finger;       // chain it belongs to ("" = wrist or palm)
  bool limited = false;
  double lo = 0, hi = 0;    // range (rad or m)
  std::string actuator;     // "" = none
  bool ctrl_limited = false;
  double ctrl_lo = 0, ctrl_hi = 0;
};

struct HandCheck {
  Embodiment embodiment;
  std::string xml;           // the prepared hand MJCF (mjcf_compat), no floating wrist
  ModelPtr model;            // compiled from xml
  HandStructure structure;   // empty chains when the generator found none
  std::vector<JointReport> joints;
  std::vector<HandProblem> problems;
};

// Loads the description (LoadEmbodiment; its refusals are thrown) and its
// model (PrepareMjcf; thrown too), then collects the report. Problems are
// returned, not thrown.
HandCheck CheckHand(const std::filesystem::path& description, const std::filesystem::path& robots_dir = {});
// The same for a loaded description (FindEmbodiment, LoadEmbodiment).
HandCheck CheckHand(const Embodiment& embodiment);

// qpos of `m` with every flexion joint of `s` at `fraction` of the way from 0
// (clamped into range) to the end of its range farther from 0, the others
// at 0 clamped into range.
Eigen::VectorXd FlexedPose(const mjModel* m, const HandStructure& s, double fraction);

}  // namespace doasido::retarget
