// Dynamics-aware retargeting (seed section 3.2), measured side by side:
//  1. the ablation of seed Table 3 in kind: synthetic pick-and-place,
//     lift-and-rotate and slide episodes (synth module; cylinders and boxes)
//     retargeted from their exact reconstruction ("clean") and from the same
//     with reconstruction-like noise ("noisy": depth-scale error, hand-object
//     misalignment, jitter, a discontinuity); rows: annealed sampling
//     (SPIDER) -> + warmup -> + perturbation -> + transition reward;
//     success rate, mean E_pos, mean E_rot per row;
//  2. simulation steps per second inside the optimiser against raw mj_step
//     of the same scene on the same number of threads: replaying the run's
//     own controls (the same contact load), and at rest from qpos0; and the
//     replay with MuJoCo's dense against its sparse constraint Jacobian;
//  3. wall time and success retargeting --wall_clips 10-s clips (from clip
//     --wall_first) with the fast preset, and on the first --seed_wall=N of
//     them (noisy) with the seed preset (14-17 min a clip; without it,
//     its bound at 32 iterations a plan, i.e. without early stops);
//  4. real references (--sections=hot3d): the HOT3D sample's hands and the
//     object each hand's fingertips come closest to (eval/hot3d_recording.h),
//     the left hand onto sharpa_left and, mirrored, onto sharpa_right; the
//     right hand onto sharpa_right; fast preset, and seed with --seed_wall;
//  5. the kinematic reference's grasps (--sections=grasp), with and without
//     the grasp terms (KinematicConfig contact_weight): hand-object contacts
//     per in-hand frame, the deepest penetration, and whether the grasp at
//     the highest frame holds the object for a second (reference_hold.h):
//     a reference whose own grasp drops the object cannot be tracked into a
//     lift (--grasp=wrap drops it: no opposing contact).
//  6. two hands (--sections=bimanual): synthetic handover, carry and
//     hold-and-act episodes (clean and noisy) and the HOT3D sample's two
//     hands, both robot hands in one scene (bimanual_retarget.h), rows as
//     the ablation's; success, E_pos, E_rot of the object, each wrist's
//     distance from its reference;
// Episodes' motions are scaled by --lift_scale (default 2: lifts of ~20 cm),
// so that an object left on the floor fails the 0.1 m success threshold.
// Sizes are flags, so a short run is possible:
//   retarget_dynamics_bench --refs=30 --frames=60 --samples=16 --iterations=3
//       --horizon=0.5 --threads=2 --clip_seconds=10 --sections=ablation,throughput,wall,hot3d,grasp,bimanual
//   [--contact_weight=16 --contact_depth=0.01 --contact_epsilon=E] (grasp terms in every section)
//   [--elevation=RAD] (the synthetic hand's approach above the horizontal; 0.55)
//   [--grasp=pinch|wrap] (the synthetic hand's grasp, synth::GraspType)
//   [--density=400] (kg/m^3 of the synthetic objects)
//   [--seed=0] (the sampler's seed: rerun to see how much a row moves by chance)
//   [--wall_clips=3 --wall_first=0 --seed_wall=0 --wall_preset=fast] (the wall-time section)
//   [--noise_scale=1] (times the sampler's noise; 0 replays the kinematic reference)
//   [--penetration_scale=3000 --terminal_scale=10] (RewardConfig; not where a preset replaces the flags)
//   [--ladder_clips=2 --ladder_first=0 --ladder_clean --ladder_presets=fast,medium] (section "ladder")
//   [--ladder_clean_only] (the ladder section on the clean references only)
//   [--ladder_alone=P,Q] (the presets run alone on every clip; the other rungs
//     run only where the ladder reaches them; default: every preset)
//  7. the ladder (--sections=ladder): each preset of --ladder_presets alone
//     on --ladder_clips clips, wall and CPU seconds and success per clip;
//     the ladder of those presets in that order is composed from the same
//     runs (a rung's run is the preset's run: same seed, deterministic), its
//     success, wall time (the rungs it ran) and the rungs' shares;
//  8. the default configuration (--sections=default): DynamicRetargetConfig{}
//     (the ladder) on a --clip_seconds synthetic clip (clean), wall and CPU
//     seconds per rung and in all, the rung that succeeded; as the stage,
//     the scene, model and kinematic reference are made once (ClipRetarget)
//     [--default_contact_weight=W replaces the default's grasp weight].
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <thread>

#include <sys/resource.h>

#include "core/error.h"
#include "core/hand_keypoints.h"
#include "eval/hot3d_recording.h"
#include "eval/reconstruction_noise.h"
#include "eval/reference_hold.h"
#include "retarget/dynamic/bimanual_retarget.h"
#include "retarget/dynamic/dynamic_retarget.h"
#include "retarget/dynamic/rollout_pool.h"
#include "synth/objects.h"

