#include "synth/generator.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "synth/render.h"
#include "synth/texture.h"

namespace doasido::synth {
namespace fs = std::filesystem;
namespace {

constexpr int kFadeFrames = 10;
constexpr int kFadeInFrames = 8;

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

struct ObjectChoice {
  std::string name;
  TriMesh mesh;
};

ObjectChoice ChooseObject(const SynthConfig& cfg, std::mt19937_64& rng) {
  std::vector<fs::path> files;
  if (!cfg.mesh_dir.empty()) {
    if (!fs::is_directory(cfg.mesh_dir)) {
      throw Error("bad_config", "mesh folder not found",
                  {.file = cfg.mesh_dir, .field = "mesh_dir"});
    }
    for (const auto& e : fs::directory_iterator(cfg.mesh_dir)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".obj" || ext == ".ply" || ext == ".glb" || ext == ".stl")
        files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
  }
  const int n_kinds = 4 + (files.empty() ? 0 : 1);
  const int k = std::uniform_int_distribution<int>(0, n_kinds - 1)(rng);
  switch (k) {
    case 0:
      return {"box", MakeBox(Uniform(rng, 0.05, 0.08), Uniform(rng, 0.05, 0.08),
                             Uniform(rng, 0.08, 0.15))};
    case 1:
      return {"cylinder", MakeCylinder(Uniform(rng, 0.03, 0.045), Uniform(rng, 0.08, 0.16))};
    case 2:
      return {"sphere", MakeSphere(Uniform(rng, 0.035, 0.05))};
    case 3:
      return {"mug", MakeMug(Uniform(rng, 0.035, 0.045), Uniform(rng, 0.08, 0.11))};
    default: {
      const fs::path& f = files[std::uniform_int_distribution<size_t>(0, files.size() - 1)(rng)];
      return {f.stem().string(), LoadObjectMesh(f)};
    }
  }
}

struct ScenePlan {
  World world;
  Camera camera;
  Pose camera_from_world;
  Vec3 eye;
  EpisodeSpec spec;
  std::uint64_t style_seed = 0;
};

ScenePlan PlanScene(const SynthConfig& cfg, const ObjectChoice& object, DefectKind kind,
                    std::mt19937_64& rng) {
  ScenePlan p;
  p.style_seed = rng();
  p.world.style = RandomStyle(p.style_seed);
  p.world.light_dir = Vec3(Uniform(rng, -0.6, 0.6), Uniform(rng, -0.7, -0.2), 1.0).normalized();
  p.world.ambient = Uniform(rng, 0.3, 0.45);
  EpisodeSpec& s = p.spec;
  s.frames = cfg.frames;
  s.verb = static_cast<Verb>(std::uniform_int_distribution<int>(0, 3)(rng));
  s.active = Uniform(rng, 0, 1) < 0.7 ? Side::kRight : Side::kLeft;
  s.two_hands = Uniform(rng, 0, 1) < cfg.two_hand_fraction;
  s.two_hand_task = TwoHandTaskFromName(cfg.two_hand_task);
  s.grasp = GraspTypeFromName(cfg.grasp);
  s.object_xy = Vec2(Uniform(rng, -0.03, 0.03), Uniform(rng, 0.0, 0.06));
  const double yaw_centre = object.name == "mug" ? (s.active == Side::kRight ? M_PI : 0.0) : 0.0;
  s.object_yaw = yaw_centre + Uniform(rng, -0.8, 0.8);
  s.approach_azimuth = Uniform(rng, -0.5, -0.15);
  s.approach_elevation = Uniform(rng, 0.45, 0.75);
  s.manipulation_scale = Uniform(rng, 0.8, 1.2);
  s.touch = kind != DefectKind::kNoContact;
  s.static_scene = kind == DefectKind::kStatic;
  s.leave = kind == DefectKind::kHandOut     ? LeaveFrame::kHand
            : kind == DefectKind::kObjectOut ? LeaveFrame::kObject
                                             : LeaveFrame::kNone;
  const double f = cfg.width * Uniform(rng, 0.82, 0.95);
  p.camera = {cfg.width, cfg.height, f, f, (cfg.width - 1) / 2.0, (cfg.height - 1) / 2.0};
  const Vec3 target(s.object_xy.x(), s.object_xy.y() + 0.02, 0.05);
  p.eye = target +
          Vec3(Uniform(rng, -0.08, 0.08), Uniform(rng, -0.47, -0.38), Uniform(rng, 0.28, 0.38));
  p.camera_from_world = LookAt(p.eye, target);
  return p;
}

// Fraction of mesh vertices (in the world) that project inside the image.
double InFrame(const TriMesh& world_mesh, const Camera& cam, const Pose& cw) {
  if (world_mesh.num_vertices() == 0) return 0;
  int inside = 0;
  for (int i = 0; i < world_mesh.num_vertices(); ++i) {
    const Vec3 p = cw * Vec3(world_mesh.vertices.row(i).transpose());
    if (p.z() <= 0.01) continue;
    const Vec2 uv = cam.Project(p);
    inside +=
        uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < cam.width - 0.5 && uv.y() < cam.height - 0.5;
  }
  return static_cast<double>(inside) / world_mesh.num_vertices();
}

// Area-weighted surface samples (object-local).
std::vector<Vec3> SampleSurface(const TriMesh& m, int n, std::mt19937_64& rng) {
  std::vector<double> cum(m.num_faces());
  double total = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)),
               c = m.vertices.row(m.faces(f, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cum[f] = total;
  }
  std::vector<Vec3> out;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const double r = u(rng) * total;
    const int f = static_cast<int>(std::lower_bound(cum.begin(), cum.end(), r) - cum.begin());
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)),
               c = m.vertices.row(m.faces(f, 2));
    double s = u(rng), t = u(rng);
    if (s + t > 1) s = 1 - s, t = 1 - t;
    out.push_back(a + s * (b - a) + t * (c - a));
  }
  return out;
}

