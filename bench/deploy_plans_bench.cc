// Arm plans a real UR3e can run (deploy/plan.h): retargeted trajectories
// planned for the arm, measured over
//  - --refs synthetic references x clean/noisy (pick-and-place,
//    lift-and-rotate, slide in turn; made and retargeted with the `fast`
//    preset as bench/retarget_dynamics_bench.cc's wall section does),
//  - the HOT3D sample (left hand with the coffee pot's stand-in sphere,
//    onto sharpa_left),
//  - --carries synthetic two-hand carries of --carry_seconds (both Sharpa
//    hands, `deploy plan-two`),
// the share of plans passing every check (reach, joint speed and
// acceleration at every command, the flange on the wrist path between
// frames), the slowdowns (median, max), the arm replay's object success
// against the floating hand's, and the wrist tracking error (mean, max).
// Per plan, "betw. mm" is the largest flange deviation from the wrist path
// over the re-timed commands (plan.h PathDeviation), and the checks column
// names the frames of the worst run off the path and the placement used.
//
// Retargeting is the slow part (275-680 s a 10-s clip on 2 threads, ~1000 s
// on one thread of a loaded machine), so the
// trajectories are cached in --cache (trajectory.json + scene/ per
// reference, stages/dynamic_stage.h's layout) and made only when
// missing; --make_only stops after making them, --plan_only plans the ones
// made so far without making more.
//   deploy_plans_bench [--cache=/tmp/doasido-deploy-bench] [--refs=10] [--carries=5]
//       [--clip_seconds=10] [--carry_seconds=4] [--threads=2] [--make_only [--from=I] | --plan_only]
//       [--no_replay] [--compare] [--only=NAME] [--real=DIR] [--follow_rounds=N] [--follow_smoothing=S]
//       [--preset=fast|medium|seed|ladder] [--no_hot3d] [--default_scene] [--diagnose]
//       [--sampler=JSON] [--trace_windows=FROM,TO]
// --trace_windows=2.5,5 prints each planning window starting in [2.5, 5] s
// (retarget::WindowTrace; issue 51): the returns and the object's height at
// the horizon's end of the plan entering the window, the reference's
// controls, the best sample and the executed weighted mean, each rolled out
// from the window's start state, and that state's finger gap and
// hand-object contacts; with --diagnose, for the open-loop replay too.
// --sampler='{"horizon":2}' replaces those fields of the --preset's sampler
// (AnnealedSamplerConfig keys; one rung). --default_scene makes the references with DynamicRetargetConfig{}'s
// kinematic and scene settings (object density, grasp terms off) instead of
// the dynamics bench's; use its own --cache. --diagnose makes nothing and
// prints, per made reference, the object's error every half second against
// the reference and against an open-loop replay of the kinematic
// reference and the object left at rest, and whether the reference grasp
// holds the object (issue 51).
// --preset retargets the single-hand references with that preset, or with
// "ladder" along DynamicRetargetConfig{}'s ladder as the `retarget` stage
// does (the scene, model and kinematic reference once, a rung only when the
// one before failed); use a --cache per preset. Each reference's rungs
// (wall and CPU seconds, success) go to made.json beside its trajectory,
// and the report gives per reference the rungs, the kept rung's share and
// the first rung alone against the ladder. --no_hot3d neither makes nor
// plans the HOT3D reference.
// The arm is planned on the floating hand's replayed wrist (plan.h step
// 3b, deploy.follow_rounds; --follow_rounds=0: on the trajectory's wrist).
// --compare replays each plan also on the floating hand (plan.h
// ReplayMount::kFloating), under the plan's time map and at the video's
// clock, and the arm at the video's clock (limits ignored): which of the
// re-timing, the lead-in or the arm loses an object; --only=NAME prints
// that reference command by command (and makes only that reference). --real=DIR plans the hand-only
// trajectories of real clips a doasido run made (no object: no replay).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench/child_cpu.h"
#include "core/error.h"
#include "deploy/bimanual.h"
#include "deploy/plan.h"
#include "eval/hot3d_recording.h"
#include "eval/reference_hold.h"
#include "eval/reconstruction_noise.h"
#include "retarget/dynamic/bimanual_retarget.h"
#include "retarget/dynamic/dynamic_retarget.h"
#include "robot/mj_model.h"
#include "robot/trajectory/source.h"
#include "synth/objects.h"

