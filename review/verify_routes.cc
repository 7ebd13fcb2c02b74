#include "review/verify_routes.h"

#include "ingest/file_sha256.h"

#include "review/request_body.h"

#include <cstdlib>

#include "core/data_dirs.h"
#include "core/error.h"
#include "core/file_text.h"
#include "review/trajectory_lookup.h"
#include "robot/embodiment.h"
#include "robot/trajectory/format.h"
#include "robot/trajectory/source.h"

#include <httplib.h>  // after Eigen (see verify_routes.h)

namespace doasido::review {
namespace {

const std::vector<std::string>& TrajectoryStages() {
  static const std::vector<std::string> stages(retarget::kTrajectoryStages.begin(),
                                               retarget::kTrajectoryStages.end());
  return stages;
}

const char* GeomType(int type) {
  switch (type) {
    case mjGEOM_PLANE: return "plane";
    case mjGEOM_SPHERE: return "sphere";
    case mjGEOM_CAPSULE: return "capsule";
    case mjGEOM_ELLIPSOID: return "ellipsoid";
    case mjGEOM_CYLINDER: return "cylinder";
    case mjGEOM_BOX: return "box";
    case mjGEOM_MESH: return "mesh";
    default: return "";
  }
}

template <typename T>
Json Slice(const T* p, int n) {
  return Json(std::vector<T>(p, p + n));
}

// Geoms by body and meshes of a compiled model: groups 0-3 (3 holds the
// object scenes' convex hulls, which are all the object has).
Json Geometry(const mjModel* m) {
  Json bodies = Json::array(), meshes = Json::array();
  for (int b = 0; b < m->nbody; ++b) {
    const char* name = mj_id2name(m, mjOBJ_BODY, b);
    bodies.push_back({{"name", name ? name : ""}, {"geoms", Json::array()}});
  }
  for (int g = 0; g < m->ngeom; ++g) {
    const std::string type = GeomType(m->geom_type[g]);
    if (type.empty() || m->geom_group[g] > 3) continue;
    Json geom = {{"type", type}, {"size", Slice(m->geom_size + 3 * g, 3)},
                 {"pos", Slice(m->geom_pos + 3 * g, 3)}, {"quat", Slice(m->geom_quat + 4 * g, 4)},
                 {"rgba", Slice(m->geom_rgba + 4 * g, 4)}};
    if (m->geom_type[g] == mjGEOM_MESH) geom["mesh"] = m->geom_dataid[g];
    bodies[m->geom_bodyid[g]]["geoms"].push_back(geom);
  }
  for (int k = 0; k < m->nmesh; ++k) {
    meshes.push_back({{"vertices", Slice(m->mesh_vert + 3 * m->mesh_vertadr[k], 3 * m->mesh_vertnum[k])},
                      {"faces", Slice(m->mesh_face + 3 * m->mesh_faceadr[k], 3 * m->mesh_facenum[k])}});
  }
  return {{"bodies", bodies}, {"meshes", meshes}};
}

Json PoseJson(const Pose& p) {
  return Json::array({p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
}

// Body poses (x y z qw qx qy qz per body) of every trajectory frame.
Json Replay(const mjModel* m, const retarget::HandTrajectory& t) {
  retarget::DataPtr data = retarget::MakeData(m);
  mjData* d = data.get();
  const std::vector<std::string> names = retarget::QposNames(m);
  std::vector<std::pair<int, int>> map;  // (trajectory index, qpos address)
  for (size_t i = 0; i < t.qpos_names.size(); ++i) {
    const auto it = std::find(names.begin(), names.end(), t.qpos_names[i]);
    if (it != names.end()) map.emplace_back(static_cast<int>(i), static_cast<int>(it - names.begin()));
  }
  const int object = retarget::NameToId(m, mjOBJ_BODY, "object");
  const int free_qpos = object >= 0 && m->body_jntnum[object] > 0 &&
                                m->jnt_type[m->body_jntadr[object]] == mjJNT_FREE
                            ? m->jnt_qposadr[m->body_jntadr[object]]
                            : -1;
  Json frames = Json::array();
  for (size_t f = 0; f < t.qpos.size(); ++f) {
    for (const auto& [i, adr] : map) d->qpos[adr] = t.qpos[f][i];
    if (free_qpos >= 0 && f < t.object_poses.size()) {
      const Pose& p = t.object_poses[f];
      const double q[7] = {p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()};
      std::copy(q, q + 7, d->qpos + free_qpos);
    }
    mj_kinematics(m, d);
    std::vector<double> poses;
    poses.reserve(7 * m->nbody);
    for (int b = 0; b < m->nbody; ++b) {
      poses.insert(poses.end(), d->xpos + 3 * b, d->xpos + 3 * b + 3);
      poses.insert(poses.end(), d->xquat + 4 * b, d->xquat + 4 * b + 4);
    }
    frames.push_back(poses);
  }
  return frames;
}

// The three.js the page draws the robot with, from the npm packages.
void ServeThree(httplib::Response& res) {
  const std::filesystem::path p = NpmDir() / "node_modules/three/build/three.min.js";
  if (!std::filesystem::is_regular_file(p)) {
    res.status = 404;
    res.set_content(Json({{"error", "three.js is not installed at " + p.string() +
                                        " (run scripts/setup.sh)"}}).dump(),
                    "application/json");
    return;
  }
  res.set_header("Cache-Control", "max-age=3600");
  res.set_content(TryReadFile(p).value_or(""), "text/javascript; charset=utf-8");
}

// A person's accept or reject of a clip's trajectory (POST /api/verify/decision).
void RecordDecision(Database& d, const httplib::Request& req, httplib::Response& res) {
  const Json body = ParseRequestBody(req.body);
  const DecisionRequest r = ReadDecision(body);
  if (!retarget::IsTrajectoryStage(r.stage)) {
    throw Error("bad_request", "must be a trajectory stage", {.field = "stage"});
  }
  const ClipId clip = r.clip;
  const std::string& stage = r.stage;
  // The decision is for the trajectory file as it is now; a page that
  // says which one it showed (trajectory_sha256) is refused when the
  // trajectory changed since.
  std::string why;
  const auto files = FindTrajectoryFiles(d, clip, &why, true);
  if (!files || files->stage != stage) {
    res.status = 409;
    res.set_content(Json({{"error", "no trajectory to verify: " + why}}).dump(),
                    "application/json");
    return;
  }
  const std::string sha = ingest::FileSha256(files->trajectory);
  const std::string shown = body.value("trajectory_sha256", std::string());
  if (!shown.empty() && shown != sha) {
    res.status = 409;
    res.set_content(Json({{"error", "the trajectory changed since it was shown; reload"}}).dump(),
                    "application/json");
    return;
  }
  d.RecordVerification(clip, stage, r.reviewer, r.accept, r.reason, sha);
  res.set_content(Json({{"ok", true},
                        {"remaining", d.ListTrajectoriesToVerify(TrajectoryStages()).size()}}).dump(),
                  "application/json");
}

}  // namespace

Json TrajectoryScene(Database& db, ClipId clip, const std::string& stage) {
  std::string why;
  std::optional<retarget::TrajectoryFiles> files = FindTrajectoryFiles(db, clip, &why, true);
  if (files && files->stage != stage) {
    why = "stage " + stage + " is not the trajectory stage (" + files->stage + ")";
    files.reset();
  }
  if (!files) {
    throw Error("no_such_trajectory", "no trajectory for this clip and stage: " + why,
                {.clip = std::to_string(clip), .field = "stage"});
  }
  const retarget::HandTrajectory t = retarget::ReadTrajectoryJson(files->trajectory);
  // Two hands ran in the scene the stage wrote beside the trajectory; one
  // hand is rebuilt from its description and the object scene.
  retarget::ModelPtr model;
  if (retarget::IsBimanualEmbodiment(t.embodiment)) {
    const auto xml = files->trajectory.parent_path() / retarget::kRobotSceneFile;
    model = retarget::CompileMjcfText(ReadFileOrThrow(xml, "no_such_trajectory", "no robot scene beside a two-hand "
                                                      "trajectory"), xml.string());
  } else {
    model = retarget::BuildHandModel(retarget::FindEmbodiment(t.embodiment, retarget::DefaultRobotsDir()),
                                     retarget::ReadSceneXml(files->scene_dir), files->scene_dir)
                .model;
  }
  Json out = Geometry(model.get());
  out["trajectory_sha256"] = ingest::FileSha256(files->trajectory);
  out["run_id"] = files->run_id;
  out["fps"] = t.fps;
  out["frames"] = t.qpos.size();
  out["embodiment"] = t.embodiment;
  out["poses"] = Replay(model.get(), t);
  out["object_body"] = retarget::NameToId(model.get(), mjOBJ_BODY, "object");
  Json ref = Json::array();
  for (const Pose& p : t.object_poses) ref.push_back(PoseJson(p));
  out["object_reference"] = ref;
  Json keypoints = Json::array();
  for (const retarget::Keypoints21& k : t.reference_keypoints) {
    keypoints.push_back(k.allFinite() ? Json(std::vector<double>(k.data(), k.data() + 63)) : Json());
  }
  out["reference_keypoints"] = keypoints;
  out["fingertip_error"] = t.fingertip_error;
  const auto m = db.GetMeasurements(clip, stage);
  out["measurements"] = m ? *m : Json::object();
  return out;
}

void AddVerifyRoutes(httplib::Server& http, const VerifyHooks& hooks) {
  http.Get("/verify", [hooks](const httplib::Request&, httplib::Response& res) {
    const std::string nonce = hooks.make_nonce();
    res.set_header("Content-Security-Policy",
                   "default-src 'none'; script-src 'nonce-" + nonce + "'; style-src 'nonce-" +
                       nonce + "'; img-src 'self' data:; media-src 'self'; connect-src 'self'; "
                       "base-uri 'none'; form-action 'self'; frame-ancestors 'none'");
    res.set_content(VerifyPage(nonce, {{"token", hooks.token}, {"reviewer", hooks.reviewer}}),
                    "text/html; charset=utf-8");
  });

  http.Get("/vendor/three.min.js",
           [](const httplib::Request&, httplib::Response& res) { ServeThree(res); });

  http.Get("/api/verify/queue", [hooks](const httplib::Request&, httplib::Response& res) {
    hooks.with_db(res, [&](Database& d) {
      Json items = Json::array();
      for (const auto& r : d.ListTrajectoriesToVerify(TrajectoryStages())) {
        items.push_back({{"clip_id", r.clip_id}, {"external_id", r.external_id},
                         {"stage", r.stage}, {"verdict", r.verdict}, {"reason", r.reason}});
      }
      res.set_content(Json({{"items", items}}).dump(), "application/json");
    });
  });

  http.Get(R"(/api/verify/scene/(\d+))", [hooks](const httplib::Request& req, httplib::Response& res) {
    hooks.with_db(res, [&](Database& d) {
      const std::string stage = req.get_param_value("stage");
      if (!retarget::IsTrajectoryStage(stage)) {
        res.status = 400;
        res.set_content(Json({{"error", "stage must be a trajectory stage"}}).dump(), "application/json");
        return;
      }
      res.set_content(TrajectoryScene(d, PathId(req.matches[1].str()), stage).dump(),
                      "application/json");
    });
  });

  http.Post("/api/verify/decision", [hooks](const httplib::Request& req, httplib::Response& res) {
    hooks.with_db(res, [&](Database& d) { RecordDecision(d, req, res); });
  });
}

}  // namespace doasido::review