namespace {

using namespace doasido;
using namespace doasido::retarget;
using Clock = std::chrono::steady_clock;

const std::filesystem::path kData = DOASIDO_SHARED_DATA;

struct Flags {
  int refs = 30, frames = 60, samples = 16, iterations = 3, threads = 2;
  std::uint64_t seed = 0;  // the sampler's (AnnealedSamplerConfig::seed)
  double horizon = 0.5, ctrl_dt = 0.25, knot_dt = 0.25, clip_seconds = 10, lift_scale = 2.0;
  double improvement_threshold = 0.01;  // the sampler's early stop (AnnealedSamplerConfig)
  double noise_scale = 1;  // times the sampler's noise scales; 0 replays the kinematic reference
  double penetration_scale = -1;  // RewardConfig::penetration_penalty_scale; < 0 keeps the default
  double terminal_scale = -1;     // RewardConfig::terminal_rew_scale; < 0 keeps the default
  double elevation = 0.55;  // the synthetic hand's approach, radians above the horizontal
  // The synthetic references are grasped so that a robot hand copying them
  // can hold the object: the hand pinches (thumb against two fingers), the
  // kinematic reference presses touching fingertips 1 cm into the surface
  // (the grip a position-controlled hand needs), and the objects weigh what
  // hollow household objects of their size do (80-140 g). --grasp=wrap
  // --contact_weight=0 --density=1000 measure the references without.
  std::string grasp = "pinch";  // the synthetic hand's grasp (synth::GraspTypeName)
  double density = 400;         // kg/m^3 of the object (SceneConfig)
  // The kinematic reference's grasp terms (KinematicConfig); < 0 keeps the default.
  double contact_weight = 16, contact_depth = 0.01, contact_epsilon = -1;
  bool verbose = false;
  // The wall-time section's preset; "" runs --samples, --iterations, ... as given.
  std::string wall_preset = "fast";
  int wall_clips = 3;  // clips of the wall-time section
  int wall_first = 0;  // the index of its first clip (MakeCase)
  int seed_wall = 0;   // of those clips, how many also run the seed preset (noisy)
  std::string sections = "ablation,throughput,wall,hot3d,grasp,bimanual";
  // The ladder section: clips --ladder_first ... + --ladder_clips (noisy,
  // and clean with --ladder_clean), each preset of --ladder_presets alone;
  // the ladder (those presets in that order) follows from them.
  int ladder_clips = 2, ladder_first = 0;
  bool ladder_clean = false, ladder_clean_only = false;
  std::string ladder_presets = "fast,medium";
  std::string ladder_alone;  // "" = every preset of ladder_presets
  // The default section: >= 0 replaces the default config's
  // kinematic.contact_weight (to compare with the grasp terms off).
  double default_contact_weight = -1;
};

Flags Parse(int argc, char** argv) {
  Flags f;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto eq = a.find('=');
    const std::string k = a.substr(0, eq), v = eq == std::string::npos ? "1" : a.substr(eq + 1);
    if (k == "--refs") f.refs = std::stoi(v);
    else if (k == "--frames") f.frames = std::stoi(v);
    else if (k == "--samples") f.samples = std::stoi(v);
    else if (k == "--iterations") f.iterations = std::stoi(v);
    else if (k == "--threads") f.threads = std::stoi(v);
    else if (k == "--seed") f.seed = std::stoull(v);
    else if (k == "--horizon") f.horizon = std::stod(v);
    else if (k == "--ctrl_dt") f.ctrl_dt = std::stod(v);
    else if (k == "--knot_dt") f.knot_dt = std::stod(v);
    else if (k == "--improvement_threshold") f.improvement_threshold = std::stod(v);
    else if (k == "--noise_scale") f.noise_scale = std::stod(v);
    else if (k == "--penetration_scale") f.penetration_scale = std::stod(v);
    else if (k == "--terminal_scale") f.terminal_scale = std::stod(v);
    else if (k == "--clip_seconds") f.clip_seconds = std::stod(v);
    else if (k == "--wall_clips") f.wall_clips = std::stoi(v);
    else if (k == "--lift_scale") f.lift_scale = std::stod(v);
    else if (k == "--elevation") f.elevation = std::stod(v);
    else if (k == "--grasp") f.grasp = v;
    else if (k == "--density") f.density = std::stod(v);
    else if (k == "--contact_weight") f.contact_weight = std::stod(v);
    else if (k == "--contact_depth") f.contact_depth = std::stod(v);
    else if (k == "--contact_epsilon") f.contact_epsilon = std::stod(v);
    else if (k == "--seed_wall") f.seed_wall = std::stoi(v);
    else if (k == "--wall_first") f.wall_first = std::stoi(v);
    else if (k == "--wall_preset") f.wall_preset = eq == std::string::npos ? "" : v;
    else if (k == "--sections") f.sections = v;
    else if (k == "--ladder_clips") f.ladder_clips = std::stoi(v);
    else if (k == "--ladder_first") f.ladder_first = std::stoi(v);
    else if (k == "--ladder_clean") f.ladder_clean = v != "0";
    else if (k == "--ladder_clean_only") f.ladder_clean = f.ladder_clean_only = v != "0";
    else if (k == "--ladder_presets") f.ladder_presets = v;
    else if (k == "--ladder_alone") f.ladder_alone = v;
    else if (k == "--default_contact_weight") f.default_contact_weight = std::stod(v);
    else if (k == "--verbose") f.verbose = v != "0";
    else std::fprintf(stderr, "unknown flag %s\n", a.c_str());
  }
  return f;
}

struct Case {
  recon::Reconstruction clean, noisy;
  TriMesh mesh;
};

// Reference i: verb, object and approach vary with i; noise seeded by i.
Case MakeCase(const Flags& f, int i, int frames) {
  const synth::Verb verbs[] = {synth::Verb::kPickPlace, synth::Verb::kLiftRotate, synth::Verb::kSlide};
  Case c;
  c.mesh = i % 2 ? synth::MakeBox(0.05, 0.05, 0.08) : synth::MakeCylinder(0.03 + 0.005 * (i % 3), 0.09, 16);
  synth::EpisodeSpec spec;
  spec.verb = verbs[i % 3];
  spec.frames = frames;
  spec.manipulation_scale = f.lift_scale;
  spec.object_yaw = 0.4 * i;
  spec.approach_elevation = f.elevation;
  spec.grasp = synth::GraspTypeFromName(f.grasp);
  spec.approach_azimuth = -0.35 + 0.1 * ((i / 3) % 4);
  c.clean = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, c.mesh), 30.0);
  c.noisy = c.clean;
  synth::AddReconstructionNoise(c.noisy, {}, 1000 + i);
  return c;
}

DynamicRetargetConfig BaseConfig(const Flags& f) {
  DynamicRetargetConfig c;
  c.preset = "";
  c.robots_dir = (kData / "robots").string();
  c.kinematic.restarts = 1;
  if (f.contact_weight >= 0) c.kinematic.contact_weight = f.contact_weight;
  if (f.contact_depth >= 0) c.kinematic.contact_depth = f.contact_depth;
  if (f.contact_epsilon >= 0) c.kinematic.contact_epsilon = f.contact_epsilon;
  c.scene.density = f.density;
  AnnealedSamplerConfig& s = c.sampler;
  s.num_samples = f.samples;
  s.max_num_iterations = f.iterations;
  s.horizon = f.horizon;
  s.ctrl_dt = f.ctrl_dt;
  s.knot_dt = f.knot_dt;
  s.improvement_threshold = f.improvement_threshold;
  s.pos_noise_scale *= f.noise_scale;
  s.rot_noise_scale *= f.noise_scale;
  s.joint_noise_scale *= f.noise_scale;
  if (f.penetration_scale >= 0) s.reward.penetration_penalty_scale = f.penetration_scale;
  if (f.terminal_scale >= 0) s.reward.terminal_rew_scale = f.terminal_scale;
  s.blend_seconds = f.ctrl_dt;
  s.threads = f.threads;
  s.seed = f.seed;
  return c;
}