namespace {

using namespace doasido;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

const fs::path kData = DOASIDO_SHARED_DATA;

struct Flags {
  fs::path cache = fs::temp_directory_path() / "doasido-deploy-bench";
  int refs = 10, carries = 5, threads = 2;
  int from = 0;  // make references from..refs-1 only (two makers split the list)
  double clip_seconds = 10, carry_seconds = 4;
  bool make_only = false, plan_only = false, replay = true, hot3d = true;
  bool compare = false;
  // --default_scene: the kinematic and scene settings of DynamicRetargetConfig{}
  // (density, grasp terms, restarts) instead of the dynamics bench's.
  bool default_scene = false;
  bool diagnose = false;  // --diagnose: the object's error over time (Diagnose)
  // --trace_windows=A,B: print the planner's windows starting in [A, B] s
  // (retarget::WindowTrace) while making references, and in --diagnose's replay.
  double trace_from = 1, trace_to = 0;
  // --sampler='{"horizon": 2}': the --preset's sampler with these fields
  // replaced (a JSON object of AnnealedSamplerConfig keys), run as one rung.
  Json sampler_patch;
  // Hand-only trajectories of real clips: every <clip>/retarget_kinematic/
  // trajectory.json under this folder (a doasido run's artifact root).
  fs::path real;     // also replay the floating hand (re-timed and at the video's clock)
  std::string only;         // plan only the reference of this name
  std::string preset = "fast";  // the single-hand references' preset, or "ladder"
  deploy::PlanConfig plan;  // --no_leads: without the lead moves
};

Flags Parse(int argc, char** argv) {
  Flags f;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto eq = a.find('=');
    const std::string k = a.substr(0, eq), v = eq == std::string::npos ? "" : a.substr(eq + 1);
    if (k == "--cache") f.cache = v;
    else if (k == "--refs") f.refs = std::stoi(v);
    else if (k == "--from") f.from = std::stoi(v);
    else if (k == "--carries") f.carries = std::stoi(v);
    else if (k == "--threads") f.threads = std::stoi(v);
    else if (k == "--clip_seconds") f.clip_seconds = std::stod(v);
    else if (k == "--carry_seconds") f.carry_seconds = std::stod(v);
    else if (k == "--make_only") f.make_only = true;
    else if (k == "--plan_only") f.plan_only = true;
    else if (k == "--no_replay") f.replay = false;
    else if (k == "--no_hot3d") f.hot3d = false;
    else if (k == "--compare") f.compare = true;
    else if (k == "--real") f.real = v;
    else if (k == "--no_leads") f.plan.lead_in = f.plan.lead_out = false;
    else if (k == "--only") f.only = v;
    else if (k == "--preset") f.preset = v;
    else if (k == "--default_scene") f.default_scene = true;
    else if (k == "--diagnose") f.diagnose = true;
    else if (k == "--trace_windows") {
      const auto comma = v.find(',');
      f.trace_from = std::stod(v.substr(0, comma));
      f.trace_to = comma == std::string::npos ? f.trace_from : std::stod(v.substr(comma + 1));
    }
    else if (k == "--sampler") f.sampler_patch = Json::parse(v);
    else if (k == "--servo_omega") f.plan.servo_omega = std::stod(v);
    else if (k == "--follow_rounds") f.plan.follow_rounds = std::stoi(v);
    else if (k == "--follow_smoothing") f.plan.follow_smoothing = std::stod(v);
    else if (k == "--smooth_hz") f.plan.wrist_smoothing.cutoff_hz = std::stod(v);
    else if (k == "--smooth_mm") f.plan.wrist_smoothing.tolerance = std::stod(v) / 1000;
    else if (k == "--smooth_rad") f.plan.wrist_smoothing.rotation_tolerance = std::stod(v);
    else throw std::runtime_error("unknown flag " + a);
  }
  return f;
}

// The retargeting settings of the dynamics bench's wall section.
retarget::DynamicRetargetConfig FastConfig(const Flags& f) {
  retarget::DynamicRetargetConfig c;
  c.preset = "fast";
  c.robots_dir = (kData / "robots").string();
  c.kinematic.restarts = 1;
  c.kinematic.contact_weight = 16;
  c.kinematic.contact_depth = 0.01;
  c.scene.density = 400;
  c.sampler.threads = f.threads;
  if (f.default_scene) {
    c.kinematic = retarget::KinematicConfig{};
    c.scene = retarget::DynamicRetargetConfig{}.scene;
  }
  return c;
}

void Save(const retarget::HandTrajectory& t, const fs::path& dir) {
  retarget::WriteTrajectoryJson(t, dir / "trajectory.json.tmp");
  fs::rename(dir / "trajectory.json.tmp", dir / "trajectory.json");
}

// One reference along the rungs of `config` (one rung for a preset), as
// the `retarget` stage runs them: the scene, model and kinematic reference
// once (ClipRetarget), then a rung only when the one before failed. The
// kept trajectory carries the ladder's measurements; made.json holds each
// rung's wall and CPU seconds and the preparation's.
// --trace_windows: one line per planning window in [trace_from, trace_to]
// s; returns (and object heights at the horizon's end) of the plan entering
// the window, the reference's controls, the best sample and the executed
// weighted mean, each rolled out from the window's start state; below
// each window, every plan's return parts (PlanOutcome).
retarget::WindowTraceFn WindowPrinter(const Flags& f, const std::string& label) {
  if (f.trace_from > f.trace_to) return {};
  std::fprintf(stderr, "%s trace: t s | ref z | nominal ret z | ref-ctrl ret z | best ret z (scored) | executed ret z "
               "| it | finger gap rad, contacts, force N\n", label.c_str());
  return [f, label](const retarget::WindowTrace& w) {
    if (w.time < f.trace_from - 1e-9 || w.time > f.trace_to + 1e-9) return;
    std::fprintf(stderr, "%s trace: %5.2f-%5.2f | %.3f | %8.4f %.3f | %8.4f %.3f | %8.4f %.3f (%8.4f) | %8.4f %.3f | %2d "
                 "| %.3f, %d, %.2f\n", label.c_str(), w.time, w.end_time, w.ref_object_z, w.nominal.ret,
                 w.nominal.object_z, w.reference.ret, w.reference.object_z, w.best.ret, w.best.object_z,
                 w.best_score, w.executed.ret, w.executed.object_z, w.iterations, w.finger_gap,
                 w.object_contacts, w.object_force);
    const std::pair<const char*, const retarget::PlanOutcome*> plans[] = {
        {"nominal", &w.nominal}, {"ref-ctrl", &w.reference}, {"best", &w.best}, {"executed", &w.executed}};
    for (const auto& [name, o] : plans) {
      std::fprintf(stderr, "%s trace:   %-8s parts: object pos %.4f rot %.4f | wrist pos %.4f rot %.4f | fingers "
                   "%.4f | penetration %.4f transition %.4f\n", label.c_str(), name, o->object_pos, o->object_rot,
                   o->wrist_pos, o->wrist_rot, o->fingers, o->penetration, o->transition);
    }
  };
}

