// Trajectory verification in the review app (docs/review.md): a second
// queue of robot trajectories (the `retarget` stage's, else
// `retarget_kinematic`'s) that a person accepts ("verified") or rejects
// with a reason, watching the clip beside a 3D replay (three.js, served by
// the server from the npm cache; no network at run time).
//
// Routes (same security as the rest of the app: token and same origin on
// POST, loopback Host, numeric ids only):
//   GET  /verify                          the page
//   GET  /vendor/three.min.js             three.js from the npm cache
//   GET  /api/verify/queue                trajectories not yet verified
//   GET  /api/verify/scene/<clip>?stage=  geometry (geom types, sizes, mesh
//                                         vertices) and per-frame body poses
//                                         from the compiled MuJoCo model, the
//                                         reference object poses, metrics
//   POST /api/verify/decision             {clip_id, stage, decision, reviewer,
//                                          reason_code, reason_text}
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "core/config.h"
#include "db/database.h"

// httplib.h is included only by .cc files, after Eigen: it pulls in
// <resolv.h>, whose `_res` macro breaks Eigen's headers.
namespace httplib {
class Server;
struct Response;
}  // namespace httplib

namespace doasido::review {

struct VerifyHooks {
  // Runs fn with the database under the server's lock, answering errors.
  std::function<void(httplib::Response&, const std::function<void(Database&)>&)> with_db;
  std::function<std::string()> make_nonce;
  std::string token;
  std::string reviewer;
};

// The geometry and replay of a trajectory (the /api/verify/scene answer).
// Throws Error("no_trajectory") when neither stage wrote one.
Json TrajectoryScene(Database& db, ClipId clip, const std::string& stage);

void AddVerifyRoutes(httplib::Server& http, const VerifyHooks& hooks);

// The verification page; `config` holds token and reviewer.
std::string VerifyPage(const std::string& nonce, const Json& config);

}  // namespace doasido::review