// The ablation's row `row` (0-3): annealed sampling, then + warmup, +
// perturbation, + transition reward (seed Table 3).
const char* const kAblationRows[] = {"annealed sampling", "+ warmup", "+ perturbation", "+ transition reward"};
DynamicRetargetConfig AblationRow(const Flags& f, int row) {
  DynamicRetargetConfig config = BaseConfig(f);
  config.sampler.warmup = row >= 1;
  config.sampler.warmup_seconds = f.horizon;
  config.sampler.perturb = row >= 2;
  config.sampler.reward.transition = row >= 3;
  return config;
}

struct Tally {
  int n = 0, success = 0, errors = 0;
  double e_pos = 0, e_rot = 0;
  void Add(const TrackingMetrics& m) {
    ++n;
    success += m.success;
    e_pos += m.e_pos;
    e_rot += m.e_rot;
  }
};

DynamicRetargetRun RunOne(const recon::Reconstruction& r, const TriMesh& mesh,
                          const DynamicRetargetConfig& c, const std::string& label,
                          const std::function<void(int, int)>& progress = {}) {
  const auto dir = std::filesystem::temp_directory_path() / "doasido-dynamics-bench";
  return RetargetReconstruction(r, mesh, FindEmbodiment(c.hand, c.robots_dir), c, dir, label, progress);
}

// The hand geom of contact c when it is between the hand and the object, else -1.
int HandGeomTouchingObject(const mjModel* m, const mjData* d, const SceneIndex& index, int c) {
  const mjContact& con = d->contact[c];
  const int b1 = m->geom_bodyid[con.geom1], b2 = m->geom_bodyid[con.geom2];
  if ((b1 == index.object_body) == (b2 == index.object_body) || b1 == 0 || b2 == 0) return -1;
  return b1 == index.object_body ? con.geom2 : con.geom1;
}

// Hand-object contacts when the hand stands at `traj`'s joints of frame k
// and the object at `object` (for --verbose): how many, and the deepest.
std::pair<int, double> Contacts(const mjModel* m, mjData* d, const HandTrajectory& traj, int k,
                                const Pose& object) {
  const SceneIndex index = IndexScene(m);
  PoseHandAndObject(m, d, traj, k, object);
  mj_forward(m, d);
  int n = 0;
  double deepest = 0;
  for (int c = 0; c < d->ncon; ++c) {
    if (HandGeomTouchingObject(m, d, index, c) < 0) continue;
    ++n;
    deepest = std::min(deepest, d->contact[c].dist);
  }
  return {n, deepest};
}