void MakeRungs(const Flags& f, const recon::Reconstruction& r, const TriMesh& mesh,
               const retarget::DynamicRetargetConfig& config, const fs::path& dir) {
  const std::string label = dir.filename().string();
  const double cpu0 = bench::SelfCpu();
  const auto t0 = Clock::now();
  std::optional<retarget::ClipRetarget> clip;
  Json made = {{"preset", config.preset}, {"rungs", Json::array()}};
  const std::function<retarget::DynamicRetargetRun(const std::string&)> track = [&](const std::string& rung) {
    if (!clip) {
      clip.emplace(r, mesh, retarget::FindEmbodiment(config.hand, config.robots_dir), config, dir / "scene", label);
      made["prepare_seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
      made["prepare_cpu_seconds"] = bench::SelfCpu() - cpu0;
    }
    const double rung_cpu0 = bench::SelfCpu();
    const auto r0 = Clock::now();
    retarget::DynamicRetargetRun run = clip->Track(retarget::RungSampler(config, rung), {}, WindowPrinter(f, label + " " + rung));
    const double seconds = std::chrono::duration<double>(Clock::now() - r0).count();
    const double cpu = bench::SelfCpu() - rung_cpu0;
    made["rungs"].push_back({{"name", rung}, {"seconds", seconds}, {"cpu_seconds", cpu},
                             {"success", run.metrics.success}, {"e_pos", run.metrics.e_pos},
                             {"e_rot", run.metrics.e_rot}});
    std::fprintf(stderr, "%s rung %s: success %d (E_pos %.3f, E_rot %.3f), %.0f s wall, %.0f s CPU\n",
                 label.c_str(), rung.c_str(), run.metrics.success, run.metrics.e_pos, run.metrics.e_rot, seconds,
                 cpu);
    return run;
  };
  retarget::LadderResult<retarget::DynamicRetargetRun> ladder = retarget::RunLadder(retarget::LadderRungs(config), track);
  retarget::HandTrajectory& t = ladder.best.trajectory;
  retarget::WriteLadderMeasurements(ladder.rungs, ladder.best_rung, t.metrics);
  made["kept"] = ladder.rungs[ladder.best_rung].name;
  made["success"] = ladder.best.metrics.success;
  made["seconds"] = std::chrono::duration<double>(Clock::now() - t0).count();
  made["cpu_seconds"] = bench::SelfCpu() - cpu0;
  Save(t, dir);
  std::ofstream(dir / "made.json") << made.dump(1) << "\n";
  std::fprintf(stderr, "made %s: success %d at rung %s, %.0f s wall, %.0f s CPU\n", label.c_str(),
               ladder.best.metrics.success, made["kept"].get<std::string>().c_str(), made["seconds"].get<double>(),
               made["cpu_seconds"].get<double>());
}

// Reference i as the dynamics bench makes it (verb, object, approach vary with i).
struct SingleReference {
  TriMesh mesh;
  recon::Reconstruction clean, noisy;
};
SingleReference MakeSingleReference(const Flags& f, int i) {
  const synth::Verb verbs[] = {synth::Verb::kPickPlace, synth::Verb::kLiftRotate, synth::Verb::kSlide};
  SingleReference s;
  s.mesh = i % 2 ? synth::MakeBox(0.05, 0.05, 0.08) : synth::MakeCylinder(0.03 + 0.005 * (i % 3), 0.09, 16);
  synth::EpisodeSpec spec;
  spec.verb = verbs[i % 3];
  spec.frames = static_cast<int>(f.clip_seconds * 30);
  spec.manipulation_scale = 2.0;
  spec.object_yaw = 0.4 * i;
  spec.approach_elevation = 0.55;
  spec.grasp = synth::GraspTypeFromName("pinch");
  spec.approach_azimuth = -0.35 + 0.1 * ((i / 3) % 4);
  s.clean = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, s.mesh), 30.0);
  s.noisy = s.clean;
  synth::AddReconstructionNoise(s.noisy, {}, 1000 + i);
  return s;
}

void MakeSingle(const Flags& f, int i) {
  const SingleReference s = MakeSingleReference(f, i);
  retarget::DynamicRetargetConfig config = FastConfig(f);
  config.preset = f.preset;
  if (!f.sampler_patch.is_null()) {
    Json sampler = retarget::SamplerPreset(f.preset);
    sampler.merge_patch(f.sampler_patch);
    sampler["threads"] = f.threads;
    config.sampler = sampler.get<retarget::AnnealedSamplerConfig>();
    retarget::CheckConfig(config.sampler, "--sampler");
    config.preset = "";
  }
  for (int n = 0; n < 2; ++n) {
    const fs::path dir = f.cache / ("ref" + std::to_string(i) + (n ? "_noisy" : "_clean"));
    if (fs::exists(dir / "trajectory.json") || (!f.only.empty() && dir.filename() != f.only)) continue;
    fs::create_directories(dir);
    MakeRungs(f, n ? s.noisy : s.clean, s.mesh, config, dir);
  }
}