Json PoseJson(const Pose& p) {
  return Json{{"q", {p.q.w(), p.q.x(), p.q.y(), p.q.z()}}, {"t", {p.t.x(), p.t.y(), p.t.z()}}};
}

// Longest run of frames with value <= threshold; {-1, -1} when none.
std::pair<int, int> LongestRun(const std::vector<double>& v, double threshold) {
  std::pair<int, int> best{-1, -1};
  int start = -1;
  for (int t = 0; t <= static_cast<int>(v.size()); ++t) {
    const bool in = t < static_cast<int>(v.size()) && v[t] <= threshold;
    if (in && start < 0) start = t;
    if (!in && start >= 0) {
      if (best.first < 0 || t - 1 - start > best.second - best.first) best = {start, t - 1};
      start = -1;
    }
  }
  return best;
}

struct SceneFrame {
  FrameState state;
  RenderedFrame render;
  const EpisodeFrame* episode = nullptr;
};

SceneFrame RenderScene(const ScenePlan& plan, const Episode& ep, const CameraTrack& track,
                       const TriMesh& mesh, int t, BackgroundCache& cache) {
  SceneFrame out;
  const EpisodeFrame& ef = ep.frames[t];
  out.episode = &ef;
  out.state.camera = track.camera[t];
  out.state.camera_from_world = track.camera_from_world[t];
  out.state.object_pose = ef.object_pose;
  for (int s = 0; s < 2; ++s) {
    if (!ef.hands[s]) continue;
    out.state.hands[s] = PoseHand(*ef.hands[s], static_cast<Side>(s));
    out.state.hand_wrist[s] = ef.hands[s]->wrist;
  }
  out.render = RenderFrame(plan.world, mesh, out.state, {}, &cache);
  return out;
}

Json SceneJson(const ScenePlan& p, const ObjectChoice& object) {
  return Json{{"verb", VerbName(p.spec.verb)},
              {"object", object.name},
              {"active_hand", p.spec.active == Side::kRight ? "right" : "left"},
              {"two_hands", p.spec.two_hands},
              {"touch", p.spec.touch},
              {"static", p.spec.static_scene},
              {"style_seed", p.style_seed},
              {"eye", {p.eye.x(), p.eye.y(), p.eye.z()}},
              {"focal", p.camera.fx}};
}

}  // namespace