void Ablation(const Flags& f) {
  const auto& rows = kAblationRows;
  std::map<std::pair<int, int>, Tally> tally;  // (row, noisy)
  const auto t0 = Clock::now();
  for (int i = 0; i < f.refs; ++i) {
    const Case c = MakeCase(f, i, f.frames);
    for (int row = 0; row < 4; ++row) {
      const DynamicRetargetConfig config = AblationRow(f, row);
      for (int noisy = 0; noisy < 2; ++noisy) {
        Tally& t = tally[{row, noisy}];
        try {
          const recon::Reconstruction& r = noisy ? c.noisy : c.clean;
          const DynamicRetargetRun run = RunOne(r, c.mesh, config, "ref" + std::to_string(i));
          t.Add(run.metrics);
          if (f.verbose) {
            double lift_sim = 0, lift_ref = 0;
            for (int k = 0; k < r.frames(); ++k) {
              lift_sim = std::max(lift_sim, run.trajectory.object_poses[k].t.z() - run.trajectory.object_poses[0].t.z());
              lift_ref = std::max(lift_ref, r.object_poses[k].t.z() - r.object_poses[0].t.z());
            }
            std::fprintf(stderr, "\nref %d row %d %s: E_pos %.3f E_rot %.3f lift sim %.3f ref %.3f, in-hand frames %d, %lld steps %.1f s",
                         i, row, noisy ? "noisy" : "clean", run.metrics.e_pos, run.metrics.e_rot,
                         lift_sim, lift_ref, run.in_hand_frames, run.stats.sim_steps, run.stats.seconds);
            const ModelPtr m = CompileMjcfText(run.robot_scene_xml, (std::filesystem::temp_directory_path() / "doasido-dynamics-bench/robot_scene.xml").string());
            const DataPtr d = MakeData(m.get());
            for (int k = 0; k < r.frames(); k += 10) {
              const auto ref_c = Contacts(m.get(), d.get(), run.kinematic, k, r.object_poses[k]);
              const auto sim_c = Contacts(m.get(), d.get(), run.trajectory, k, run.trajectory.object_poses[k]);
              const Eigen::VectorXd dq = run.trajectory.qpos[k] - run.kinematic.qpos[k];
              std::fprintf(stderr, "\n   frame %2d: fingertips asked to touch %d; reference hand-object contacts %2d (deepest %.4f m), simulated %2d (%.4f m); "
                           "sim - ref: base %.4f m, largest joint %.3f rad; object %.3f m",
                           k, run.grasp_contacts.empty() ? 0 : run.grasp_contacts[k], ref_c.first, ref_c.second, sim_c.first, sim_c.second, dq.head(3).norm(),
                           dq.tail(dq.size() - 6).cwiseAbs().maxCoeff(),
                           (run.trajectory.object_poses[k].t - r.object_poses[k].t).norm());
            }
          }
        } catch (const Error& e) {
          ++t.errors;
          std::fprintf(stderr, "ref %d row %d: %s\n", i, row, e.what());
        }
      }
    }
    std::fprintf(stderr, "\rablation: %d/%d references (%.0f s)", i + 1, f.refs,
                 std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::printf("\n== Ablation (seed Table 3 in kind): %d synthetic references, %d frames at 30 fps,\n"
              "   %d samples x %d iterations, horizon %.2f s, ctrl_dt %.2f s, knot_dt %.2f s, %d threads, seed %llu\n",
              f.refs, f.frames, f.samples, f.iterations, f.horizon, f.ctrl_dt, f.knot_dt, f.threads,
              static_cast<unsigned long long>(f.seed));
  std::printf("%-22s | %-26s | %-26s\n", "", "noisy: succ  E_pos  E_rot", "clean: succ  E_pos  E_rot");
  for (int row = 0; row < 4; ++row) {
    std::printf("%-22s", rows[row]);
    for (int noisy = 1; noisy >= 0; --noisy) {
      const Tally& t = tally[{row, noisy}];
      const int n = std::max(1, t.n);
      std::printf(" |       %.2f  %.3f  %.3f%s", double(t.success) / std::max(1, t.n + t.errors),
                  t.e_pos / n, t.e_rot / n, t.errors ? "*" : " ");
    }
    std::printf("\n");
  }
  std::printf("(* some runs ended in an error, counted as failures; E means over the rest)\n");
}

// Raw mj_step throughput of `m` on `threads` threads (one mjData each).
// Without `run`: from qpos0 with the controls at zero. With it: the run's
// own simulated trajectory replayed from its first frame, its controls
// applied frame by frame, restarting at the end, so the raw loop carries
// the contact load the optimiser's rollouts carry (a hand grasping an
// object steps slower than one in free space).
double RawStepsPerSecond(const mjModel* m, int threads, double seconds,
                         const DynamicRetargetRun* run = nullptr) {
  RolloutPool pool(m, threads);
  std::vector<long long> steps(threads, 0);
  const auto start = [&](mjData* d) {
    if (run) {
      PoseHandAndObject(m, d, run->trajectory, 0, run->trajectory.object_poses[0]);
    } else {
      mj_resetData(m, d);
    }
  };
  const int steps_per_frame = run ? std::max(1, static_cast<int>(std::lround(1.0 / (run->trajectory.fps * m->opt.timestep)))) : 1;
  const auto t0 = Clock::now();
  pool.Run(threads, [&](int i, int thread) {
    mjData* d = pool.data(thread);
    start(d);
    long long k = 0;
    while (std::chrono::duration<double>(Clock::now() - t0).count() < seconds) {
      for (int n = 0; n < 100; ++n, ++k) {
        if (run) {
          const size_t frame = static_cast<size_t>(k / steps_per_frame);
          if (frame >= run->trajectory.ctrl.size()) {
            start(d);
            k = 0;
          }
          const Eigen::VectorXd& u = run->trajectory.ctrl[std::min(frame, run->trajectory.ctrl.size() - 1)];
          for (int a = 0; a < m->nu; ++a) d->ctrl[a] = u[a];
        }
        mj_step(m, d);
      }
      steps[i] += 100;
    }
  });
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  long long total = 0;
  for (long long s : steps) total += s;
  return total / dt;
}

void Throughput(const Flags& f) {
  const Case c = MakeCase(f, 0, f.frames);
  std::printf("\n== Simulation throughput: sim steps/s inside the optimiser vs raw mj_step, same scene\n");
  std::printf("%-8s | %-14s | %-22s | %-22s\n", "threads", "optimiser", "raw: replayed / ratio",
              "raw: at rest / ratio");
  for (int threads = 1; threads <= f.threads; ++threads) {
    DynamicRetargetConfig config = BaseConfig(f);
    config.sampler.threads = threads;
    const DynamicRetargetRun run = RunOne(c.noisy, c.mesh, config, "throughput");
    const double inside = run.stats.sim_steps / run.stats.rollout_seconds;
    // The same scene: compile the robot scene the run used.
    const auto dir = std::filesystem::temp_directory_path() / "doasido-dynamics-bench";
    const ModelPtr m = CompileMjcfText(run.robot_scene_xml, (dir / "robot_scene.xml").string());
    const double replayed = RawStepsPerSecond(m.get(), threads, 3.0, &run);
    const double rest = RawStepsPerSecond(m.get(), threads, 3.0);
    std::printf("%-8d | %14.0f | %14.0f / %.2f | %14.0f / %.2f\n", threads, inside, replayed,
                inside / replayed, rest, inside / rest);
    // The scene's constraint Jacobian: MuJoCo picks dense below 60 dofs.
    for (const int jacobian : {mjJAC_DENSE, mjJAC_SPARSE}) {
      m->opt.jacobian = jacobian;
      std::printf("         raw replay, %s Jacobian: %.0f steps/s\n", jacobian == mjJAC_DENSE ? "dense" : "sparse",
                  RawStepsPerSecond(m.get(), threads, 3.0, &run));
    }
    m->opt.jacobian = mjJAC_AUTO;
  }
}

// One clip of the wall-time section: wall seconds, the run.
// With `progress`, prints the wall time at the end of every plan to stderr.
std::pair<double, DynamicRetargetRun> TimedRun(const recon::Reconstruction& r, const TriMesh& mesh,
                                               const DynamicRetargetConfig& config, const std::string& label,
                                               bool progress = false) {
  const auto t0 = Clock::now();
  auto report = [&](int done, int total) {
    std::fprintf(stderr, "  %s: step %d of %d, %.0f s\n", label.c_str(), done, total,
                 std::chrono::duration<double>(Clock::now() - t0).count());
  };
  DynamicRetargetRun run = RunOne(r, mesh, config, label, progress ? report : std::function<void(int, int)>());
  return {std::chrono::duration<double>(Clock::now() - t0).count(), std::move(run)};
}

// For --verbose: the object's height in the reference and in the run, every half second.
void PrintHeights(const recon::Reconstruction& r, const DynamicRetargetRun& run) {
  for (int k = 0; k < r.frames(); k += 15) {
    std::fprintf(stderr, "  t %4.1f s: object z ref %.3f sim %.3f, error %.3f m\n", k / 30.0,
                 r.object_poses[k].t.z(), run.trajectory.object_poses[k].t.z(),
                 (run.trajectory.object_poses[k].t - r.object_poses[k].t).norm());
  }
}

void PrintWallRun(const char* preset, int clip, bool noisy, double seconds, const DynamicRetargetRun& run) {
  std::printf("%s preset, clip %d (%s): %.1f s wall, %d plans, %d iterations, %lld sim steps (%.0f/s), "
              "success %d (E_pos %.3f, E_rot %.3f), in-hand frames %d\n",
              preset, clip, noisy ? "noisy" : "clean", seconds, run.stats.plans, run.stats.iterations,
              run.stats.sim_steps, run.stats.sim_steps / run.stats.rollout_seconds, run.metrics.success,
              run.metrics.e_pos, run.metrics.e_rot, run.in_hand_frames);
}

// Clips --wall_first ... + --wall_clips with the --wall_preset (clean and
// noisy); the first --seed_wall of them (noisy) with the seed preset too.
void Wall(const Flags& f) {
  const int frames = static_cast<int>(f.clip_seconds * 30);
  std::printf("\n== Wall time for %d %.0f-s clips from clip %d (%d frames; pick-and-place, lift-and-rotate, "
              "slide in turn), %d threads\n", f.wall_clips, f.clip_seconds, f.wall_first, frames, f.threads);
  DynamicRetargetConfig fast = BaseConfig(f);
  fast.preset = f.wall_preset;
  fast.sampler.threads = f.threads;
  DynamicRetargetConfig seed = fast;
  seed.preset = "seed";
  const char* name = f.wall_preset.empty() ? "flags" : f.wall_preset.c_str();
  Tally tally[2], seed_tally, fast_on_seed_clips;
  double wall[2] = {0, 0}, seed_wall = 0, steps_per_s = 0;
  for (int n = 0; n < f.wall_clips; ++n) {
    const int i = f.wall_first + n;
    const Case c = MakeCase(f, i, frames);
    for (int noisy = 0; noisy < 2; ++noisy) {
      const auto& r = noisy ? c.noisy : c.clean;
      const auto [seconds, run] = TimedRun(r, c.mesh, fast, "wall");
      tally[noisy].Add(run.metrics);
      if (noisy && n < f.seed_wall) fast_on_seed_clips.Add(run.metrics);
      wall[noisy] += seconds;
      steps_per_s = run.stats.sim_steps / run.stats.rollout_seconds;
      PrintWallRun(name, i, noisy, seconds, run);
      if (f.verbose) PrintHeights(r, run);
    }
    if (n >= f.seed_wall) continue;
    const auto [seconds, run] = TimedRun(c.noisy, c.mesh, seed, "wall_seed", true);
    seed_tally.Add(run.metrics);
    seed_wall += seconds;
    PrintWallRun("seed", i, true, seconds, run);
    if (f.verbose) PrintHeights(c.noisy, run);
  }
  for (int noisy = 0; noisy < 2; ++noisy) {
    std::printf("%s preset, %s: %.1f s wall per clip, success %d of %d\n", name, noisy ? "noisy" : "clean",
                wall[noisy] / std::max(1, f.wall_clips), tally[noisy].success, tally[noisy].n);
  }
  if (f.seed_wall > 0) {
    std::printf("seed preset, noisy, the first %d clips: %.1f s wall per clip, success %d of %d "
                "(%s preset on the same clips: success %d of %d)\n", seed_tally.n,
                seed_wall / std::max(1, seed_tally.n), seed_tally.success, seed_tally.n, name,
                fast_on_seed_clips.success, fast_on_seed_clips.n);
    return;
  }
  const AnnealedSamplerConfig s = SamplerPreset("seed");
  const double steps = std::ceil((f.clip_seconds + s.horizon) / s.ctrl_dt) * s.max_num_iterations *
                       s.num_samples * (s.horizon / 0.005);
  std::printf("seed preset, bound without early stops: %.3g sim steps / %.0f per s = %.0f s (%.1f h) per clip "
              "(--seed_wall=N runs it)\n", steps, steps_per_s, steps / steps_per_s, steps / steps_per_s / 3600);
}

// For --verbose: where the human fingertips and the robot's contacts sit
// around the object at frame k (angle about the object's vertical axis from
// its centre, height; robot contacts with their normal's angle).
void DescribeGrasp(const mjModel* m, mjData* d, const HandTrajectory& traj,
                   const recon::Reconstruction& r, const TriMesh& mesh, int k) {
  const Pose& o = r.object_poses[k];
  const Vec3 centre = o * Vec3(0.5 * (mesh.Min() + mesh.Max()));
  auto angle = [&](const Vec3& p) {
    const Vec3 l = o.q.inverse() * (p - centre);
    return std::make_pair(std::atan2(l.y(), l.x()) * 180 / 3.14159265, l.z());
  };
  const Vec3 palm = (Vec3(r.right_joints[k].row(0).transpose()) + Vec3(r.right_joints[k].row(9).transpose())) * 0.5;
  std::fprintf(stderr, "  human: palm %.0f deg z %.3f;", angle(palm).first, angle(palm).second);
  for (int tip : kFingertips) {
    const Vec3 p = r.right_joints[k].row(tip).transpose();
    const double dist = synth::DistanceToMesh(mesh.Transformed(o), p);
    std::fprintf(stderr, " tip%d %.0f deg z %.3f d %.3f;", tip, angle(p).first, angle(p).second, dist);
  }
  const SceneIndex index = IndexScene(m);
  PoseHandAndObject(m, d, traj, k, o);
  mj_forward(m, d);
  std::fprintf(stderr, "\n  robot:");
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& con = d->contact[c];
    const int hand_geom = HandGeomTouchingObject(m, d, index, c);
    if (hand_geom < 0) continue;
    const Vec3 p(con.pos[0], con.pos[1], con.pos[2]);
    std::fprintf(stderr, " %s(%.0f deg z %.3f d %.4f)", mj_id2name(m, mjOBJ_BODY, m->geom_bodyid[hand_geom]),
                 angle(p).first, angle(p).second, con.dist);
  }
  std::fprintf(stderr, "\n");
}

// The kinematic reference's grasps with and without the grasp terms
// (KinematicConfig contact_weight) on the lifting references (pick-and-place
// and lift-and-rotate): hand-object contacts per in-hand frame, the deepest
// penetration, and whether the grasp at the highest reference frame holds
// the object for 1 s (falls less than 2 cm).
void Grasp(const Flags& f) {
  const double weight = f.contact_weight > 0 ? f.contact_weight : 16;
  std::printf("\n== Kinematic reference grasps on the lifting references (of %d), grasp terms off / "
              "on (contact_weight %g)\n", f.refs, weight);
  std::printf("%-10s | %-11s | %-13s | %-17s | %s\n", "terms", "references", "contacts/frame",
              "deepest penetr.", "grasp holds 1 s");
  for (const double w : {0.0, weight}) {
    int refs = 0, holds = 0, frames = 0, contacts = 0;
    double deepest = 0;
    for (int i = 0; i < f.refs; ++i) {
      if (i % 3 == 2) continue;  // slides never leave the floor
      const Case c = MakeCase(f, i, f.frames);
      DynamicRetargetConfig config = BaseConfig(f);
      config.sampler.num_samples = 1;
      config.sampler.max_num_iterations = 1;
      config.kinematic.contact_weight = w;
      const DynamicRetargetRun run = RunOne(c.clean, c.mesh, config, "grasp");
      const ModelPtr m = CompileMjcfText(run.robot_scene_xml, (std::filesystem::temp_directory_path() / "doasido-dynamics-bench/robot_scene.xml").string());
      const DataPtr d = MakeData(m.get());
      const std::vector<bool> in_hand = LabelInHand(c.clean, c.clean.object_poses, c.mesh,
                                                    config.sampler.reward.transition_epsilon);
      int top = 0;
      for (int k = 0; k < c.clean.frames(); ++k) {
        if (c.clean.object_poses[k].t.z() > c.clean.object_poses[top].t.z()) top = k;
        if (!in_hand[k]) continue;
        const auto [n, depth] = Contacts(m.get(), d.get(), run.kinematic, k, c.clean.object_poses[k]);
        ++frames;
        contacts += n;
        deepest = std::min(deepest, depth);
      }
      if (f.verbose) DescribeGrasp(m.get(), d.get(), run.kinematic, c.clean, c.mesh, top);
      const double drop = ReferenceHoldDrop(m.get(), d.get(), run.kinematic, top, c.clean.object_poses[top], 1.0);
      ++refs;
      holds += drop < 0.02;
      if (f.verbose) std::fprintf(stderr, "ref %d terms %g: frame %d, object fell %.3f m\n", i, w, top, drop);
    }
    std::printf("%-10s | %11d | %13.2f | %14.1f mm | %d/%d\n", w > 0 ? "on" : "off", refs,
                double(contacts) / std::max(1, frames), -1000 * deepest, holds, refs);
  }
}

void Bimanual(const Flags& f) {
  const auto& rows = kAblationRows;
  const synth::TwoHandTask tasks[] = {synth::TwoHandTask::kHandover, synth::TwoHandTask::kCarry,
                                      synth::TwoHandTask::kHoldAndAct};
  struct Row { Tally tally; double wrists = 0; };
  std::map<std::pair<int, int>, Row> table;  // (row, noisy)
  const auto robots = kData / "robots";
  const Embodiment left = FindEmbodiment("sharpa_left", robots), right = FindEmbodiment("sharpa_right", robots);
  const auto dir = std::filesystem::temp_directory_path() / "doasido-dynamics-bench-bimanual";
  const auto t0 = Clock::now();
  for (int i = 0; i < f.refs; ++i) {
    synth::EpisodeSpec spec;
    spec.frames = f.frames;
    spec.two_hand_task = tasks[i % 3];
    spec.grasp = synth::GraspTypeFromName(f.grasp);
    spec.object_yaw = 0.4 * i;
    spec.approach_azimuth = -0.35 + 0.1 * ((i / 3) % 4);
    const TriMesh mesh = i % 2 ? synth::MakeBox(0.06, 0.06, 0.09) : synth::MakeCylinder(0.035, 0.10, 16);
    const recon::Reconstruction clean = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, mesh), 30.0);
    recon::Reconstruction noisy = clean;
    synth::AddReconstructionNoise(noisy, {}, 2000 + i);
    for (int row = 0; row < 4; ++row) {
      const DynamicRetargetConfig config = AblationRow(f, row);
      for (int n = 0; n < 2; ++n) {
        Row& r = table[{row, n}];
        try {
          const BimanualRun run = RetargetBimanual(n ? noisy : clean, mesh, left, right, config, dir, "bimanual");
          r.tally.Add(run.metrics);
          r.wrists += 0.5 * (run.left_wrist_error + run.right_wrist_error);
        } catch (const Error& e) {
          ++r.tally.errors;
          std::fprintf(stderr, "bimanual ref %d row %d: %s\n", i, row, e.what());
        }
      }
    }
    std::fprintf(stderr, "\rbimanual: %d/%d references (%.0f s)", i + 1, f.refs,
                 std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::printf("\n== Two hands: %d synthetic references (handover, carry, hold-and-act in turn), %d frames,\n"
              "   both Sharpa hands and the object in one scene, %d samples x %d iterations, seed %llu\n",
              f.refs, f.frames, f.samples, f.iterations, static_cast<unsigned long long>(f.seed));
  std::printf("%-22s | %-36s | %-36s\n", "", "noisy: succ  E_pos  E_rot  wrists", "clean: succ  E_pos  E_rot  wrists");
  for (int row = 0; row < 4; ++row) {
    std::printf("%-22s", rows[row]);
    for (int n = 1; n >= 0; --n) {
      const Row& r = table[{row, n}];
      const int k = std::max(1, r.tally.n);
      std::printf(" |       %.2f  %.3f  %.3f  %5.1f mm%s", double(r.tally.success) / std::max(1, r.tally.n + r.tally.errors),
                  r.tally.e_pos / k, r.tally.e_rot / k, 1000 * r.wrists / k, r.tally.errors ? "*" : " ");
    }
    std::printf("\n");
  }
  // The HOT3D sample's two hands, the pot (a 5-cm sphere stands in) as the object.
  const auto sample = kData / "hot3d_sample";
  const auto recording = sample / "Aria" / "P0003_c701bd11";
  if (!std::filesystem::exists(recording)) return;
  recon::Hot3dReferenceOptions o;
  o.hand = "left";
  o.both_hands = true;
  o.object_uid = "228358276546933";
  o.stand_in = synth::MakeSphere(0.05);
  const recon::Hot3dReference ref = recon::Hot3dToReconstruction(recon::ReadHot3dRecording(recording),
                                                                 sample / "object_library", o);
  for (int row : {0, 3}) {
    const DynamicRetargetConfig config = AblationRow(f, row);
    const auto t1 = Clock::now();
    const BimanualRun run = RetargetBimanual(ref.reconstruction, ref.mesh, left, right, config, dir, "hot3d");
    std::printf("HOT3D two hands, %-20s: succ %d, E_pos %.3f, E_rot %.3f, wrists %.1f / %.1f mm, in-hand %d / %d "
                "of %d frames, %.1f s\n", rows[row], run.metrics.success, run.metrics.e_pos, run.metrics.e_rot,
                1000 * run.left_wrist_error, 1000 * run.right_wrist_error, run.left_in_hand_frames,
                run.right_in_hand_frames, ref.reconstruction.frames(),
                std::chrono::duration<double>(Clock::now() - t1).count());
  }
}

double CpuSeconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  for (char ch : text + ",") {
    if (ch != ',') item += ch;
    else if (!item.empty()) out.push_back(item), item.clear();
  }
  return out;
}