// --diagnose: for each made reference, the object's error over time in the
// cached trajectory against the reference (a late drop, a drift or an
// offset), beside an open-loop replay of the kinematic reference (the
// sampler's nominal controls alone: one iteration, no noise) and whether
// the reference's grasp at its highest frame holds the object for 1 s
// (eval/reference_hold.h).
void Diagnose(const Flags& f, int i) {
  const SingleReference s = MakeSingleReference(f, i);
  for (int n = 0; n < 2; ++n) {
    const fs::path dir = f.cache / ("ref" + std::to_string(i) + (n ? "_noisy" : "_clean"));
    if (!fs::exists(dir / "trajectory.json")) continue;
    const recon::Reconstruction& r = n ? s.noisy : s.clean;
    const std::vector<Pose> ref = retarget::FilledObjectPoses(r);
    const retarget::HandTrajectory made = retarget::ReadTrajectoryJson(dir / "trajectory.json");
    retarget::DynamicRetargetConfig replay = FastConfig(f);
    replay.preset = "";
    replay.sampler = retarget::SamplerPreset("fast");
    replay.sampler.threads = f.threads;
    // Every sample the nominal (no noise; the planner draws at least two): the reference's controls alone.
    replay.sampler.num_samples = 2;
    replay.sampler.max_num_iterations = 1;
    replay.sampler.pos_noise_scale = replay.sampler.rot_noise_scale = replay.sampler.joint_noise_scale = 0;
    const double cpu0 = bench::SelfCpu();
    const retarget::DynamicRetargetRun run =
        retarget::ClipRetarget(r, s.mesh, retarget::FindEmbodiment(replay.hand, replay.robots_dir), replay,
                               dir / "diagnose_scene", "diagnose")
            .Track(replay.sampler, {}, WindowPrinter(f, dir.filename().string() + " replay"));
    int top = 0;
    for (int k = 0; k < r.frames(); ++k) top = ref[k].t.z() > ref[top].t.z() ? k : top;
    const retarget::ModelPtr m = retarget::CompileMjcfText(run.robot_scene_xml, (dir / "diagnose_scene" / "robot_scene.xml").string());
    const retarget::DataPtr d = retarget::MakeData(m.get());
    const double drop = retarget::ReferenceHoldDrop(m.get(), d.get(), run.kinematic, top, ref[top], 1.0);
    const retarget::TrackingMetrics mm = retarget::ObjectTrackingMetrics(made.object_poses, ref);
    // The object left where it starts: what the success threshold separates a lift from.
    const retarget::TrackingMetrics rest =
        retarget::ObjectTrackingMetrics(std::vector<Pose>(ref.size(), made.object_poses.front()), ref);
    std::printf("\n== %s: trajectory E_pos %.3f E_rot %.3f; kinematic replay E_pos %.3f E_rot %.3f "
                "(%.0f CPU s); object left at rest E_pos %.3f E_rot %.3f; grasp at the highest frame %d (z %.3f): "
                "object falls %.3f m in 1 s\n",
                dir.filename().c_str(), mm.e_pos, mm.e_rot, run.metrics.e_pos, run.metrics.e_rot,
                bench::SelfCpu() - cpu0, rest.e_pos, rest.e_rot, top, ref[top].t.z(), drop);
    // How far the trajectory's hand is from the kinematic reference it
    // tracked (qpos: wrist x y z, wrist rotations, then the fingers).
    const auto hand_off = [&](const retarget::HandTrajectory& t, int k) {
      const Eigen::VectorXd e = t.qpos[k] - run.kinematic.qpos[k];
      return std::pair{1000 * e.head<3>().norm(), e.tail(e.size() - 6).cwiseAbs().mean()};
    };
    std::printf("%6s | %7s | %7s %8s %8s %8s %8s | %7s %8s %8s %8s\n", "t s", "ref z", "traj z", "E_pos m", "E_rot",
                "wrist mm", "fing rad", "replay z", "E_pos m", "wrist mm", "fing rad");
    const auto& sim = run.trajectory.object_poses;
    for (int k = 0; k < r.frames(); k += std::max(1, r.frames() / 20)) {
      const auto [tw, tf] = hand_off(made, k);
      const auto [rw, rf] = hand_off(run.trajectory, k);
      std::printf("%6.2f | %7.3f | %7.3f %8.3f %8.3f %8.1f %8.3f | %7.3f %8.3f %8.1f %8.3f\n", k / 30.0,
                  ref[k].t.z(), made.object_poses[k].t.z(), (made.object_poses[k].t - ref[k].t).norm(),
                  RotationAngle(ref[k].q, made.object_poses[k].q), tw, tf, sim[k].t.z(),
                  (sim[k].t - ref[k].t).norm(), rw, rf);
    }
  }
}

void MakeHot3d(const Flags& f) {
  const fs::path dir = f.cache / "hot3d_left";
  const auto recording = kData / "hot3d_sample" / "Aria" / "P0003_c701bd11";
  if (fs::exists(dir / "trajectory.json") || !fs::exists(recording)) return;
  recon::Hot3dReferenceOptions o;
  o.hand = "left";
  o.object_uid = "228358276546933";  // the coffee pot, a 5-cm sphere standing in
  o.stand_in = synth::MakeSphere(0.05);
  const recon::Hot3dReference ref = recon::Hot3dToReconstruction(
      recon::ReadHot3dRecording(recording), kData / "hot3d_sample" / "object_library", o);
  retarget::DynamicRetargetConfig config = FastConfig(f);
  config.hand = "sharpa_left";
  fs::create_directories(dir);
  const retarget::DynamicRetargetRun run = retarget::RetargetReconstruction(
      ref.reconstruction, ref.mesh, retarget::FindEmbodiment(config.hand, config.robots_dir), config,
      dir / "scene", "hot3d");
  Save(run.trajectory, dir);
  std::fprintf(stderr, "made hot3d_left: success %d\n", run.metrics.success);
}

