#include "retarget/dynamic/dynamic_retarget.h"

#include "core/config_check.h"
#include "core/error.h"
#include "core/file_text.h"
#include "retarget/config_checks.h"

namespace doasido::retarget {

Error NamingClip(const Error& e, const std::string& label) {
  ErrorSite site = e.site();
  if (site.clip.empty()) site.clip = label;
  return Error(e.code(), e.message(), site);
}

HandTrajectory SimulatedTrajectory(const mjModel* m, const SceneIndex& index, const DynamicReference& ref,
                                   const DynamicResult& result, const HandTrajectory& kinematic) {
  HandTrajectory out;
  out.embodiment = kinematic.embodiment;
  out.fps = kinematic.fps;
  out.scale = kinematic.scale;
  out.qpos_names = kinematic.qpos_names;
  out.valid = kinematic.valid;
  out.fingertip_error = kinematic.fingertip_error;
  out.reference_keypoints = kinematic.reference_keypoints;
  std::vector<int> adr;
  for (const std::string& n : kinematic.qpos_names) {
    adr.push_back(m->jnt_qposadr[NameToId(m, mjOBJ_JOINT, n)]);
  }
  for (int a = 0; a < m->nu; ++a) {
    const char* n = mj_id2name(m, mjOBJ_ACTUATOR, a);
    out.ctrl_names.push_back(n ? n : "actuator_" + std::to_string(a));
  }
  for (int f = 0; f < ref.frames; ++f) {
    const int s = ref.StepOfFrame(f);
    Eigen::VectorXd q(adr.size());
    for (size_t i = 0; i < adr.size(); ++i) q[i] = result.qpos(s, adr[i]);
    out.qpos.push_back(q);
    out.ctrl.push_back(result.ctrl.row(s).transpose());
    const double* o = result.qpos.row(s).data() + index.object_qpos;
    out.object_poses.push_back({Quat(o[3], o[4], o[5], o[6]).normalized(), Vec3(o[0], o[1], o[2])});
  }
  return out;
}

void CheckConfig(const DynamicRetargetConfig& c, const std::string& section) {
  if (c.preset == kLadderPreset && c.ladder.empty()) {
    throw Error("bad_config", "an empty ladder (name one rung or more)", {.field = section + ".ladder"});
  }
  for (const std::string& rung : LadderRungs(c)) {
    if (rung == kSamplerRung) continue;
    try {
      SamplerPreset(rung);
    } catch (const Error& e) {
      throw Error("bad_config", e.message() + " or \"" + kSamplerRung + "\"",
                  {.field = section + (c.preset == kLadderPreset ? ".ladder" : ".preset")});
    }
  }
  CheckHandName(c.hand, c.robots_dir, section, "hand");
  CheckHandName(c.left_hand, c.robots_dir, section, "left_hand");
  CheckConfig(c.sampler, section + ".sampler");
  CheckConfig(c.kinematic, section + ".kinematic");
  CheckConfig(c.scene, section + ".scene");
}

std::vector<std::string> LadderRungs(const DynamicRetargetConfig& config) {
  if (config.preset == kLadderPreset) return config.ladder;
  return {config.preset.empty() ? std::string(kSamplerRung) : config.preset};
}

AnnealedSamplerConfig RungSampler(const DynamicRetargetConfig& config, const std::string& rung) {
  if (rung == kSamplerRung) return config.sampler;
  AnnealedSamplerConfig s = SamplerPreset(rung);
  s.threads = config.sampler.threads;
  s.seed = config.sampler.seed;
  return s;
}

DynamicRetargetConfig AtRung(const DynamicRetargetConfig& config, const std::string& rung) {
  DynamicRetargetConfig c = config;
  c.preset = rung == kSamplerRung ? "" : rung;
  return c;
}

AnnealedSamplerConfig EffectiveSampler(const DynamicRetargetConfig& config) {
  return RungSampler(config, LadderRungs(config).front());
}

TrackingMetrics ObjectMetrics(const ClipObject& clip, const HandTrajectory& simulated) {
  std::vector<bool> valid(clip.r.frames());
  for (int t = 0; t < clip.r.frames(); ++t) valid[t] = clip.r.object_valid[t];
  return ObjectTrackingMetrics(simulated.object_poses, clip.object, valid);
}

ClipRetarget::ClipRetarget(const recon::Reconstruction& r, const TriMesh& mesh, const Embodiment& hand,
                           const DynamicRetargetConfig& config, const std::filesystem::path& scene_dir,
                           const std::string& label)
    : clip_{r, mesh, label, {}} {
  try {
    CheckReference(r, label);
    clip_.object = FilledObjectPoses(r);
    SceneConfig scene_config = config.scene;
    scene_config.place_on_floor = false;  // the reconstruction's floor is z = 0 already
    const ObjectScene scene = BuildObjectScene(mesh, clip_.object[0], scene_config, scene_dir);
    model_ = BuildHandModel(hand, TryReadFile(scene.xml_path).value_or(""), scene_dir);
    KinematicRetargeter kinematic(model_, config.kinematic);
    kinematic_ = kinematic.Solve(r.right_joints, r.right_valid, r.fps, {}, &clip_.object, &grasp_contacts_);
    kinematic_.object_poses = clip_.object;
  } catch (const Error& e) {
    throw NamingClip(e, label);
  }
}

DynamicRetargetRun ClipRetarget::Track(const AnnealedSamplerConfig& sampler,
                                       const std::function<void(int, int)>& progress,
                                       const WindowTraceFn& trace) const {
  DynamicRetargetRun run;
  run.robot_scene_xml = model_.xml;
  run.kinematic = kinematic_;
  run.grasp_contacts = grasp_contacts_;
  const mjModel* m = model_.model.get();
  try {
    const RewardConfig& reward = sampler.reward;
    const std::vector<bool> in_hand = LabelInHand(clip_.r, clip_.object, clip_.mesh, reward.transition_epsilon);
    const std::vector<bool> resting = LabelResting(clip_.object, clip_.mesh, reward.transition_rest_height);
    for (size_t t = 0; t < in_hand.size(); ++t) run.in_hand_frames += in_hand[t] && !resting[t];

    const SceneIndex index = IndexScene(m);
    const DynamicReference ref =
        BuildReference(m, run.kinematic, clip_.object, std::vector<uint8_t>(in_hand.begin(), in_hand.end()),
                       resting, WarmupSeconds(sampler));
    const DynamicResult result = RetargetDynamics(m, ref, sampler, progress, trace);
    run.stats = result.stats;
    run.trajectory = SimulatedTrajectory(m, index, ref, result, run.kinematic);
    run.metrics = ObjectMetrics(clip_, run.trajectory);
  } catch (const Error& e) {
    throw NamingClip(e, clip_.label);
  }
  run.trajectory.metrics = {{kMetricPositionError, run.metrics.e_pos},
                            {kMetricRotationError, run.metrics.e_rot},
                            {kMetricSuccess, run.metrics.success},
                            {"frames", run.metrics.frames}};
  return run;
}

DynamicRetargetRun RetargetReconstruction(const recon::Reconstruction& r, const TriMesh& mesh,
                                          const Embodiment& hand,
                                          const DynamicRetargetConfig& config,
                                          const std::filesystem::path& scene_dir,
                                          const std::string& label,
                                          const std::function<void(int, int)>& progress) {
  return ClipRetarget(r, mesh, hand, config, scene_dir, label).Track(EffectiveSampler(config), progress);
}

}  // namespace doasido::retarget
