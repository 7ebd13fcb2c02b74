#include "stages/dynamic_stage.h"

#include <algorithm>
#include <fstream>
#include <functional>
#include <optional>

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "stages/clip_inputs.h"
#include "retarget/dynamic/bimanual_retarget.h"
#include "retarget/holding_hand.h"
#include "retarget/mirror_scene.h"
#include "stages/kinematic_stage.h"

namespace doasido::stages {

using namespace retarget;  // the algorithms this stage runs

DynamicRetargetStage::DynamicRetargetStage(DynamicRetargetConfig config) : config_(std::move(config)) {
  CheckConfig(config_, kRetargetStageName);
}

StageResult DynamicRetargetStage::KeepKinematic(const ClipContext& context, StageResult result) const {
  // Nothing to simulate without an object: the kinematic trajectory is the
  // clip's trajectory, copied here because readers take the trajectory from
  // this stage when the pipeline has it (robot/trajectory/format.h).
  const std::filesystem::path kinematic = SiblingArtifactDir(context, kKinematicStageName);
  if (!std::filesystem::is_regular_file(kinematic / kTrajectoryFile)) {
    result.verdict = Verdict::kReject;  // no retarget_kinematic before this stage
    result.reason = kReasonNoObject;
    return result;
  }
  std::filesystem::create_directories(context.artifact_dir);
  for (const char* file : {kTrajectoryFile, kTrajectoryCsvFile, kLeftTrajectoryFile}) {
    if (!std::filesystem::is_regular_file(kinematic / file)) continue;
    std::filesystem::copy_file(kinematic / file, context.artifact_dir / file,
                               std::filesystem::copy_options::overwrite_existing);
    result.artifacts.emplace_back(file == kTrajectoryFile      ? "trajectory"
                                  : file == kTrajectoryCsvFile ? "trajectory_csv"
                                                               : "trajectory_left",
                                  file);
  }
  result.reason = kReasonHandOnlyKinematic;  // a pass that says why nothing was simulated
  result.measurements[kMeasureTrajectorySource] = kKinematicStageName;
  const HandTrajectory t = ReadTrajectoryJson(kinematic / kTrajectoryFile);
  result.measurements["frames"] = t.qpos.size();
  spdlog::info("{} {}: hand-only, keeps the {} trajectory", kRetargetStageName, ClipName(context),
               kKinematicStageName);
  return result;
}

StageResult DynamicRetargetStage::Run(const ClipContext& context) {
  const std::string clip = context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                                            : context.clip.external_id;
  const std::filesystem::path dir = SiblingArtifactDir(context, recon::kReconStageName);
  recon::Reconstruction r;
  TriMesh mesh;
  try {
    r = recon::ReadReconstruction(dir);
    if (!r.object_mesh.empty()) mesh = LoadMesh(r.object_mesh);
  } catch (const Error& e) {
    ErrorSite site = e.site();
    site.clip = clip;
    throw Error(e.code(), e.message(), site);
  }
  StageResult result;
  result.measurements["reconstruction"] = dir.string();
  if (r.object_mesh.empty()) return KeepKinematic(context, std::move(result));
  const auto any = [](const std::vector<bool>& v) {
    return std::find(v.begin(), v.end(), true) != v.end();
  };
  const bool left_seen = any(r.left_valid);
  // One robot hand and two human hands: the one that holds the object
  // (retarget/holding_hand.h), mirrored when it is the left.
  if (config_.left_hand.empty() && left_seen && any(r.right_valid) && LeftHandHoldsObject(r, mesh)) {
    r = KeepOnlyLeftHand(std::move(r));
  }
  if (!any(r.right_valid)) {
    if (!left_seen) {  // recon rejects a clip without hands; a file may still say so
      result.verdict = Verdict::kReject;
      result.reason = kReasonNoHands;
      return result;
    }
    // A lone left hand: the whole scene mirrored onto the right robot hand
    // (retarget/mirror_scene.h), as retarget_kinematic does.
    r = MirrorLeftOntoRight(std::move(r));
    mesh = MirrorMesh(std::move(mesh));
  }
  result.measurements[kMeasureRetargetedHand] = !any(r.left_valid) && left_seen ? kHandLeftMirrored
                                                                                : kHandRight;
  const std::string robots = config_.robots_dir.empty() ? DefaultRobotsDir() : config_.robots_dir;
  std::filesystem::create_directories(context.artifact_dir);
  Json& m = result.measurements;
  const bool bimanual = !config_.left_hand.empty() && any(r.left_valid);
  // One rung's run: the one-hand run, or the two-hand run in its fields
  // with the left hand's extras.
  struct ClipRun {
    DynamicRetargetRun run;
    TrackingMetrics metrics;
    HandTrajectory left_kinematic;
    Json extra = Json::object();
  };
  // The scene, model and kinematic reference are the same at every rung:
  // made at the first and reused by the others.
  const std::filesystem::path scene_dir = context.artifact_dir / kSceneFolder;
  std::optional<BimanualRetarget> both_hands;
  std::optional<ClipRetarget> one_hand;
  const std::function<ClipRun(const std::string&)> track = [&](const std::string& rung) {
    const AnnealedSamplerConfig sampler = RungSampler(config_, rung);
    ClipRun out;
    if (bimanual) {
      if (!both_hands) {
        both_hands.emplace(r, mesh, FindEmbodiment(config_.left_hand, robots),
                           FindEmbodiment(config_.hand, robots), config_, scene_dir, clip);
      }
      BimanualRun both = both_hands->Track(sampler);
      out.left_kinematic = std::move(both.left_kinematic);
      out.extra["left_wrist_error"] = both.left_wrist_error;
      out.extra["right_wrist_error"] = both.right_wrist_error;
      out.extra["left_in_hand_frames"] = both.left_in_hand_frames;
      out.run.trajectory = std::move(both.trajectory);
      out.run.kinematic = std::move(both.right_kinematic);
      out.run.metrics = both.metrics;
      out.run.stats = both.stats;
      out.run.robot_scene_xml = std::move(both.robot_scene_xml);
      out.run.in_hand_frames = both.right_in_hand_frames;
    } else {
      if (!one_hand) {
        one_hand.emplace(r, mesh, FindEmbodiment(config_.hand, robots), config_, scene_dir, clip);
      }
      out.run = one_hand->Track(sampler);
    }
    out.metrics = out.run.metrics;
    spdlog::info("{} {}: rung {}: E_pos {:.3f} m, E_rot {:.3f} rad, {}", kRetargetStageName, clip, rung,
                 out.metrics.e_pos, out.metrics.e_rot, out.metrics.success ? "success" : "failure");
    return out;
  };
  LadderResult<ClipRun> ladder = RunLadder(LadderRungs(config_), track);
  DynamicRetargetRun& run = ladder.best.run;
  if (bimanual) {
    WriteTrajectoryJson(ladder.best.left_kinematic, context.artifact_dir / "kinematic_reference_left.json");
    result.artifacts.push_back({"kinematic_reference_left", "kinematic_reference_left.json"});
    m.update(ladder.best.extra);
  }
  WriteLadderMeasurements(ladder.rungs, ladder.best_rung, m);

  WriteTrajectoryJson(run.trajectory, context.artifact_dir / kTrajectoryFile);
  WriteTrajectoryCsv(run.trajectory, context.artifact_dir / kTrajectoryCsvFile);
  WriteTrajectoryJson(run.kinematic, context.artifact_dir / "kinematic_reference.json");
  std::ofstream(context.artifact_dir / kRobotSceneFile) << run.robot_scene_xml;
  result.artifacts.insert(result.artifacts.begin(), {{"trajectory", kTrajectoryFile},
                                                     {"trajectory_csv", kTrajectoryCsvFile},
                                                     {"kinematic_reference", "kinematic_reference.json"},
                                                     {"scene", std::string(kSceneFolder) + "/" + kSceneFile},
                                                     {"robot_scene", kRobotSceneFile}});
  m[kMetricPositionError] = run.metrics.e_pos;
  m[kMetricRotationError] = run.metrics.e_rot;
  m[kMetricSuccess] = run.metrics.success;
  m["frames"] = r.frames();
  m["in_hand_frames"] = run.in_hand_frames;
  m["plans"] = run.stats.plans;
  m["iterations"] = run.stats.iterations;
  m["rollouts"] = run.stats.rollouts;
  m["sim_steps"] = run.stats.sim_steps;
  m["optimizer_seconds"] = run.stats.seconds;
  m["rollout_steps_per_second"] =
      run.stats.rollout_seconds > 0 ? run.stats.sim_steps / run.stats.rollout_seconds : 0.0;
  if (auto redecided = Redecide(m)) {
    result.verdict = redecided->verdict;
    result.reason = redecided->reason;
  }
  spdlog::info("{} {}: E_pos {:.3f} m, E_rot {:.3f} rad, {} at rung {} of {}", kRetargetStageName, clip,
               run.metrics.e_pos, run.metrics.e_rot, run.metrics.success ? "success" : "failure",
               ladder.best_rung + 1, ladder.rungs.size());
  return result;
}

std::optional<StageResult> DynamicRetargetStage::Redecide(const Json& measurements) const {
  if (!measurements.contains(kMetricPositionError) || !measurements.contains(kMetricRotationError)) {
    return std::nullopt;
  }
  StageResult r;
  r.measurements = measurements;
  const Json& pos = measurements[kMetricPositionError];
  const Json& rot = measurements[kMetricRotationError];
  const double e_pos = pos.is_number() ? pos.get<double>() : 1e9;
  const double e_rot = rot.is_number() ? rot.get<double>() : 1e9;
  if (!(e_pos < kSuccessPosition && e_rot < kSuccessRotation)) {
    r.verdict = Verdict::kReject;
    r.reason = kReasonTrackingFailed;
  }
  return r;
}

}  // namespace doasido::stages