void MakeCarry(const Flags& f, int i) {
  const fs::path dir = f.cache / ("carry" + std::to_string(i));
  if (fs::exists(dir / "trajectory.json")) return;
  synth::EpisodeSpec spec;
  spec.frames = static_cast<int>(f.carry_seconds * 30);
  spec.two_hand_task = synth::TwoHandTask::kCarry;
  spec.grasp = synth::GraspTypeFromName("pinch");
  spec.object_yaw = 0.4 * i;
  spec.approach_azimuth = -0.35 + 0.1 * (i % 4);
  const TriMesh mesh = i % 2 ? synth::MakeBox(0.06, 0.06, 0.09) : synth::MakeCylinder(0.035, 0.10, 16);
  const recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, mesh), 30.0);
  const retarget::DynamicRetargetConfig config = FastConfig(f);
  const auto robots = kData / "robots";
  fs::create_directories(dir);
  const retarget::BimanualRun run =
      retarget::RetargetBimanual(r, mesh, retarget::FindEmbodiment("sharpa_left", robots),
                                 retarget::FindEmbodiment("sharpa_right", robots), config, dir / "scene", "carry");
  Save(run.trajectory, dir);
  std::fprintf(stderr, "made carry%d: success %d\n", i, run.metrics.success);
}

struct Row {
  std::string name;
  bool ok = false;
  double slowdown = 0;
  int reference_success = -1, arm_success = -1;
  double wrist_mean = 0, wrist_max = 0;
  double between_frames = 0;  // m: the largest flange deviation between frames (plan.h PathDeviation)
  std::string why;
};

// The plan's checks for a row's `why`: counts, and the between-frames
// deviation with the frames of its worst run.
std::string Checks(const deploy::Plan& plan) {
  const deploy::PathDeviation& d = plan.path_deviation;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "%zu unreachable, %zu too fast, %zu too abrupt, %d off path (between frames "
                "%.1f mm / %.3f rad", plan.unreachable.size(), plan.too_fast.size(), plan.over_acceleration.size(),
                d.OffPathCommands(), 1000 * d.position_max, d.rotation_max);
  std::string out = buf;
  if (!d.off_path.empty()) {
    const auto worst = std::max_element(d.off_path.begin(), d.off_path.end(), [](const auto& a, const auto& b) {
      return a.position_deviation < b.position_deviation;
    });
    std::snprintf(buf, sizeof(buf), "; worst between frames %d-%d, joint step %.2f rad", worst->from_frame,
                  worst->to_frame, worst->joint_jump);
    out += buf;
  }
  return out + ")";
}

// The plan's commands at the video's own clock (no lead moves, time map
// the identity): what the floating hand did in the retargeting.
deploy::Plan AtVideoClock(const deploy::Plan& plan) {
  deploy::Plan video = plan;
  video.lead_in = video.lead_out = 0;
  video.times.clear();
  video.source_times.clear();
  const int count = static_cast<int>(std::floor(plan.trajectory_duration * plan.rate_hz)) + 1;
  for (int k = 0; k < count; ++k) {
    video.times.push_back(k / plan.rate_hz);
    video.source_times.push_back(k / plan.rate_hz);
  }
  // The arm's path at trajectory time s, from the re-timed commands (the
  // time map inverted), ignoring the arm's limits.
  video.arm.clear();
  video.hand.clear();
  const size_t begin = plan.lead_in, end = plan.times.size() - plan.lead_out;
  size_t c = begin;
  for (int k = 0; k < count; ++k) {
    const double s = k / plan.rate_hz;
    while (c + 1 < end && plan.source_times[c + 1] < s) ++c;
    const size_t n = std::min(c + 1, end - 1);
    const double span = plan.source_times[n] - plan.source_times[c];
    const double a = span > 0 ? std::clamp((s - plan.source_times[c]) / span, 0.0, 1.0) : 0.0;
    video.arm.push_back((1 - a) * plan.arm[c] + a * plan.arm[n]);
    video.hand.push_back((1 - a) * plan.hand[c] + a * plan.hand[n]);
  }
  return video;
}

std::string Outcome(const char* what, const deploy::ReplayReport& r) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%s %s %.0f mm %.2f rad (wrist %.1f mm %.3f rad)", what,
                r.success ? "ok" : "LOST", 1000 * r.object_position_error_mean, r.object_rotation_error_mean,
                1000 * r.wrist_position_error_mean, r.wrist_rotation_error_mean);
  return buf;
}

// The arm's replay against the floating hand's: re-timed, and at the video's clock.
// With --only, command by command (every 25th): object, wrist and finger
// errors and hand-object contacts, arm | floating hand.
void PrintCommands(const deploy::Plan& plan, const deploy::ReplayReport& floating) {
  const deploy::ReplayReport& r = plan.replay;
  std::printf("  %7s %7s | arm: object mm rad, wrist mm, fingers rad, contacts | floating: the same\n", "t s",
              "traj s");
  for (size_t k = 0; k < r.object_position_error.size() && k < floating.object_position_error.size(); k += 25) {
    const size_t c = k + plan.lead_in;
    std::printf("  %7.2f %7.2f | %6.1f %5.2f %5.1f %5.3f %2d | %6.1f %5.2f %5.1f %5.3f %2d\n", plan.times[c],
                plan.source_times[c], 1000 * r.object_position_error[k], r.object_rotation_error[k],
                1000 * r.wrist_position_error[k], r.finger_error[k], r.hand_contacts[k],
                1000 * floating.object_position_error[k], floating.object_rotation_error[k],
                1000 * floating.wrist_position_error[k], floating.finger_error[k], floating.hand_contacts[k]);
  }
}

