// doasido retarget-kinematic: offline kinematic retargeting of a keypoint
// CSV (21 OpenPose keypoints x xyz per row, metres) onto a robot hand.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "cli/output_options.h"
#include "core/error.h"
#include "core/progress.h"
#include "retarget/kinematic/kinematic_retarget.h"
#include "stages/kinematic_stage.h"
#include "robot/embodiment.h"

namespace doasido::cli {

namespace {
struct RetargetOptions {
  std::string hand = "sharpa_right";
  std::string keypoints;
  std::string out;
  std::string robots_dir;
  double fps = 30;
  bool force = false;
  retarget::KinematicConfig kinematic;
};
}  // namespace

void AddRetargetCommand(CLI::App& app) {
  auto opt = std::make_shared<RetargetOptions>();
  auto* cmd = app.add_subcommand(
      "retarget-kinematic",
      "Retarget human hand keypoints onto a robot hand (fingertips and knuckles matched\n"
      "under joint limits, scale adapted, warm-started from the previous frame, random starts\n"
      "at the first frame and after a jump) and write the\n"
      "reference robot trajectory");
  cmd->add_option("--hand", opt->hand,
                  "sharpa_right, sharpa_left, shadow, allegro, or an embodiment .json (for a URDF or "
                  "MJCF hand, `doasido hand import` writes one)")
      ->capture_default_str();
  cmd->add_option("--keypoints", opt->keypoints,
                  "CSV with header k0_x,k0_y,k0_z,...,k20_z; one frame a row, metres")
      ->required();
  cmd->add_option("--out", opt->out, "Output folder (created)")->required();
  cmd->add_option("--robots-dir", opt->robots_dir,
                  "Folder of robot models the descriptions refer to (default: "
                  "$DOASIDO_ROBOTS_DIR, else share/doasido/robots beside the executable's "
                  "folder)");
  cmd->add_option("--fps", opt->fps, "Frame rate of the keypoints")->check(FiniteRange(0.1, 10000))->capture_default_str();
  cmd->add_option("--restarts", opt->kinematic.restarts,
                  "Random starts at the first frame and after a jump (a keypoint moving more than 5 cm "
                  "from the last solved frame)")
      ->check(FiniteRange(1, 1000))
      ->capture_default_str();
  cmd->add_option("--scale", opt->kinematic.scale, "Human->robot scale; 0 adapts it")->check(FiniteRange(0, 100))
      ->capture_default_str();
  AddForceFlag(*cmd, opt->force);
  cmd->footer(
      "Writes <out>/trajectory.json and <out>/trajectory.csv (robot qpos per frame,\n"
      "floating wrist first) and prints the fingertip error after scale adaptation.\n\n"
      "Example:\n"
      "  doasido retarget-kinematic --hand allegro \\\n"
      "      --keypoints ../shared/data/retarget/human_hand_keypoints_right.csv --out work/allegro");
  cmd->callback([opt] {
    CheckOutputPath({.path = opt->out,
                     .kind = OutputRequest::Kind::kFolder,
                     .what = "the trajectory",
                     .is_own_output = FolderHolds({retarget::kTrajectoryFile}),
                     .force = opt->force});
    const std::string robots =
        opt->robots_dir.empty() ? retarget::DefaultRobotsDir() : opt->robots_dir;
    const auto frames = retarget::ReadKeypointCsv(opt->keypoints);
    if (frames.empty()) {
      throw Error("bad_keypoints", "no frames", {.file = opt->keypoints});
    }
    const retarget::HandModel hand =
        retarget::BuildHandModel(retarget::FindEmbodiment(opt->hand, robots));
    retarget::KinematicRetargeter solver(hand, opt->kinematic);
    Progress progress("retarget", frames.size());
    const retarget::HandTrajectory t =
        solver.Solve(frames, {}, opt->fps, [&progress](std::size_t done) { progress.Set(done); });
    progress.Finish();
    WriteWhole(opt->out, OutputKind::kFolder, [&](const std::filesystem::path& temp) {
      retarget::WriteTrajectoryJson(t, temp / retarget::kTrajectoryFile);
      retarget::WriteTrajectoryCsv(t, temp / retarget::kTrajectoryCsvFile);
    });
    const retarget::FingertipErrorStats e = retarget::SummarizeFingertipError(t.fingertip_error);
    std::printf("%s: %d frames, scale %.3f, fingertip error mean %.1f mm, p95 %.1f mm -> %s\n",
                t.embodiment.c_str(), e.frames, t.scale, 1000 * e.mean, 1000 * e.p95,
                opt->out.c_str());
  });
}

}  // namespace doasido::cli