std::map<DefectKind, double> ParseMix(const std::string& spec) {
  std::map<DefectKind, double> mix;
  std::stringstream ss(spec);
  std::string item;
  double total = 0;
  while (std::getline(ss, item, ',')) {
    if (item.find_first_not_of(" \t") == std::string::npos) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      throw Error("bad_config", "mix entry '" + item + "' is not name=weight", {.field = "mix"});
    }
    auto trim = [](std::string x) {
      const auto a = x.find_first_not_of(" \t"), b = x.find_last_not_of(" \t");
      return a == std::string::npos ? std::string() : x.substr(a, b - a + 1);
    };
    const DefectKind kind = DefectFromName(trim(item.substr(0, eq)));
    double w = 0;
    try {
      size_t used = 0;
      const std::string num = trim(item.substr(eq + 1));
      w = std::stod(num, &used);
      if (used != num.size()) throw std::invalid_argument(num);
    } catch (const std::exception&) {
      throw Error("bad_config", "mix weight in '" + item + "' is not a number", {.field = "mix"});
    }
    if (!(w >= 0) || !std::isfinite(w)) {
      throw Error("bad_config", "mix weight in '" + item + "' must be >= 0", {.field = "mix"});
    }
    mix[kind] += w;
    total += w;
  }
  if (total <= 0) throw Error("bad_config", "mix has no positive weight", {.field = "mix"});
  for (auto& [kind, w] : mix) w /= total;
  return mix;
}

std::vector<DefectKind> AssignDefects(const std::map<DefectKind, double>& mix, int clips,
                                      std::uint64_t seed) {
  std::vector<std::pair<DefectKind, double>> kinds;
  for (const auto& [k, w] : mix) {
    if (w > 0) kinds.emplace_back(k, w);
  }
  std::vector<int> count(kinds.size(), 0);
  int assigned = 0;
  // Every kind asked for appears once when there is room; the rest goes by
  // largest remainder of the remaining share.
  if (clips >= static_cast<int>(kinds.size())) {
    std::fill(count.begin(), count.end(), 1);
    assigned = static_cast<int>(kinds.size());
  }
  std::vector<double> want(kinds.size());
  for (size_t i = 0; i < kinds.size(); ++i) {
    want[i] = std::max(0.0, kinds[i].second * clips - count[i]);
  }
  double want_total = std::accumulate(want.begin(), want.end(), 0.0);
  const int left = clips - assigned;
  std::vector<double> rem(kinds.size(), 0.0);
  int given = 0;
  for (size_t i = 0; i < kinds.size() && want_total > 0; ++i) {
    const double share = want[i] / want_total * left;
    const int whole = static_cast<int>(std::floor(share));
    count[i] += whole;
    given += whole;
    rem[i] = share - whole;
  }
  std::vector<size_t> order(kinds.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rem[a] > rem[b]; });
  for (size_t k = 0; given < left && !order.empty(); k = (k + 1) % order.size(), ++given) {
    ++count[order[k]];
  }
  std::vector<DefectKind> out;
  for (size_t i = 0; i < kinds.size(); ++i) out.insert(out.end(), count[i], kinds[i].first);
  out.resize(clips, DefectKind::kClean);
  std::mt19937_64 rng(Hash(seed, 0x5eed));
  std::shuffle(out.begin(), out.end(), rng);
  return out;
}