void Compare(const Flags& f, const deploy::Plan& plan, const retarget::HandTrajectory& t,
             const retarget::Embodiment& hand, const retarget::TrajectoryFiles& files) {
  const std::string xml = retarget::ReadSceneXml(files.scene_dir);
  deploy::Plan floating = plan, video = AtVideoClock(plan);
  deploy::ReplayPlan(floating, t, hand, xml, files.scene_dir, f.plan.servo_omega, deploy::ReplayMount::kFloating);
  deploy::ReplayPlan(video, t, hand, xml, files.scene_dir, f.plan.servo_omega, deploy::ReplayMount::kFloating);
  deploy::Plan arm_video = AtVideoClock(plan);
  deploy::ReplayPlan(arm_video, t, hand, xml, files.scene_dir, f.plan.servo_omega);
  std::printf("  compare %-12s %.2fx: %s | %s | %s\n", files.trajectory.parent_path().filename().c_str(),
              plan.slowdown, Outcome("arm", plan.replay).c_str(), Outcome("floating re-timed", floating.replay).c_str(),
              Outcome("floating video clock", video.replay).c_str());
  std::printf("  compare %-12s 1.00x: %s\n", files.trajectory.parent_path().filename().c_str(),
              Outcome("arm at the video clock (limits ignored)", arm_video.replay).c_str());
  if (!f.only.empty()) PrintCommands(plan, floating.replay);
}

Row PlanOne(const Flags& f, const fs::path& dir, std::string name = {}) {
  Row row{.name = name.empty() ? dir.filename().string() : name};
  const retarget::TrajectoryFiles files = retarget::FilesBeside(dir / "trajectory.json");
  const retarget::HandTrajectory t = retarget::ReadTrajectoryJson(files.trajectory);
  const retarget::Embodiment hand = retarget::FindEmbodiment(t.embodiment, kData / "robots");
  deploy::Plan plan = deploy::MakePlan(t, hand, f.plan);
  if (f.replay && !t.object_poses.empty()) {
    const std::string xml = retarget::ReadSceneXml(files.scene_dir);
    deploy::FollowedPlan followed = deploy::PlanOnFloatingWrist(plan, t, hand, f.plan, xml, files.scene_dir);
    plan = std::move(followed.plan);
    deploy::ReplayPlan(plan, followed.trajectory, hand, xml, files.scene_dir, f.plan.servo_omega);
    if (f.compare) Compare(f, plan, followed.trajectory, hand, files);
  }
  row.ok = plan.ok;
  row.slowdown = plan.slowdown;
  row.reference_success = plan.replay.reference_success;
  row.arm_success = plan.replay.ran ? plan.replay.success : -1;
  row.wrist_mean = plan.replay.wrist_position_error_mean;
  row.wrist_max = plan.replay.wrist_position_error_max;
  row.between_frames = plan.path_deviation.position_max;
  row.why = Checks(plan);
  {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "; placed yaw %.0f deg at (%.2f, %.2f) m", plan.placement.yaw * 180 / M_PI,
                  plan.placement.x, plan.placement.y);
    row.why += buf;
  }
  if (plan.wrist_smoothing.applied) {
    char buf[128];
    std::snprintf(buf, sizeof(buf), "; smoothed at %.1f Hz: wrist moved <= %.1f mm / %.3f rad, %d frames bounded",
                  plan.wrist_smoothing.cutoff_hz, 1000 * plan.wrist_smoothing.position_deviation_max,
                  plan.wrist_smoothing.rotation_deviation_max, plan.wrist_smoothing.bounded_frames);
    row.why += buf;
  }
  if (plan.replay.ran) {
    char buf[128];
    std::snprintf(buf, sizeof(buf), "; object %.0f mm / %.2f rad", 1000 * plan.replay.object_position_error_mean,
                  plan.replay.object_rotation_error_mean);
    row.why += buf;
  }
  return row;
}

// Both arms' wrist tracking and the object, for a row's `why`.
std::string TwoArmOutcome(const char* what, const deploy::BimanualPlan& plan) {
  const deploy::ReplayReport& l = plan.left.replay;
  const deploy::ReplayReport& r = plan.right.replay;
  char buf[200];
  std::snprintf(buf, sizeof(buf), "%s %s %.0f mm %.2f rad (wrist left %.1f / %.1f mm, right %.1f / %.1f mm)",
                what, r.success ? "ok" : "LOST", 1000 * r.object_position_error_mean, r.object_rotation_error_mean,
                1000 * l.wrist_position_error_mean, 1000 * l.wrist_position_error_max,
                1000 * r.wrist_position_error_mean, 1000 * r.wrist_position_error_max);
  return buf;
}