void Ladder(const Flags& f) {
  const int frames = static_cast<int>(f.clip_seconds * 30);
  const std::vector<std::string> presets = SplitList(f.ladder_presets);
  const std::vector<std::string> alone_presets = SplitList(f.ladder_alone.empty() ? f.ladder_presets : f.ladder_alone);
  const auto runs_alone = [&](const std::string& p) {
    return std::find(alone_presets.begin(), alone_presets.end(), p) != alone_presets.end();
  };
  std::printf("\n== Ladder %s on %d %.0f-s clips from clip %d (%s), %d threads\n", f.ladder_presets.c_str(),
              f.ladder_clips, f.clip_seconds, f.ladder_first, f.ladder_clean_only ? "clean" : f.ladder_clean ? "noisy and clean" : "noisy",
              f.threads);
  struct Sum { int n = 0, success = 0; double wall = 0, cpu = 0; };
  std::map<std::string, Sum> alone;
  Sum ladder;
  std::map<std::string, int> shares;
  for (int n = 0; n < f.ladder_clips; ++n) {
    const int i = f.ladder_first + n;
    const Case c = MakeCase(f, i, frames);
    for (int noisy = f.ladder_clean_only ? 0 : 1; noisy >= (f.ladder_clean ? 0 : 1); --noisy) {
      bool done = false;
      for (const std::string& preset : presets) {
        if (done && !runs_alone(preset)) continue;
        DynamicRetargetConfig config = BaseConfig(f);
        config.preset = preset;
        const double cpu0 = CpuSeconds();
        const auto [seconds, run] = TimedRun(noisy ? c.noisy : c.clean, c.mesh, config, "ladder");
        const double cpu = CpuSeconds() - cpu0;
        Sum& a = alone[preset];
        ++a.n, a.success += run.metrics.success, a.wall += seconds, a.cpu += cpu;
        if (!done) {
          ladder.wall += seconds, ladder.cpu += cpu;
          if (run.metrics.success || &preset == &presets.back()) {
            done = true;
            ++ladder.n, ladder.success += run.metrics.success;
            ++shares[run.metrics.success ? preset : "none"];
          }
        }
        std::printf("clip %d (%s) %-7s: success %d, E_pos %.3f, E_rot %.3f, %.1f s wall, %.1f s CPU, "
                    "%d iterations in %d plans, %lld sim steps\n", i, noisy ? "noisy" : "clean", preset.c_str(),
                    run.metrics.success, run.metrics.e_pos, run.metrics.e_rot, seconds, cpu,
                    run.stats.iterations, run.stats.plans, run.stats.sim_steps);
        std::fflush(stdout);
      }
    }
  }
  for (const std::string& preset : presets) {
    const Sum& a = alone[preset];
    std::printf("%-7s alone : success %d of %d, %.1f s wall, %.1f s CPU per clip\n", preset.c_str(), a.success,
                a.n, a.wall / std::max(1, a.n), a.cpu / std::max(1, a.n));
  }
  std::printf("ladder        : success %d of %d, %.1f s wall, %.1f s CPU per clip; kept rung:", ladder.success,
              ladder.n, ladder.wall / std::max(1, ladder.n), ladder.cpu / std::max(1, ladder.n));
  for (const auto& [rung, count] : shares) std::printf(" %s %d,", rung.c_str(), count);
  std::printf("\n");
}

