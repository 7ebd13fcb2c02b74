// The velocity-field seam end to end: tools/velocity_server.py (the
// reference server, Debian's python3-numpy) answering from the same
// Gaussian mixture as the in-process stand-in gives the same velocities,
// divergences and tracks; a server that dies, answers garbage, NaN or
// another protocol version fails with a named error.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "eval/mixture_file.h"
#include "recon/track/object_tracker.h"
#include "recon/track/silhouette.h"
#include "recon/track/velocity_server.h"
#include "synth/tracking_scene.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

std::string ServerCommand(const std::filesystem::path& modes, const std::string& extra = "") {
  return std::string("/usr/bin/python3 ") + DOASIDO_SOURCE_DIR + "/tools/velocity_server.py " +
         modes.string() + extra;
}

TEST(VelocityServer, AnswersAsTheInProcessModelAndTracksTheSame) {
  TempDir dir;
  const synth::TrackingScene scene = synth::MakeTrackingScene(8);
  WriteMixtureNpz(dir / "modes.npz", *scene.model);
  GaussianMixtureFlow local = ReadMixtureNpz(dir / "modes.npz");
  VelocityServer server(ServerCommand(dir / "modes.npz"), dir / "server.log");
  ASSERT_EQ(server.Layout().dim(), scene.model->Layout().dim());
  EXPECT_EQ(server.frames(), 25);

  StateMatrix x = StateMatrix::Random(6, server.Layout().dim());
  for (double t : {0.0, 0.3, 0.96}) {
    StateMatrix v_server, v_local;
    server.Velocity(4, t, x, &v_server);
    scene.model->Velocity(4, t, x, &v_local);
    EXPECT_LT((v_server - v_local).cwiseAbs().maxCoeff(), 1e-9 * (1 + v_local.cwiseAbs().maxCoeff()));
    Eigen::VectorXd d_server, d_local;
    server.PoseDivergence(4, t, x, &d_server);
    local.PoseDivergence(4, t, x, &d_local);
    EXPECT_LT((d_server - d_local).cwiseAbs().maxCoeff(), 1e-7 * (1 + d_local.cwiseAbs().maxCoeff()));
  }

  const SilhouetteRenderer renderer(scene.mesh);
  TrackInputs inputs;
  inputs.pose_guidance = std::vector<double>(25, 0.5);
  inputs.silhouette_iou = [&](int k, const Pose& p) {
    return renderer.IoU(p, scene.camera, scene.masks[k], 2, scene.hand_masks[k]);
  };
  for (const char* method : {kSelectLikelihood, kSelectClustering}) {
    const auto a = TrackObject(server, 25, inputs, {}, {.method = method});
    const auto b = TrackObject(local, 25, inputs, {}, {.method = method});
    for (int k = 0; k < 25; ++k) {
      EXPECT_EQ(a[k].choice.index, b[k].choice.index) << method << " frame " << k;
      EXPECT_LT((a[k].pose.t - b[k].pose.t).norm(), 1e-9) << method << " frame " << k;
    }
  }
}

void ExpectServerError(const std::string& misbehave, const std::string& code,
                       const std::string& mentions) {
  TempDir dir;
  const synth::TrackingScene scene = synth::MakeTrackingScene(2);
  WriteMixtureNpz(dir / "modes.npz", *scene.model);
  const std::string command =
      misbehave == "missing" ? "/nonexistent/model_server"
                             : ServerCommand(dir / "modes.npz", " --misbehave " + misbehave);
  try {
    VelocityServer server(command, dir / "server.log");
    StateMatrix x = StateMatrix::Zero(3, server.Layout().dim()), v;
    server.Velocity(0, 0.5, x, &v);
    ADD_FAILURE() << misbehave << ": no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(command));
    EXPECT_THAT(e.what(), HasSubstr("server.log"));
    EXPECT_THAT(e.what(), HasSubstr(mentions));
  }
}

TEST(VelocityServer, AServerThatMisbehavesFailsWithANamedError) {
  ExpectServerError("die", kServerDied, "exit code 3");
  ExpectServerError("die", kServerDied, "dying on purpose");  // the log's tail
  ExpectServerError("garbage", kServerProtocol, "header length");
  ExpectServerError("version", kServerVersion, "protocol 2");
  ExpectServerError("nan", kServerProtocol, "NaN");
  ExpectServerError("missing", kServerDied, "exit code 127");
}

}  // namespace
}  // namespace doasido::recon