// The two-arm plan replayed with both arms (and, with --compare, on the two
// floating hands under the same time map).
void ReplayTwo(const Flags& f, deploy::BimanualPlan& plan, const retarget::HandTrajectory& both,
               const retarget::Embodiment& left_hand, const retarget::Embodiment& right_hand, const fs::path& dir) {
  const retarget::TrajectoryFiles files = retarget::FilesBeside(dir / "trajectory.json");
  const std::string xml = retarget::ReadSceneXml(files.scene_dir);
  deploy::BimanualPlan floating = plan;
  deploy::ReplayBimanualPlan(plan, both, left_hand, right_hand, xml, files.scene_dir, f.plan.servo_omega);
  if (!f.compare) return;
  deploy::ReplayBimanualPlan(floating, both, left_hand, right_hand, xml, files.scene_dir, f.plan.servo_omega,
                             deploy::ReplayMount::kFloating);
  deploy::BimanualPlan video = plan;
  video.left = AtVideoClock(plan.left);
  video.right = AtVideoClock(plan.right);
  deploy::ReplayBimanualPlan(video, both, left_hand, right_hand, xml, files.scene_dir, f.plan.servo_omega,
                             deploy::ReplayMount::kFloating);
  std::printf("  compare %-12s %.2fx: %s | %s | %s\n", dir.filename().c_str(), plan.right.slowdown,
              TwoArmOutcome("arms", plan).c_str(), TwoArmOutcome("floating re-timed", floating).c_str(),
              TwoArmOutcome("floating video clock", video).c_str());
}

Row PlanTwo(const Flags& f, const fs::path& dir) {
  Row row{.name = dir.filename().string()};
  const retarget::HandTrajectory both = retarget::ReadTrajectoryJson(dir / "trajectory.json");
  const auto [left, right] = retarget::SplitBimanualTrajectory(both);
  const retarget::Embodiment left_hand = retarget::FindEmbodiment(left.embodiment, kData / "robots");
  const retarget::Embodiment right_hand = retarget::FindEmbodiment(right.embodiment, kData / "robots");
  deploy::BimanualConfig config;
  config.plan = f.plan;
  deploy::BimanualPlan plan = deploy::MakeBimanualPlan(left, right, left_hand, right_hand, config);
  if (f.replay) ReplayTwo(f, plan, both, left_hand, right_hand, dir);
  row.ok = plan.ok;
  row.slowdown = plan.right.slowdown;
  row.reference_success = left.metrics.value("success", false);
  const double closest = *std::min_element(plan.arm_distance.begin(), plan.arm_distance.end());
  row.between_frames = std::max(plan.left.path_deviation.position_max, plan.right.path_deviation.position_max);
  row.why = "left " + Checks(plan.left) + " / right " + Checks(plan.right) + "; " +
            std::to_string(plan.collisions.size()) + " collisions, closest " + std::to_string(closest).substr(0, 5) +
            " m";
  if (plan.right.replay.ran) {
    const deploy::ReplayReport& l = plan.left.replay;
    const deploy::ReplayReport& r = plan.right.replay;
    row.arm_success = r.success;
    row.wrist_mean = 0.5 * (l.wrist_position_error_mean + r.wrist_position_error_mean);
    row.wrist_max = std::max(l.wrist_position_error_max, r.wrist_position_error_max);
    row.why += "; " + TwoArmOutcome("arms", plan);
  }
  return row;
}

void Report(const std::vector<Row>& rows) {
  std::printf("%-14s | %-4s | %8s | %-13s | %-17s | %-8s | %s\n", "reference", "ok", "slowdown", "success f/arm",
              "wrist mm mean/max", "betw. mm", "checks");
  std::vector<double> slowdowns;
  int ok = 0, ref_success = 0, arm_success = 0, replays = 0, kept = 0;
  double wrist_sum = 0, wrist_max = 0, between_max = 0;
  for (const Row& r : rows) {
    std::printf("%-14s | %-4s | %7.2fx | %4d / %-6d | %6.1f / %-7.1f | %8.1f | %s\n", r.name.c_str(),
                r.ok ? "yes" : "NO", r.slowdown, r.reference_success, r.arm_success, 1000 * r.wrist_mean,
                1000 * r.wrist_max, 1000 * r.between_frames, r.why.c_str());
    between_max = std::max(between_max, r.between_frames);
    ok += r.ok;
    slowdowns.push_back(r.slowdown);
    if (r.arm_success < 0) continue;
    ++replays;
    ref_success += r.reference_success > 0;
    arm_success += r.arm_success;
    kept += r.reference_success > 0 && r.arm_success > 0;
    wrist_sum += r.wrist_mean;
    wrist_max = std::max(wrist_max, r.wrist_max);
  }
  if (rows.empty()) return;
  std::sort(slowdowns.begin(), slowdowns.end());
  const size_t n = slowdowns.size();
  const double median = n % 2 ? slowdowns[n / 2] : 0.5 * (slowdowns[n / 2 - 1] + slowdowns[n / 2]);
  std::printf("passing every check: %d of %zu (%.0f%%); slowdown median %.2fx, max %.2fx; flange between frames "
              "max %.1f mm\n", ok, n, 100.0 * ok / n, median, slowdowns.back(), 1000 * between_max);
  if (replays) {
    std::printf("object success over %d replays: floating hand %d (%.0f%%), arm %d (%.0f%%), the arm keeps %d of "
                "the floating hand's %d; wrist tracking mean %.2f mm, max %.2f mm\n", replays, ref_success,
                100.0 * ref_success / replays, arm_success, 100.0 * arm_success / replays, kept, ref_success,
                1000 * wrist_sum / replays, 1000 * wrist_max);
  }
}