namespace {

// The scenes of one clip: one, or two across a cut or cross-fade.
struct ClipScenes {
  ObjectChoice object;
  std::vector<ScenePlan> plans;
  std::vector<Episode> episodes;
  std::vector<CameraTrack> tracks;
  std::vector<BackgroundCache> caches;
};

ClipScenes PlanClip(const SynthConfig& cfg, DefectKind kind, std::mt19937_64& rng) {
  ClipScenes c;
  c.object = ChooseObject(cfg, rng);
  const bool two_scenes = kind == DefectKind::kCut || kind == DefectKind::kCrossFade;
  c.plans = {PlanScene(cfg, c.object, kind, rng)};
  if (two_scenes) c.plans.push_back(PlanScene(cfg, c.object, DefectKind::kClean, rng));
  c.caches.resize(c.plans.size());
  for (const ScenePlan& p : c.plans) {
    c.episodes.push_back(ScriptEpisode(p.spec, c.object.mesh));
    c.tracks.push_back(StaticCamera(p.camera, p.camera_from_world, cfg.frames));
  }
  return c;
}

struct DefectTiming {
  int cut = -1;         // first frame of scene B
  int fade_start = -1;  // first frame of the cross-fade
};

// Draws when the scripted defect happens, moves scene A's camera for the
// camera defects and records each defect.
DefectTiming TimeDefects(DefectKind kind, int T, std::mt19937_64& rng,
                         std::vector<CameraTrack>& tracks, std::vector<DefectRecord>& defects) {
  DefectTiming timing;
  switch (kind) {
    case DefectKind::kCut: {
      const int cut = T / 3 + std::uniform_int_distribution<int>(0, T / 3)(rng);
      timing.cut = cut;
      defects.push_back({"cut", cut, cut, {{"from_scene", 0}, {"to_scene", 1}}});
      break;
    }
    case DefectKind::kCrossFade: {
      const int start = T / 3 + std::uniform_int_distribution<int>(0, T / 3 - kFadeFrames)(rng);
      timing.fade_start = start;
      defects.push_back({"fade",
                         start,
                         start + kFadeFrames - 1,
                         {{"from_scene", 0}, {"to_scene", 1}, {"frames", kFadeFrames}}});
      break;
    }
    case DefectKind::kFadeBlack:
      defects.push_back({"black", 0, kFadeInFrames - 1, {{"direction", "in"}}});
      defects.push_back({"black", T - kFadeFrames, T - 1, {{"direction", "out"}}});
      break;
    case DefectKind::kPan: {
      const int s = T / 4, e = s + T / 2;
      const double rate = (Uniform(rng, 0, 1) < 0.5 ? -1 : 1) * Uniform(rng, 0.005, 0.008);
      ApplyPan(tracks[0], s, e, rate);
      defects.push_back({"pan", s, e, {{"rad_per_frame", rate}}});
      break;
    }
    case DefectKind::kShake: {
      const int s = T / 4, e = 3 * T / 4;
      const double amp = Uniform(rng, 0.003, 0.006);
      ApplyShake(tracks[0], s, e, amp, rng);
      defects.push_back({"shake", s, e, {{"amplitude_rad", amp}}});
      break;
    }
    case DefectKind::kZoom: {
      const int s = T / 4, e = 3 * T / 4;
      const double factor =
          Uniform(rng, 0, 1) < 0.5 ? Uniform(rng, 1.25, 1.45) : Uniform(rng, 0.7, 0.8);
      ApplyZoom(tracks[0], s, e, factor);
      defects.push_back({"zoom", s, e, {{"factor", factor}}});
      break;
    }
    default:
      break;
  }
  return timing;
}

// Which scene frame t shows, how far into a cross-fade and how dimmed.
struct FrameMix {
  int scene = 0;
  double blend = 0;  // > 0 inside a cross-fade from scene 0 to 1
  double gain = 1;   // < 1 while fading from or to black
};

FrameMix MixOf(int t, int T, DefectKind kind, const DefectTiming& timing) {
  FrameMix m;
  if (timing.cut >= 0 && t >= timing.cut) m.scene = 1;
  if (timing.fade_start >= 0) {
    if (t >= timing.fade_start + kFadeFrames) {
      m.scene = 1;
    } else if (t >= timing.fade_start) {
      m.blend = double(t - timing.fade_start + 1) / (kFadeFrames + 1);
      m.scene = m.blend >= 0.5 ? 1 : 0;
    }
  }
  if (kind == DefectKind::kFadeBlack) {
    if (t < kFadeInFrames) m.gain = double(t) / kFadeInFrames;
    if (t >= T - kFadeFrames) m.gain = double(T - 1 - t) / kFadeFrames;
  }
  return m;
}

// Renders frame t as written to the video (`bgr`, before sensor noise) and
// returns the ground truth of its dominant scene.
SceneFrame ComposeFrame(ClipScenes& c, const FrameMix& mix, int t, cv::Mat& bgr) {
  const int main_scene = mix.blend > 0 ? 0 : mix.scene;
  SceneFrame a = RenderScene(c.plans[main_scene], c.episodes[main_scene], c.tracks[main_scene],
                             c.object.mesh, t, c.caches[main_scene]);
  bgr = a.render.bgr;
  if (mix.blend <= 0) {
    if (mix.gain < 1) bgr = Dim(bgr, mix.gain);
    return a;
  }
  SceneFrame other = RenderScene(c.plans[1], c.episodes[1], c.tracks[1], c.object.mesh, t,
                                 c.caches[1]);
  bgr = CrossFade(a.render.bgr, other.render.bgr, mix.blend);
  if (mix.gain < 1) bgr = Dim(bgr, mix.gain);
  return mix.scene == 1 ? other : a;
}

// What the generator gathers over a clip's frames besides the bundle.
struct ClipTruth {
  explicit ClipTruth(int T, int track_points)
      : first_seen(track_points, -1),
        hand_in({std::vector<double>(T, 0.0), std::vector<double>(T, 0.0)}),
        object_in(T, 0.0), scene_of(T, 0), phase_of(T) {
    tracks.x.resize(track_points, T);
    tracks.y.resize(track_points, T);
    tracks.visible.resize(track_points, T);
    tracks.query.resize(track_points, 3);
  }
  std::array<recon::HandTrack, 2> hands;
  std::array<bool, 2> hand_seen{false, false};
  std::vector<Vec3> track_pts;  // object frame
  recon::PointTracks tracks;
  std::vector<int> first_seen;
  Json frames_json = Json::array();
  std::array<std::vector<double>, 2> hand_in;  // fraction of the hand in frame
  std::vector<double> object_in;
  std::vector<int> scene_of;
  std::vector<std::string> phase_of;
  double min_gap = std::numeric_limits<double>::infinity();  // hover: hand to object, m
  bool k_varies = false;
};

// Camera, depth, masks and object pose of frame t into the bundle.
void RecordScene(const SynthConfig& cfg, const ClipScenes& c, const SceneFrame& gt, int t,
                 recon::ClipBundle& b, ClipTruth& truth) {
  const Camera& cam = gt.state.camera;
  const Pose& cw = gt.state.camera_from_world;
  if (t > 0 && (cam.fx != b.K.back()(0, 0) || cam.fy != b.K.back()(1, 1))) truth.k_varies = true;
  b.K.push_back(cam.K());
  b.depth.push_back(gt.render.raster.depth.clone());
  if (cfg.point_maps) b.points.push_back(DepthToPoints(b.depth.back(), cam));
  b.mask_object.push_back(SurfaceMask(gt.render.raster, kSurfaceObject));
  b.mask_hand_left.push_back(SurfaceMask(gt.render.raster, kSurfaceHandLeft));
  b.mask_hand_right.push_back(SurfaceMask(gt.render.raster, kSurfaceHandRight));
  b.object_poses.push_back(cw * gt.state.object_pose);
  b.gravity_up.push_back(cw.R() * Vec3::UnitZ());
  truth.object_in[t] = InFrame(c.object.mesh.Transformed(gt.state.object_pose), cam, cw);
  truth.phase_of[t] = gt.episode->phase;
}

// Both hands of frame t (joints and mesh in the camera frame), and the
// hover gap of a no-contact clip.
void RecordHands(DefectKind kind, const ClipScenes& c, const SceneFrame& gt, int t,
                 ClipTruth& truth) {
  const Camera& cam = gt.state.camera;
  const Pose& cw = gt.state.camera_from_world;
  const TriMesh obj_world = c.object.mesh.Transformed(gt.state.object_pose);
  for (int s = 0; s < 2; ++s) {
    recon::HandTrack& h = truth.hands[s];
    const auto& posed = gt.state.hands[s];
    if (!posed) {
      h.valid.push_back(false);
      h.joints.push_back(recon::Joints21::Zero());
      h.verts.emplace_back(0, 3);
      continue;
    }
    truth.hand_seen[s] = true;
    h.valid.push_back(true);
    recon::Joints21 j;
    for (int k = 0; k < 21; ++k) j.row(k) = (cw * Vec3(posed->joints.row(k).transpose())).transpose();
    h.joints.push_back(j);
    h.verts.push_back(posed->mesh.Transformed(cw).vertices);
    h.faces = posed->mesh.faces;
    truth.hand_in[s][t] = InFrame(posed->mesh, cam, cw);
    if (kind != DefectKind::kNoContact || gt.episode->phase != "hover" ||
        s != static_cast<int>(c.plans[0].spec.active)) {
      continue;
    }
    for (const Capsule& cap : posed->capsules) {
      for (int k = 0; k <= 2; ++k) {
        const Vec3 p = cap.a + (cap.b - cap.a) * (k / 2.0);
        truth.min_gap = std::min(truth.min_gap, DistanceToMesh(obj_world, p) - cap.radius);
      }
    }
  }
}

// Projects the object's tracked surface points into frame t with their
// visibility (depth test against the rendered object).
void TrackPoints(const SceneFrame& gt, const Pose& obj_cam, int t, ClipTruth& truth) {
  const Camera& cam = gt.state.camera;
  recon::PointTracks& pt = truth.tracks;
  for (int i = 0; i < static_cast<int>(truth.track_pts.size()); ++i) {
    const Vec3 p = obj_cam * truth.track_pts[i];
    const Vec2 uv = p.z() > 0.01 ? cam.Project(p) : Vec2(-1e6, -1e6);
    pt.x(i, t) = static_cast<float>(uv.x());
    pt.y(i, t) = static_cast<float>(uv.y());
    const int ui = static_cast<int>(std::lround(uv.x())),
              vi = static_cast<int>(std::lround(uv.y()));
    bool vis = false;
    if (p.z() > 0.01 && ui >= 0 && vi >= 0 && ui < cam.width && vi < cam.height) {
      const float z = gt.render.raster.depth.at<float>(vi, ui);
      vis = gt.render.raster.surface.at<std::uint8_t>(vi, ui) == kSurfaceObject &&
            std::abs(z - p.z()) < std::max(0.004, 0.02 * p.z());
    }
    pt.visible(i, t) = vis;
    if (vis && truth.first_seen[i] < 0) {
      truth.first_seen[i] = t;
      pt.query.row(i) << float(t), pt.y(i, t), pt.x(i, t);
    }
  }
}

// 100DOH-style VOC boxes of frame t from the visible masks.
VocFrame VocOf(const SynthConfig& cfg, const std::string& clip_id, const SceneFrame& gt, int t,
               const recon::ClipBundle& b) {
  VocFrame voc;
  voc.genre = cfg.genre;
  voc.video_id = clip_id;
  voc.frame = t;
  voc.width = cfg.width;
  voc.height = cfg.height;
  const PixelBox obox = MaskBox(b.mask_object.back());
  const std::array<const cv::Mat*, 2> hmask = {&b.mask_hand_left.back(),
                                               &b.mask_hand_right.back()};
  for (int s = 0; s < 2; ++s) {
    const PixelBox hb = MaskBox(*hmask[s]);
    if (hb.empty()) continue;
    VocHand vh;
    vh.side = s;
    vh.box = hb;
    vh.contact_state = gt.episode->contact[s] ? 3 : 0;
    if (gt.episode->contact[s] && !obox.empty()) vh.object_box = obox;
    voc.hands.push_back(vh);
  }
  if (!obox.empty()) voc.objects.push_back({obox, gt.episode->contact[0], gt.episode->contact[1]});
  return voc;
}

// The per-frame facts of the ground-truth JSON, with the background motion
// from the previous frame of the same scene (camera defects only move scene
// A's camera; across a cut there is no motion).
Json FrameFacts(const ClipScenes& c, const FrameMix& mix, const SceneFrame& gt, int t,
                const recon::ClipBundle& b, const ClipTruth& truth) {
  const Camera& cam = gt.state.camera;
  Json fj{{"t", t},
          {"scene", mix.scene},
          {"blend", mix.blend},
          {"gain", mix.gain},
          {"phase", gt.episode->phase},
          {"K", {cam.fx, cam.fy, cam.cx, cam.cy}},
          {"camera_from_world", PoseJson(gt.state.camera_from_world)},
          {"object_in_frame", truth.object_in[t]},
          {"object_pixels", cv::countNonZero(b.mask_object.back())},
          {"contact", {gt.episode->contact[0], gt.episode->contact[1]}},
          {"hand_present", {bool(gt.state.hands[0]), bool(gt.state.hands[1])}},
          {"hand_in_frame", {truth.hand_in[0][t], truth.hand_in[1][t]}},
          {"hand_pixels",
           {cv::countNonZero(b.mask_hand_left.back()), cv::countNonZero(b.mask_hand_right.back())}}};
  Mat3 H = Mat3::Identity();
  if (t > 0 && truth.scene_of[t - 1] == mix.scene) {
    const CameraTrack& tr = c.tracks[mix.scene];
    H = ViewHomography(tr.camera[t - 1], tr.camera_from_world[t - 1], tr.camera[t],
                       tr.camera_from_world[t]);
  }
  const Vec2 d = Displacement(H, cam.cx, cam.cy);
  Mat3 Hr = H.transpose();
  fj["H_prev"] = std::vector<double>(Hr.data(), Hr.data() + 9);  // row-major
  fj["bg_dx"] = d.x();
  fj["bg_dy"] = d.y();
  return fj;
}

// Defects whose extent only the rendered geometry tells: how long the hand
// or object was out of frame, when the hand hovered.
void AddMeasuredDefects(DefectKind kind, int T, int active, const ClipTruth& truth,
                        std::vector<DefectRecord>& defects) {
  if (kind == DefectKind::kHandOut || kind == DefectKind::kObjectOut) {
    const auto& series = kind == DefectKind::kHandOut ? truth.hand_in[active] : truth.object_in;
    const auto run = LongestRun(series, 0.0);
    if (run.first >= 0) {
      defects.push_back({DefectName(kind),
                         run.first,
                         run.second,
                         {{"subject", kind == DefectKind::kHandOut ? "hand" : "object"},
                          {"side", active == 1 ? "right" : "left"}}});
    }
  }
  if (kind == DefectKind::kNoContact) {
    int s = -1, e = -1;
    for (int t = 0; t < T; ++t) {
      if (truth.phase_of[t] != "hover") continue;
      if (s < 0) s = t;
      e = t;
    }
    defects.push_back({"no_contact", s, e, {{"min_gap_m", truth.min_gap}}});
  }
  if (kind == DefectKind::kStatic) defects.push_back({"static", 0, T - 1, Json::object()});
}

// The per-clip ground-truth JSON (docs: synth/generator.h).
Json ClipJson(const SynthConfig& cfg, int index, DefectKind kind, const RenderedClip& clip,
              const ClipScenes& scenes, const ClipTruth& truth) {
  Json defects = Json::array();
  for (const auto& d : clip.defects) defects.push_back(ToJson(d));
  Json plans = Json::array();
  for (const auto& p : scenes.plans) plans.push_back(SceneJson(p, scenes.object));
  return Json{{"clip", clip.id},
              {"video", "videos/" + clip.id + ".mp4"},
              {"index", index},
              {"seed", cfg.seed},
              {"frames", cfg.frames},
              {"width", cfg.width},
              {"height", cfg.height},
              {"fps", cfg.fps},
              {"kind", DefectName(kind)},
              {"defects", defects},
              {"scenes", plans},
              {"per_frame", truth.frames_json}};
}

// Renders every frame into `clip` (video frames, bundle, VOC boxes) and
// returns what was gathered on the way.
ClipTruth RenderFrames(const SynthConfig& cfg, DefectKind kind, const DefectTiming& timing,
                       std::uint64_t clip_seed, ClipScenes& scenes, std::mt19937_64& rng,
                       RenderedClip& clip) {
  const int T = cfg.frames;
  ClipTruth truth(T, cfg.track_points);
  truth.track_pts = SampleSurface(scenes.object.mesh, cfg.track_points, rng);
  recon::ClipBundle& b = clip.bundle;
  for (int t = 0; t < T; ++t) {
    const FrameMix mix = MixOf(t, T, kind, timing);
    cv::Mat bgr;
    const SceneFrame gt = ComposeFrame(scenes, mix, t, bgr);
    bgr = bgr.clone();
    AddSensorNoise(bgr, cfg.sensor_noise, Hash(clip_seed, t, 77));
    clip.bgr.push_back(bgr);
    truth.scene_of[t] = mix.scene;
    RecordScene(cfg, scenes, gt, t, b, truth);
    RecordHands(kind, scenes, gt, t, truth);
    TrackPoints(gt, b.object_poses.back(), t, truth);
    clip.voc.push_back(VocOf(cfg, clip.id, gt, t, b));
    truth.frames_json.push_back(FrameFacts(scenes, mix, gt, t, b, truth));
  }
  return truth;
}

}  // namespace