// The default configuration, as a new user runs the `retarget` stage.
void Default(const Flags& f) {
  const int frames = static_cast<int>(f.clip_seconds * 30);
  const Case c = MakeCase(f, f.ladder_first, frames);
  DynamicRetargetConfig config;
  config.robots_dir = (kData / "robots").string();
  if (f.default_contact_weight >= 0) config.kinematic.contact_weight = f.default_contact_weight;
  std::printf("\n== Default configuration (ladder");
  for (const std::string& rung : config.ladder) std::printf(" %s", rung.c_str());
  std::printf(") on clip %d, %.0f s (clean), %d threads, contact_weight %g\n", f.ladder_first, f.clip_seconds,
              config.sampler.threads, config.kinematic.contact_weight);
  const double cpu0 = CpuSeconds();
  const auto t0 = Clock::now();
  // As the `retarget` stage does: scene, model and kinematic reference once.
  std::optional<ClipRetarget> clip;
  double prepare_seconds = 0;
  const std::function<DynamicRetargetRun(const std::string&)> track = [&](const std::string& rung) {
    if (!clip) {
      const auto p0 = Clock::now();
      clip.emplace(c.clean, c.mesh, FindEmbodiment(config.hand, config.robots_dir), config,
                   std::filesystem::temp_directory_path() / "doasido-dynamics-bench", "default");
      prepare_seconds = std::chrono::duration<double>(Clock::now() - p0).count();
    }
    const double rung_cpu0 = CpuSeconds();
    const auto r0 = Clock::now();
    DynamicRetargetRun run = clip->Track(RungSampler(config, rung));
    std::printf("rung %-7s: success %d, E_pos %.3f, E_rot %.3f, %.1f s wall, %.1f s CPU, %d iterations in %d "
                "plans\n", rung.c_str(), run.metrics.success, run.metrics.e_pos, run.metrics.e_rot,
                std::chrono::duration<double>(Clock::now() - r0).count(), CpuSeconds() - rung_cpu0,
                run.stats.iterations, run.stats.plans);
    std::fflush(stdout);
    return run;
  };
  const LadderResult<DynamicRetargetRun> result = RunLadder(LadderRungs(config), track);
  std::printf("scene, model and kinematic reference (once): %.1f s wall\n", prepare_seconds);
  std::printf("default: success %d at rung %s, %.1f s wall, %.1f s CPU\n", result.best.metrics.success,
              result.rungs[result.best_rung].name.c_str(),
              std::chrono::duration<double>(Clock::now() - t0).count(), CpuSeconds() - cpu0);
}