// The single-hand references' retargeting from their made.json: per
// reference the rungs that ran, the kept one, the first rung alone against
// the whole run; then the kept rungs' shares and the sums.
void ReportRungs(const Flags& f) {
  std::printf("\n== Retargeting (made.json): per reference the rungs run (success, wall / CPU s), the first "
              "rung alone against the whole run (preparation included in both)\n");
  std::map<std::string, int> kept;
  int n = 0, first_ok = 0, all_ok = 0;
  double first_wall = 0, first_cpu = 0, all_wall = 0, all_cpu = 0;
  for (int i = 0; i < f.refs; ++i) {
    for (const char* kind : {"_clean", "_noisy"}) {
      const fs::path path = f.cache / ("ref" + std::to_string(i) + kind) / "made.json";
      if (!fs::exists(path)) continue;
      const Json made = Json::parse(std::ifstream(path));
      const Json& first = made["rungs"][0];
      const double prep = made["prepare_seconds"].get<double>(), prep_cpu = made["prepare_cpu_seconds"].get<double>();
      std::string rungs;
      for (const Json& r : made["rungs"]) {
        char buf[96];
        std::snprintf(buf, sizeof(buf), " %s %d %.0f/%.0f", r["name"].get<std::string>().c_str(),
                      r["success"].get<bool>(), r["seconds"].get<double>(), r["cpu_seconds"].get<double>());
        rungs += buf;
      }
      std::printf("%-14s | %-7s | kept %-6s %d | first alone %d %6.0f / %6.0f s | all %6.0f / %6.0f s |%s\n",
                  path.parent_path().filename().c_str(), made["preset"].get<std::string>().c_str(),
                  made["kept"].get<std::string>().c_str(), made["success"].get<bool>(), first["success"].get<bool>(),
                  prep + first["seconds"].get<double>(), prep_cpu + first["cpu_seconds"].get<double>(),
                  made["seconds"].get<double>(), made["cpu_seconds"].get<double>(), rungs.c_str());
      ++n;
      ++kept[made["success"].get<bool>() ? made["kept"].get<std::string>() : "none"];
      first_ok += first["success"].get<bool>();
      all_ok += made["success"].get<bool>();
      first_wall += prep + first["seconds"].get<double>();
      first_cpu += prep_cpu + first["cpu_seconds"].get<double>();
      all_wall += made["seconds"].get<double>();
      all_cpu += made["cpu_seconds"].get<double>();
    }
  }
  if (!n) return;
  std::printf("%d references: first rung alone success %d, %.0f s wall, %.0f s CPU in all; whole run success %d, "
              "%.0f s wall, %.0f s CPU in all; kept rung:", n, first_ok, first_wall, first_cpu, all_ok, all_wall,
              all_cpu);
  for (const auto& [rung, count] : kept) std::printf(" %s %d of %d,", rung.c_str(), count, n);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  const Flags f = Parse(argc, argv);
  fs::create_directories(f.cache);
  const auto t0 = Clock::now();
  if (f.diagnose) {
    for (int i = f.from; i < f.refs; ++i) Diagnose(f, i);
    return 0;
  }
  for (int i = f.from; i < f.refs && !f.plan_only; ++i) MakeSingle(f, i);
  if (!f.plan_only && f.hot3d) MakeHot3d(f);
  for (int i = 0; i < f.carries && !f.plan_only; ++i) MakeCarry(f, i);
  std::fprintf(stderr, "trajectories ready in %s (%.0f s)\n", f.cache.c_str(),
               std::chrono::duration<double>(Clock::now() - t0).count());
  if (f.make_only) return 0;
  std::vector<Row> single, two;
  const auto t1 = Clock::now();
  // Every cached trajectory there is (--plan_only plans what is made so far).
  const auto made = [&](const fs::path& dir) {
    return fs::exists(dir / "trajectory.json") && (f.only.empty() || dir.filename() == f.only);
  };
  for (int i = 0; i < f.refs; ++i) {
    for (const char* kind : {"_clean", "_noisy"}) {
      const fs::path dir = f.cache / ("ref" + std::to_string(i) + kind);
      if (made(dir)) single.push_back(PlanOne(f, dir));
    }
  }
  if (f.hot3d && made(f.cache / "hot3d_left")) single.push_back(PlanOne(f, f.cache / "hot3d_left"));
  for (int i = 0; i < f.carries; ++i) {
    const fs::path dir = f.cache / ("carry" + std::to_string(i));
    if (made(dir)) two.push_back(PlanTwo(f, dir));
  }
  std::printf("== One arm: %zu trajectories (%d synthetic %.0f-s references clean + noisy, %s; HOT3D fast)\n",
              single.size(), f.refs, f.clip_seconds, f.preset.c_str());
  Report(single);
  ReportRungs(f);
  std::printf("\n== Two arms (deploy plan-two, one clock): %zu synthetic carries\n", two.size());
  Report(two);
  std::vector<Row> real;
  if (!f.real.empty()) {
    std::vector<fs::path> found;
    for (const auto& e : fs::recursive_directory_iterator(f.real)) {
      if (e.path().filename() == "trajectory.json" && e.path().parent_path().filename() == "retarget_kinematic") {
        found.push_back(e.path().parent_path());
      }
    }
    std::sort(found.begin(), found.end());
    for (const fs::path& dir : found) real.push_back(PlanOne(f, dir, "real " + dir.parent_path().filename().string()));
    std::printf("\n== Real clips, hand-only (retarget_kinematic, wrist tracking only): %zu under %s\n", real.size(),
                f.real.c_str());
    Report(real);
  }
  std::vector<Row> all = single;
  all.insert(all.end(), real.begin(), real.end());
  all.insert(all.end(), two.begin(), two.end());
  std::printf("\n== All %zu plans\n", all.size());
  Report(all);
  std::printf("planning and replay: %.0f s\n", std::chrono::duration<double>(Clock::now() - t1).count());
  return 0;
}
