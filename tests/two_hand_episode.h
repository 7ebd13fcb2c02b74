// A synthetic two-hand episode retargeted onto both Sharpa hands, shared
// by the two-arm deploy tests (deploy_bimanual_test, cli_deploy_test).
#pragma once

#include <gtest/gtest.h>

#include "eval/reconstruction_noise.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "robot/embodiment.h"
#include "synth/episode.h"
#include "synth/objects.h"
#include "tests/test_util.h"

namespace doasido::testing {

struct TwoHands {
  retarget::Embodiment left_hand, right_hand;
  retarget::HandTrajectory left, right;
};

// 4 s of a two-hand pick-and-place (the second hand resting 35 cm to the
// side), each hand retargeted onto its robot.
inline const TwoHands& TwoHandEpisode() {
  static const TwoHands out = [] {
    synth::EpisodeSpec spec;
    spec.frames = 120;
    spec.two_hands = true;
    spec.second_hand_offset = 0.35;
    const recon::Reconstruction r =
        synth::EpisodeReconstruction(synth::ScriptEpisode(spec, synth::MakeCylinder(0.03, 0.09, 16)), 30.0);
    TwoHands h;
    h.left_hand = retarget::FindEmbodiment("sharpa_left", SharedData() / "robots");
    h.right_hand = retarget::FindEmbodiment("sharpa_right", SharedData() / "robots");
    retarget::KinematicConfig config;
    config.restarts = 1;
    const auto solve = [&](const retarget::Embodiment& e, const std::vector<recon::Joints21>& joints,
                           const std::vector<bool>& valid) {
      const retarget::HandModel model = retarget::BuildHandModel(e);
      retarget::KinematicRetargeter k(model, config);
      return k.Solve(joints, valid, r.fps);
    };
    EXPECT_EQ(r.left_valid.size(), 120u) << "the episode's second hand";
    h.left = solve(h.left_hand, r.left_joints, r.left_valid);
    h.right = solve(h.right_hand, r.right_joints, r.right_valid);
    return h;
  }();
  return out;
}

}  // namespace doasido::testing