RenderedClip RenderClip(const SynthConfig& cfg, int index, DefectKind kind) {
  if (cfg.frames < 24) {
    throw Error("bad_config", "frames per clip must be at least 24", {.field = "frames"});
  }
  if (cfg.width < 64 || cfg.height < 48) {
    throw Error("bad_config", "image must be at least 64x48", {.field = "width"});
  }
  const std::uint64_t clip_seed = Hash(cfg.seed, index, 0xc11b);
  std::mt19937_64 rng(clip_seed);
  RenderedClip clip;
  char number[16];
  std::snprintf(number, sizeof number, "%04d", index);
  clip.id = "s" + std::to_string(cfg.seed) + "c" + number;
  const int T = cfg.frames;
  ClipScenes scenes = PlanClip(cfg, kind, rng);
  const DefectTiming timing = TimeDefects(kind, T, rng, scenes.tracks, clip.defects);

  recon::ClipBundle& b = clip.bundle;
  b.width = cfg.width;
  b.height = cfg.height;
  b.frames = T;
  b.fps = cfg.fps;
  b.producers = Json{{"all", "doasido synth (exact ground truth)"},
                     {"candidates", "doasido synth SAM 3D-like pose sampler"}};
  b.object_mesh = scenes.object.mesh;
  ClipTruth truth = RenderFrames(cfg, kind, timing, clip_seed, scenes, rng, clip);
  if (!truth.k_varies) b.K.resize(1);
  // Frames without the hand keep a (0,3) mesh, the bundle's "no mesh" value.
  for (int s = 0; s < 2; ++s) {
    if (truth.hand_seen[s]) (s == 0 ? b.hand_left : b.hand_right) = truth.hands[s];
  }
  recon::PointTracks& pt = truth.tracks;
  for (int i = 0; i < cfg.track_points; ++i) {
    if (truth.first_seen[i] < 0) pt.query.row(i) << 0.f, pt.y(i, 0), pt.x(i, 0);
  }
  b.tracks = pt;
  const Vec3 centre(0, 0, 0.5 * scenes.object.mesh.Max().z());
  b.candidates = SamplePoseCandidates(b.object_poses, centre, cfg.candidates, rng);
  AddMeasuredDefects(kind, T, static_cast<int>(scenes.plans[0].spec.active), truth, clip.defects);
  clip.gt = ClipJson(cfg, index, kind, clip, scenes, truth);
  return clip;
}

}  // namespace doasido::synth