constexpr const char* kCoffeePot = "228358276546933";

void Hot3d(const Flags& f) {
  const auto sample = kData / "hot3d_sample";
  const auto recording = sample / "Aria" / "P0003_c701bd11";
  if (!std::filesystem::exists(recording)) {
    std::printf("\n== HOT3D: %s not found, skipped\n", recording.c_str());
    return;
  }
  const recon::Hot3dRecording rec = recon::ReadHot3dRecording(recording);
  struct Row { const char* hand; bool mirror; const char* robot; const char* object; };
  // The coffee pot is the one object a hand moves in the sample, but the
  // sample has no model of it: a 5-cm sphere at its origin stands in.
  const Row rows[] = {{"left", false, "sharpa_left", ""}, {"left", true, "sharpa_right", ""},
                      {"right", false, "sharpa_right", ""}, {"left", false, "sharpa_left", kCoffeePot},
                      {"left", true, "sharpa_right", kCoffeePot}};
  std::printf("\n== Real references: HOT3D %s, %d threads\n", recording.filename().c_str(), f.threads);
  std::printf("%-14s | %-16s | %-12s | %-6s | %5s %6s %6s | %9s | %8s | %s\n", "human hand",
              "object (dist)", "robot", "preset", "succ", "E_pos", "E_rot", "kin. tip", "in-hand", "wall | object kept still: E_pos E_rot");
  for (const Row& row : rows) {
    recon::Hot3dReferenceOptions o;
    o.hand = row.hand;
    o.mirror = row.mirror;
    o.object_uid = row.object;
    if (*row.object) o.stand_in = synth::MakeSphere(0.05);
    const recon::Hot3dReference ref = recon::Hot3dToReconstruction(rec, sample / "object_library", o);
    for (const char* preset : {"fast", "seed"}) {
      if (std::string(preset) == "seed" && !f.seed_wall) continue;
      DynamicRetargetConfig c = BaseConfig(f);
      c.preset = preset;
      c.hand = row.robot;
      c.sampler.threads = f.threads;
      const auto t0 = Clock::now();
      try {
        const DynamicRetargetRun run = RunOne(ref.reconstruction, ref.mesh, c, "hot3d");
        double tip = 0;
        for (double e : run.kinematic.fingertip_error) tip += e;
        tip /= std::max<size_t>(1, run.kinematic.fingertip_error.size());
        const auto& poses = ref.reconstruction.object_poses;
        const TrackingMetrics still =
            ObjectTrackingMetrics(std::vector<Pose>(poses.size(), poses[0]), poses);
        std::printf("%-14s | %-9.9s %4.1fcm | %-12s | %-6s | %5d %6.3f %6.3f | %6.1f mm | %3d/%-4d | %4.1f s | %.3f %.3f\n",
                    (std::string(row.hand) + (row.mirror ? " mirrored" : "")).c_str(),
                    (ref.stand_in ? "sphere" : ref.object_uid.c_str()), 100 * ref.mean_fingertip_distance, row.robot, preset,
                    run.metrics.success, run.metrics.e_pos, run.metrics.e_rot, 1000 * tip,
                    run.in_hand_frames, ref.reconstruction.frames(),
                    std::chrono::duration<double>(Clock::now() - t0).count(), still.e_pos, still.e_rot);
      } catch (const Error& e) {
        std::printf("%-14s | %-12s | %s\n", row.hand, row.robot, e.what());
      }
    }
  }
  std::printf("(object: the one with a model in the sample whose surface the hand's fingertips come\n"
              " closest to, mean distance in brackets; sphere: a 5-cm sphere standing in for the coffee pot\n"
              " (228358276546933), which the left hand moves but the sample has no model of; kin. tip: mean kinematic fingertip error;\n"
              " in-hand: frames labelled in-hand / all frames; kept still: the metrics of an object\n"
              " that never moves from its frame-0 pose, the floor an optimiser must beat)\n");
}

}  // namespace

int main(int argc, char** argv) {
  const Flags f = Parse(argc, argv);
  if (f.sections.find("ablation") != std::string::npos) Ablation(f);
  if (f.sections.find("throughput") != std::string::npos) Throughput(f);
  if (f.sections.find("wall") != std::string::npos) Wall(f);
  if (f.sections.find("hot3d") != std::string::npos) Hot3d(f);
  if (f.sections.find("grasp") != std::string::npos) Grasp(f);
  if (f.sections.find("bimanual") != std::string::npos) Bimanual(f);
  if (f.sections.find("ladder") != std::string::npos) Ladder(f);
  if (f.sections.find("default") != std::string::npos) Default(f);
  return 0;
}
