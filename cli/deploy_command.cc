// doasido deploy plan | plan-two | stream: the digital twin (UR3e + hand,
// MuJoCo; two of them for two hands) and the 50 Hz LCM command stream
// (deploy/plan.h, deploy/bimanual.h, deploy/stream.h).
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <algorithm>
#include <memory>
#include <optional>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "cli/output_options.h"
#include "core/config_check.h"
#include "core/error.h"
#include "db/database.h"
#include "deploy/bimanual.h"
#include "deploy/plan.h"
#include "deploy/stream.h"
#include "stages/kinematic_stage.h"
#include "review/trajectory_lookup.h"
#include "robot/embodiment.h"
#include "robot/trajectory/format.h"
#include "robot/trajectory/source.h"

namespace doasido::cli {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void OnSigint(int) { g_stop = true; }

struct PlanArgs {
  DbOptions db;
  long long clip = 0;
  std::string trajectory;
  std::string hand;
  std::string robots_dir;
  std::string out;
  bool no_replay = false;
  bool force = false;
  deploy::PlanConfig config;
};

// Refuses an unsafe --out before any planning (core/output_path.h).
void CheckPlanOut(const std::string& out, const char* format, bool force,
                  const std::vector<std::filesystem::path>& databases) {
  CheckOutputPath({.path = out,
                   .kind = OutputRequest::Kind::kFile,
                   .what = "the plan",
                   .is_own_output = JsonOfFormat(format),
                   .force = force,
                   .databases = databases});
}

// Step 4's between-frames check: the largest deviation, then each run of
// commands off the wrist path with the frames it lies between.
void PrintPathDeviation(const char* arm, const deploy::PathDeviation& d) {
  std::printf("%sbetween frames: flange within %.1f mm / %.3f rad of the wrist path (tolerance %.1f mm / %.3f rad)\n",
              arm, 1000 * d.position_max, d.rotation_max, 1000 * d.position_tolerance, d.rotation_tolerance);
  for (const auto& s : d.off_path) {
    std::printf("%soff path     commands %5d-%-5d t=%7.3f-%7.3f s  between frames %d and %d: flange %.1f mm / %.3f rad "
                "off the wrist path (a joint moves %.2f rad from one frame to the next)\n",
                arm, s.first_command, s.last_command, s.start_time, s.end_time, s.from_frame, s.to_frame,
                1000 * s.position_deviation, s.rotation_deviation, s.joint_jump);
  }
}

void PrintIssues(const deploy::Plan& plan, const char* arm = "") {
  for (const auto& u : plan.unreachable) {
    std::printf("unreachable  frame %5d  t=%7.3f s  position error %.1f mm  rotation error %.3f rad\n",
                u.frame, u.time, 1000 * u.value, u.limit);
  }
  for (const auto& f : plan.too_fast) {
    std::printf("too fast     command %5d  t=%7.3f s  %s %.2f rad/s > %.2f rad/s\n", f.frame, f.time,
                plan.arm_joints.at(f.joint).c_str(), f.value, f.limit);
  }
  for (const auto& f : plan.over_acceleration) {
    std::printf("too abrupt   command %5d  t=%7.3f s  %s %.2f rad/s^2 > %.2f rad/s^2\n", f.frame, f.time,
                plan.arm_joints.at(f.joint).c_str(), f.value, f.limit);
  }
  PrintPathDeviation(arm, plan.path_deviation);
}

void PrintTiming(const deploy::Plan& plan) {
  std::printf("re-timed: %.2f s of trajectory in %.2f s (slowdown %.2fx), lead-in %.2f s, lead-out %.2f s, "
              "%zu commands at %.0f Hz; wrist path: %s\n", plan.trajectory_duration,
              (plan.times.size() - plan.lead_in - plan.lead_out - 1) / plan.rate_hz, plan.slowdown,
              plan.lead_in / plan.rate_hz, plan.lead_out / plan.rate_hz, plan.times.size(), plan.rate_hz,
              plan.wrist_path.c_str());
}

void PrintReplay(const char* what, const deploy::ReplayReport& r) {
  std::printf("%s: object error mean %.1f mm (max %.1f), rotation mean %.3f rad (max %.3f), %s "
              "(floating hand: %s); wrist tracking mean %.1f mm (max %.1f), %.3f rad (max %.3f)\n", what,
              1000 * r.object_position_error_mean, 1000 * r.object_position_error_max,
              r.object_rotation_error_mean, r.object_rotation_error_max, r.success ? "success" : "failure",
              r.reference_success < 0 ? "unknown" : r.reference_success ? "success" : "failure",
              1000 * r.wrist_position_error_mean, 1000 * r.wrist_position_error_max, r.wrist_rotation_error_mean,
              r.wrist_rotation_error_max);
}

void RunPlan(const PlanArgs& a, const CLI::App& cmd) {
  std::vector<std::filesystem::path> databases;
  if (a.trajectory.empty()) databases.push_back(a.db.db);
  CheckPlanOut(a.out, deploy::kPlanFormat, a.force, databases);
  deploy::PlanConfig config = a.config;
  const Json file_config = LoadConfig(a.db, {deploy::kPlanConfigSection});
  if (file_config.is_object() && file_config.contains(deploy::kPlanConfigSection)) {
    RequireSameShape(deploy::kPlanConfigSection, Json(config),
                     file_config.at(deploy::kPlanConfigSection));
  }
  ReadSection(file_config, deploy::kPlanConfigSection, config);
  // Options given on the command line win over the config file.
  if (cmd.count("--rate")) config.rate_hz = a.config.rate_hz;
  if (cmd.count("--yaw-steps")) config.workspace.yaw_steps = a.config.workspace.yaw_steps;
  if (cmd.count("--offset-steps")) config.workspace.offset_steps = a.config.workspace.offset_steps;
  deploy::CheckConfig(config, deploy::kPlanConfigSection);
  retarget::TrajectoryFiles files;
  // Held while the run's files are read: a merge never places them halfway
  // under this plan (Database::LockForReading).
  std::optional<Database::ArtifactLock> reading;
  if (!a.trajectory.empty()) {
    // Relative to the working directory, like every path on the command line.
    files = retarget::FilesBeside(std::filesystem::absolute(a.trajectory));
  } else {
    Database db(a.db.db, Database::OpenMode::kExisting);
    reading.emplace(db.LockForReading());
    std::string why;
    auto found = review::FindTrajectoryFiles(db, a.clip, &why);
    if (!found) {
      throw Error("no_trajectory", "no trajectory to plan: " + why,
                  {.clip = std::to_string(a.clip), .file = db.path().string()});
    }
    std::fprintf(stderr, "planning %s run %lld of clip %lld: %s\n", found->stage.c_str(),
                 static_cast<long long>(found->run_id), static_cast<long long>(a.clip),
                 found->trajectory.c_str());
    files = *found;
  }
  const retarget::HandTrajectory trajectory = retarget::ReadTrajectoryJson(files.trajectory);
  if (retarget::IsBimanualEmbodiment(trajectory.embodiment) && a.hand.empty()) {
    throw Error("two_hand_trajectory",
                "the trajectory holds two hands (" + trajectory.embodiment + "); plan them with `doasido deploy "
                "plan-two --trajectory " + files.trajectory.string() + " --out PLAN`",
                {.file = files.trajectory.string(), .field = "embodiment"});
  }
  const std::string robots = a.robots_dir.empty() ? retarget::DefaultRobotsDir() : a.robots_dir;
  const retarget::Embodiment hand =
      retarget::FindEmbodiment(a.hand.empty() ? trajectory.embodiment : a.hand, robots);
  deploy::Plan plan = deploy::MakePlan(trajectory, hand, config);
  plan.source = files.trajectory.string();
  if (config.replay && !a.no_replay) {
    const std::string xml = retarget::ReadSceneXml(files.scene_dir);
    deploy::FollowedPlan followed = deploy::PlanOnFloatingWrist(plan, trajectory, hand, config, xml, files.scene_dir);
    plan = std::move(followed.plan);
    deploy::ReplayPlan(plan, followed.trajectory, hand, xml, files.scene_dir, config.servo_omega);
  }
  WriteWhole(a.out, OutputKind::kFile, [&plan](const std::filesystem::path& p) { deploy::WritePlanJson(plan, p); });
  const auto& p = plan.placement;
  std::printf("%s: placement yaw %.1f deg at (%.3f, %.3f) m, %d candidates, least manipulability %.3f\n",
              hand.name.c_str(), p.yaw * 180 / 3.14159265358979, p.x, p.y, p.candidates, p.manipulability);
  PrintTiming(plan);
  PrintIssues(plan);
  if (plan.replay.ran) PrintReplay("replay", plan.replay);
  std::printf("%s: %zu unreachable, %zu too fast, %zu too abrupt, %d off the path -> %s\n",
              plan.ok ? "ok" : "FAILED checks", plan.unreachable.size(), plan.too_fast.size(),
              plan.over_acceleration.size(), plan.path_deviation.OffPathCommands(), a.out.c_str());
  if (!plan.ok) {
    throw Error("plan_failed_checks", "the plan was written but fails its checks (see above); "
                "`deploy stream` will refuse it", {.file = a.out});
  }
}

void AddPlan(CLI::App& deploy) {
  auto a = std::make_shared<PlanArgs>();
  auto* cmd = deploy.add_subcommand(
      "plan", "Place a robot hand trajectory in the UR3e's workspace, solve arm IK for every\n"
              "command frame, check reach and joint speeds, replay in MuJoCo, write a plan");
  AddDbOptions(*cmd, a->db);
  cmd->add_option("--clip", a->clip, "Clip id whose retarget (else retarget_kinematic) trajectory to plan")->check(FiniteRange(1, 1000000000000000.0));
  cmd->add_option("--trajectory", a->trajectory, "A trajectory.json instead of --db/--clip "
                  "(scene/scene.xml beside it is the replay scene)");
  cmd->add_option("--hand", a->hand, "Embodiment (default: the trajectory's)");
  cmd->add_option("--robots-dir", a->robots_dir, "Folder of robot hand descriptions");
  cmd->add_option("--out", a->out, "Plan file to write (JSON)")->required();
  cmd->add_option("--rate", a->config.rate_hz, "Command rate, Hz")->check(FiniteRange(0, 1000))->capture_default_str();
  cmd->add_option("--yaw-steps", a->config.workspace.yaw_steps, "Yaw candidates over a full turn")->check(FiniteRange(1, 360))
      ->capture_default_str();
  cmd->add_option("--offset-steps", a->config.workspace.offset_steps,
                  "Offset candidates per axis around the default table position")->check(FiniteRange(1, 21))->capture_default_str();
  cmd->add_flag("--no-replay", a->no_replay, "Skip the MuJoCo replay");
  AddForceFlag(*cmd, a->force);
  cmd->footer(
      "The workspace (default table pose, search ranges) and IK tolerances are the\n"
      "[deploy] section of --config (deploy/plan.h PlanConfig). The plan runs slower than\n"
      "the video where the arm needs it: the wrist path is re-timed so that no joint exceeds\n"
      "its speed (180 deg/s base, shoulder, elbow; 360 deg/s wrists) or acceleration\n"
      "(5 rad/s^2) limit, starting and ending at rest, with a lead-in from the home pose and\n"
      "a lead-out back ([deploy.time_scaling], lead_in, lead_out, home). The plan records\n"
      "each command's trajectory time and the slowdown. Frames the arm cannot reach, any\n"
      "command still beyond a limit, and runs of commands whose flange leaves the wrist path\n"
      "between the frames (an IK branch jump; beyond [deploy.path_check], 10 mm / 0.1 rad)\n"
      "are listed with their times and frames, and the command exits non-zero; the plan file\n"
      "is written either way.\n\n"
      "Examples:\n"
      "  doasido deploy plan --db work/doasido.db --clip 12 --out work/plan12.json\n"
      "  doasido deploy plan --trajectory work/allegro/trajectory.json --hand sharpa_right \\\n"
      "      --out plan.json --yaw-steps 24");
  cmd->callback([a, cmd] {
    if (a->trajectory.empty() && a->clip <= 0) {
      throw Error("bad_arguments", "give --trajectory, or --db and --clip", {.field = "--clip"});
    }
    RunPlan(*a, *cmd);
  });
}

void AddPlanTwo(CLI::App& deploy) {
  struct Args {
    std::string trajectory, left, right, left_hand, right_hand, robots_dir, out;
    bool force = false, no_replay = false;
    deploy::BimanualConfig config;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = deploy.add_subcommand(
      "plan-two", "Two arms for two hands: place two UR3e arms side by side, solve each arm's IK for\n"
                  "its hand's trajectory, check reach, joint speeds and arm-arm collisions, write one plan");
  auto* both = cmd->add_option("--trajectory", a->trajectory,
                               "A two-hand trajectory.json (the retarget stage's with [retarget] left_hand)");
  auto* left_option = cmd->add_option("--left", a->left, "Or the left hand's trajectory.json");
  auto* right_option = cmd->add_option("--right", a->right, "and the right hand's");
  both->excludes(left_option)->excludes(right_option);
  cmd->add_option("--left-hand", a->left_hand, "Left embodiment (default: the trajectory's)");
  cmd->add_option("--right-hand", a->right_hand, "Right embodiment (default: the trajectory's)");
  cmd->add_option("--robots-dir", a->robots_dir, "Folder of robot hand descriptions");
  cmd->add_option("--out", a->out, "Plan file to write (JSON)")->required();
  cmd->add_option("--base-distance", a->config.base_distance, "Metres between the two arms' bases")->check(FiniteRange(0, 5))
      ->capture_default_str();
  cmd->add_option("--clearance", a->config.clearance, "Metres the arms and hands must keep apart")->check(FiniteRange(0, 1))
      ->capture_default_str();
  cmd->add_option("--rate", a->config.plan.rate_hz, "Command rate, Hz")->check(FiniteRange(0, 1000))->capture_default_str();
  cmd->add_flag("--no-replay", a->no_replay, "Skip the two-arm MuJoCo replay");
  AddForceFlag(*cmd, a->force);
  cmd->footer(
      "The bases stand side by side, the left arm at +base-distance/2 and the right at -base-distance/2\n"
      "across the table, both trajectories placed once (deploy/bimanual.h). Each arm is its link capsules\n"
      "and the hand a capsule along the flange. Both arms are re-timed on one clock (the slower arm sets\n"
      "the pace) within their speed and acceleration limits; commands where the arms come closer than the clearance are\n"
      "listed with their times and the command exits non-zero (the plan is written either way);\n"
      "`deploy stream` refuses such a plan and sends one doasido_lcm.bimanual_command per tick otherwise.\n"
      "With --trajectory (one simulation of both hands, scene/scene.xml beside it), both arms and hands are\n"
      "replayed in one MuJoCo scene with the object: each arm's wrist tracking and the object's outcome.\n\n"
      "Examples:\n"
      "  doasido deploy plan-two --trajectory work/doasido/artifacts/12/retarget/trajectory.json --out work/two.json\n"
      "  doasido deploy plan-two --left work/left/trajectory.json --right work/right/trajectory.json \\\n"
      "      --out work/two.json --base-distance 0.6\n"
      "  doasido deploy stream --plan work/two.json");
  cmd->callback([a] {
    deploy::CheckConfig(a->config, deploy::kPlanConfigSection);
    CheckPlanOut(a->out, deploy::kBimanualPlanFormat, a->force, {});
    if (a->trajectory.empty() && (a->left.empty() || a->right.empty())) {
      throw Error("bad_arguments", "give --trajectory, or --left and --right", {.field = "--trajectory"});
    }
    const auto [left, right] = a->trajectory.empty()
                                   ? std::pair(retarget::ReadTrajectoryJson(a->left), retarget::ReadTrajectoryJson(a->right))
                                   : retarget::SplitBimanualTrajectory(retarget::ReadTrajectoryJson(a->trajectory));
    const std::string robots = a->robots_dir.empty() ? retarget::DefaultRobotsDir() : a->robots_dir;
    const retarget::Embodiment lh = retarget::FindEmbodiment(a->left_hand.empty() ? left.embodiment : a->left_hand, robots);
    const retarget::Embodiment rh = retarget::FindEmbodiment(a->right_hand.empty() ? right.embodiment : a->right_hand, robots);
    deploy::BimanualPlan plan = deploy::MakeBimanualPlan(left, right, lh, rh, a->config);
    if (!a->trajectory.empty() && a->config.plan.replay && !a->no_replay) {
      const retarget::TrajectoryFiles files = retarget::FilesBeside(std::filesystem::absolute(a->trajectory));
      deploy::ReplayBimanualPlan(plan, retarget::ReadTrajectoryJson(files.trajectory), lh, rh,
                                 retarget::ReadSceneXml(files.scene_dir), files.scene_dir,
                                 a->config.plan.servo_omega);
    }
    plan.left.source = a->trajectory.empty() ? a->left : a->trajectory;
    plan.right.source = a->trajectory.empty() ? a->right : a->trajectory;
    WriteWhole(a->out, OutputKind::kFile, [&](const std::filesystem::path& p) {
      deploy::WriteBimanualPlanJson(plan, a->config, p);
    });
    const double closest = *std::min_element(plan.arm_distance.begin(), plan.arm_distance.end());
    std::printf("%s + %s: bases %.3f m apart, closest approach %.3f m\n", lh.name.c_str(), rh.name.c_str(),
                a->config.base_distance, closest);
    PrintTiming(plan.right);
    PrintIssues(plan.left, "left arm: ");
    PrintIssues(plan.right, "right arm: ");
    if (plan.right.replay.ran) {
      PrintReplay("replay, both arms", plan.right.replay);
      std::printf("  left arm: wrist tracking mean %.1f mm (max %.1f); right arm: mean %.1f mm (max %.1f)\n",
                  1000 * plan.left.replay.wrist_position_error_mean, 1000 * plan.left.replay.wrist_position_error_max,
                  1000 * plan.right.replay.wrist_position_error_mean,
                  1000 * plan.right.replay.wrist_position_error_max);
    }
    for (const auto& c : plan.collisions) {
      std::printf("collision    command %5d  t=%7.3f s  arms %.1f mm apart (clearance %.1f mm)\n", c.frame, c.time,
                  1000 * c.value, 1000 * c.limit);
    }
    std::printf("%s: %zu collision frames -> %s\n", plan.ok ? "ok" : "FAILED checks", plan.collisions.size(),
                a->out.c_str());
    if (!plan.ok) {
      throw Error("plan_failed_checks", "the two-arm plan was written but fails its checks (see above); "
                  "`deploy stream` will refuse it", {.file = a->out});
    }
  });
}

void AddStream(CLI::App& deploy) {
  struct StreamArgs {
    std::string plan;
    std::string dry_run;
    bool force = false;
    deploy::StreamOptions options;
  };
  auto a = std::make_shared<StreamArgs>();
  auto* cmd = deploy.add_subcommand(
      "stream", "Publish a plan's joint commands over LCM in real time (50 Hz by default)");
  cmd->add_option("--plan", a->plan, "Plan file from `deploy plan`")->required();
  cmd->add_option("--url", a->options.url, "LCM URL (ttl=0 keeps it on this machine)")
      ->capture_default_str();
  cmd->add_option("--channel", a->options.channel, "LCM channel")->capture_default_str();
  cmd->add_option("--rate", a->options.rate_hz, "Command rate, Hz (0: the plan's)")->check(FiniteRange(0, 1000))
      ->capture_default_str();
  cmd->add_option("--dry-run", a->dry_run, "Write the messages to this LCM log file instead "
                  "(no network, no waiting)");
  AddForceFlag(*cmd, a->force);
  cmd->footer(
      "Messages are doasido_lcm.arm_hand_command (deploy/arm_hand_command.lcm):\n"
      "timestamp_us, sequence, plan_time, arm_q[6], hand_q[num_hand]; for a plan from\n"
      "`deploy plan-two`, doasido_lcm.bimanual_command (deploy/bimanual_command.lcm): both arms\n"
      "and both hands in one message per tick. A plan that failed its checks is refused.\n"
      "Ctrl-C stops after the current message.\n\n"
      "Examples:\n"
      "  lcm-logger --lcm-url='udpm://239.255.76.67:7667?ttl=0' run.lcmlog &\n"
      "  doasido deploy stream --plan work/plan12.json\n"
      "  doasido deploy stream --plan work/plan12.json --dry-run work/plan12.lcmlog");
  cmd->callback([a] {
    if (!a->dry_run.empty()) {
      // An LCM log starts with the event sync word 0xEDA1DA01 (big-endian).
      CheckOutputPath({.path = a->dry_run,
                       .kind = OutputRequest::Kind::kFile,
                       .option = "--dry-run",
                       .what = "the LCM log",
                       .is_own_output = [](const std::filesystem::path& p) {
                         return FileStartsWith(p, std::string("\xED\xA1\xDA\x01", 4));
                       },
                       .force = a->force});
    }
    const Json file = deploy::ReadPlanFile(a->plan);
    const bool two = file.is_object() && file.value("format", "") == deploy::kBimanualPlanFormat;
    std::optional<deploy::Plan> one;
    std::optional<deploy::BimanualPlan> pair;
    if (two) {
      pair = deploy::BimanualPlanFromJson(file, a->plan);
    } else {
      one = deploy::PlanFromJson(file, a->plan);
    }
    const size_t commands = two ? pair->right.arm.size() : one->arm.size();
    deploy::StreamOptions options = a->options;
    options.dry_run_log = a->dry_run;
    g_stop = false;
    auto previous = std::signal(SIGINT, OnSigint);
    std::signal(SIGTERM, OnSigint);
    if (a->dry_run.empty()) {
      std::fprintf(stderr, "streaming %zu %scommands on %s; Ctrl-C stops after the current one\n", commands,
                   two ? "two-arm " : "", options.channel.c_str());
    }
    const deploy::StreamResult r = two ? deploy::StreamBimanualPlan(*pair, options, g_stop)
                                       : deploy::StreamPlan(*one, options, g_stop);
    std::signal(SIGINT, previous);
    std::printf("%s %d of %zu commands on %s%s\n", r.stopped ? "stopped after" : "sent", r.sent, commands,
                options.channel.c_str(),
                a->dry_run.empty() ? (" (" + options.url + ")").c_str() : (" -> " + a->dry_run).c_str());
  });
}

}  // namespace

void AddDeployCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("deploy", "Digital twin and robot commands: arm IK plans and LCM streaming");
  cmd->require_subcommand(1);
  AddPlan(*cmd);
  AddPlanTwo(*cmd);
  AddStream(*cmd);
}

}  // namespace doasido::cli
