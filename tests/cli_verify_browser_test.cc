// Trajectory verification in real headless Chromium (Debian's chromium +
// chromedriver; WebGL through SwiftShader): the page plays the clip beside
// a three.js replay of the robot trajectory, scrubbing moves the robot, and
// the keyboard's accept and reject land in the database as human verdicts.
// Screenshots go to $DOASIDO_SHOTS_DIR when it is set.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <cstdlib>
#include <numbers>

#include "core/mesh.h"
#include "dataset/version.h"
#include "db/database.h"
#include "eval/mug_mesh.h"
#include "eval/reconstruction_noise.h"
#include "stages/stage_registry.h"
#include "stages/recon_stage.h"
#include "recon/reconstruction.h"
#include "stages/dynamic_stage.h"
#include "stages/kinematic_stage.h"
#include "retarget/scene/scene_builder.h"
#include "review/server.h"
#include "robot/embodiment.h"
#include "robot/trajectory/format.h"
#include "synth/episode.h"
#include "synth/objects.h"
#include "tests/test_util.h"
#include "tests/webdriver.h"

namespace doasido {
namespace {

using testing::ChromeDriver;
using testing::RunDoasido;
using testing::TempDir;
using testing::WebDriverSession;
using testing::SnapshotView;
using testing::ChangedPixels;
using testing::kWebGlFlags;

// A 30-frame trajectory: the wrist sweeps 0.2 m along x while the fingers
// close, above a mug when `mug` is set (scene written as the stage would).
retarget::HandTrajectory WriteTrajectory(const std::filesystem::path& dir, bool mug) {
  const retarget::HandModel hand =
      retarget::BuildHandModel(retarget::FindEmbodiment("sharpa_right", {}));
  retarget::HandTrajectory t;
  t.embodiment = "sharpa_right";
  t.fps = 30;
  t.qpos_names = retarget::QposNames(hand.model.get());
  const mjModel* m = hand.model.get();
  for (int f = 0; f < 30; ++f) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(m->nq);
    q[hand.wrist_qpos[0]] = -0.1 + 0.2 * f / 29.0;
    q[hand.wrist_qpos[2]] = 0.15;
    q[hand.wrist_qpos[4]] = std::numbers::pi / 2;  // fingers along +x, palm down
    for (int j = 0; j < m->njnt; ++j) {
      const int a = m->jnt_qposadr[j];
      if (std::find(hand.finger_qpos.begin(), hand.finger_qpos.end(), a) == hand.finger_qpos.end()) continue;
      q[a] = m->jnt_range[2 * j] + (m->jnt_range[2 * j + 1] - m->jnt_range[2 * j]) * 0.6 * f / 29.0;
    }
    t.qpos.push_back(q);
    t.valid.push_back(true);
    t.fingertip_error.push_back(0.002 + 0.0001 * f);
    // The human hand it followed: a fan of five fingers ahead of the wrist.
    retarget::Keypoints21 k;
    const Vec3 wrist(q[hand.wrist_qpos[0]], q[hand.wrist_qpos[1]], q[hand.wrist_qpos[2]]);
    k.row(0) = wrist.transpose();
    for (int i = 1; i < 21; ++i) {
      k.row(i) = (wrist + Vec3(0.025 * ((i - 1) % 4 + 1), 0.02 * ((i - 1) / 4 - 2), 0.01)).transpose();
    }
    t.reference_keypoints.push_back(k);
  }
  std::filesystem::create_directories(dir);
  if (mug) {
    const retarget::ObjectScene scene = retarget::BuildObjectScene(
        retarget::MakeMug(), {Quat::Identity(), Vec3(0, 0, 0)}, retarget::SceneConfig{}, dir / "scene");
    t.object_poses.assign(30, scene.pose);
    for (int f = 0; f < 30; ++f) t.object_poses[f].t.y() += 0.002 * f;  // the reference drifts
  }
  retarget::WriteTrajectoryJson(t, dir / "trajectory.json");
  return t;
}

// Pixels of the 3D view differing from its background, and a checksum.
Json CanvasStats(WebDriverSession& session) {
  return session.Execute(R"js(
    const v = document.getElementById('view');
    const c = document.createElement('canvas'); c.width = v.width; c.height = v.height;
    const g = c.getContext('2d'); g.drawImage(v, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let differ = 0, sum = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - 0x20) + Math.abs(d[i + 1] - 0x24) + Math.abs(d[i + 2] - 0x2c) > 12) ++differ;
      sum = (sum * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
    }
    return {differ, sum, w: c.width, h: c.height, pixels: c.width * c.height};
  )js");
}

// Opens the verification page and waits for its queue; returns its length.
int OpenVerifyQueue(WebDriverSession& session, const review::ReviewServer& server) {
  session.Navigate(server.Origin() + "/verify");
  return session.WaitFor("document.body.dataset.ready === '1' && document.body.dataset.loaded === '1'"
                         " && window.doasidoVerify.queue.length", "the verification queue", 60).get<int>();
}

// `clips` rendered synthetic clips (30 frames, 160 x 120) in a database
// whose pipeline is probe then `stage`, probed; returns the database.
std::filesystem::path ProbedClips(const TempDir& dir, int clips, int seed, const std::string& stage) {
  EXPECT_EQ(RunDoasido({"synth", "--out", (dir / "synth").string(), "--clips", std::to_string(clips), "--frames",
                        "30", "--width", "160", "--height", "120", "--seed", std::to_string(seed), "--mix",
                        "clean=1", "--no-bundles"}).exit_code, 0);
  const auto db_path = dir / "work" / "d.db";
  EXPECT_EQ(RunDoasido({"init", "--db", db_path.string(), "--pipeline", "probe," + stage}).exit_code, 0);
  EXPECT_EQ(RunDoasido({"ingest", "--db", db_path.string(), (dir / "synth" / "clips.csv").string()}).exit_code, 0);
  Database db(db_path);
  auto probe = stages::MakeStage("probe", Json::object());
  while (auto claim = db.ClaimNext("test", {"probe"}, 60, 3)) {
    EXPECT_TRUE(db.Complete(*claim, "test", "h", probe->Run(db.LoadContext(claim->clip_id, "probe")), 0.0));
  }
  return db_path;
}

TEST(VerifyBrowser, ReplayBesideVideoScrubAndKeyboardVerdicts) {
  if (!testing::ChromiumAvailable()) GTEST_SKIP() << "needs Debian's chromium and chromium-driver";
  TempDir dir;
  const auto db_path = ProbedClips(dir, 2, 3, retarget::kKinematicStageName);
  Database db(db_path);
  std::vector<ClipId> clips;
  while (auto claim = db.ClaimNext("test", {retarget::kKinematicStageName}, 60, 3)) {
    const ClipId id = claim->clip_id;
    WriteTrajectory(db.ArtifactDir(id, retarget::kKinematicStageName), clips.empty());
    StageResult result;
    result.measurements = {{"fingertip_error_mean", 0.0035}, {"frames", 30}};
    ASSERT_TRUE(db.Complete(*claim, "test", "h", result, 0.0));
    clips.push_back(id);
  }
  ASSERT_EQ(clips.size(), 2u);

  ChromeDriver driver(dir / "chromedriver.log");
  review::ReviewServer server(db_path, {.port = 0, .reviewer = "vera"});
  server.Start();
  WebDriverSession session(driver, 1400, 900, kWebGlFlags);
  EXPECT_EQ(OpenVerifyQueue(session, server), 2);
  // The clip's video is loaded beside the view.
  const Json video = session.WaitFor(
      "(() => { const v = document.getElementById('video'); return v.readyState >= 1 &&"
      " v.src.endsWith('/video/" + std::to_string(clips[0]) + "') && {w: v.videoWidth}; })()",
      "the clip's video");
  EXPECT_EQ(video.at("w"), 160);

  const Json first = CanvasStats(session);
  std::printf("view %dx%d: %d of %d pixels differ from the background\n", first.at("w").get<int>(),
              first.at("h").get<int>(), first.at("differ").get<int>(), first.at("pixels").get<int>());
  EXPECT_GT(first.at("differ").get<int>(), 1000) << first.dump();
  if (const char* shots = std::getenv("DOASIDO_SHOTS_DIR")) {
    session.Screenshot(std::filesystem::path(shots) / "verify_frame0.png");
  }

  // The human keypoints the hand followed are drawn: hiding them changes pixels.
  SnapshotView(session, "with_keypoints");
  session.Execute("window.doasidoVerify.skeleton.visible = false; window.doasidoVerify.render();");
  const int keypoint_pixels = ChangedPixels(session, "with_keypoints");
  std::printf("reference keypoints: %d pixels\n", keypoint_pixels);
  EXPECT_GT(keypoint_pixels, 50);
  session.Execute("window.doasidoVerify.skeleton.visible = true; window.doasidoVerify.render();");

  // Scrub to the last frame: the robot moves (pixels change) and the video follows.
  SnapshotView(session, "before");
  session.Execute(
      "const s = document.getElementById('scrub'); s.value = 29; s.dispatchEvent(new Event('input'));");
  session.WaitFor("document.body.dataset.frame === '29'", "the scrub");
  const int changed = ChangedPixels(session, "before");
  std::printf("scrub to frame 29: %d pixels changed\n", changed);
  EXPECT_GT(changed, 500);
  const Json t = session.WaitFor(
      "(() => { const v = document.getElementById('video'); return !v.seeking && v.currentTime > 0.9 &&"
      " v.currentTime; })()", "the video to follow the scrub");
  EXPECT_NEAR(t.get<double>(), 29.0 / 30, 1.0 / 30);
  if (const char* shots = std::getenv("DOASIDO_SHOTS_DIR")) {
    session.Screenshot(std::filesystem::path(shots) / "verify_frame29.png");
  }

  // a accepts the first trajectory; 2 picks object_drift and r rejects the second.
  session.PressKeys({"a"});
  session.WaitFor("document.body.dataset.decisions === '1' && document.body.dataset.loaded === '1' &&"
                  " document.body.dataset.clipId === '" + std::to_string(clips[1]) + "'",
                  "the accept to be saved", 60);
  session.PressKeys({"2", "r"});
  session.WaitFor("document.body.dataset.decisions === '2'", "the reject to be saved");
  EXPECT_EQ(session.Execute("return window.doasidoVerify.queue.length;"), 0);

  const auto reviews = db.ListReviews();
  ASSERT_EQ(reviews.size(), 2u);
  EXPECT_EQ(reviews[0].clip_id, clips[0]);
  EXPECT_EQ(reviews[0].decision, "accept");
  EXPECT_EQ(reviews[0].reviewer, "vera");
  EXPECT_EQ(reviews[1].clip_id, clips[1]);
  EXPECT_EQ(reviews[1].decision, "reject");
  EXPECT_EQ(reviews[1].reason, "object_drift");
  const auto accepted = db.VerdictHistory(clips[0], retarget::kKinematicStageName);
  ASSERT_FALSE(accepted.empty());
  EXPECT_EQ(accepted.back().verdict, "pass");
  EXPECT_EQ(accepted.back().source, "human");
  EXPECT_EQ(accepted.back().reason, "");
  const auto rejected = db.VerdictHistory(clips[1], retarget::kKinematicStageName);
  EXPECT_EQ(rejected.back().verdict, "reject");
  EXPECT_EQ(rejected.back().source, "human");
  EXPECT_TRUE(db.ListTrajectoriesToVerify({"retarget", retarget::kKinematicStageName}).empty());

  // `dataset create` (--select verified by default) takes exactly the accepted one.
  const auto created = RunDoasido({"dataset", "create", "--db", db_path.string(), "--root",
                                   (dir / "datasets").string(), "--no-thumbnails"});
  ASSERT_EQ(created.exit_code, 0) << created.err;
  const dataset::Manifest version = dataset::ReadManifest(dir / "datasets/default/v1");
  ASSERT_EQ(version.episodes.size(), 1u);
  EXPECT_EQ(version.episodes[0].clip_id, clips[0]);
  ASSERT_TRUE(version.episodes[0].verification);
  EXPECT_EQ(version.episodes[0].verification->reviewer, "vera");
  ASSERT_EQ(version.excluded.size(), 1u);
  EXPECT_EQ(version.excluded[0].clip_id, clips[1]);
  EXPECT_EQ(version.excluded[0].decided_by.source, "human");

  // The same security as the other routes: a decision without the token is refused.
  httplib::Client client("127.0.0.1", server.port());
  const auto refused = client.Post("/api/verify/decision",
                                   R"({"clip_id":1,"stage":"retarget_kinematic","decision":"accept","reviewer":"x"})",
                                   "application/json");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403);
  EXPECT_EQ(client.Get("/api/verify/scene/1x")->status, 404);
}

// Two hands: the retarget stage, given a left robot hand, retargets a
// synthetic two-handed carry's reconstruction with both hands in one scene,
// and the verification page draws both robot hands (hiding either one's
// bodies changes the picture).
TEST(VerifyBrowser, ATwoHandTrajectoryShowsBothHands) {
  if (!testing::ChromiumAvailable()) GTEST_SKIP() << "needs Debian's chromium and chromium-driver";
  TempDir dir;
  const auto db_path = ProbedClips(dir, 1, 4, retarget::kRetargetStageName);
  Database db(db_path);
  auto claim = db.ClaimNext("test", {retarget::kRetargetStageName}, 60, 3);
  ASSERT_TRUE(claim.has_value());
  // The clip's reconstruction: a two-handed carry of a cylinder.
  const TriMesh cylinder = synth::MakeCylinder(0.035, 0.12, 16);
  synth::EpisodeSpec spec;
  spec.frames = 30;
  spec.two_hand_task = synth::TwoHandTask::kCarry;
  recon::Reconstruction r = synth::EpisodeReconstruction(synth::ScriptEpisode(spec, cylinder), 30.0);
  const auto recon_dir = db.ArtifactDir(claim->clip_id, recon::kReconStageName);
  std::filesystem::create_directories(recon_dir);
  SaveObj(cylinder, recon_dir / recon::kReconstructionMesh);
  r.object_mesh = recon_dir / recon::kReconstructionMesh;
  recon::WriteReconstruction(r, recon_dir);
  retarget::DynamicRetargetConfig config;
  config.preset = "";
  config.left_hand = "sharpa_left";
  config.robots_dir = (testing::SharedData() / "robots").string();
  config.kinematic.restarts = 1;
  config.sampler.num_samples = 4;
  config.sampler.max_num_iterations = 1;
  config.sampler.horizon = 0.2;
  config.sampler.knot_dt = 0.1;
  config.sampler.ctrl_dt = 0.1;
  config.sampler.threads = 2;
  const StageResult result =
      stages::DynamicRetargetStage(config).Run(db.LoadContext(claim->clip_id, retarget::kRetargetStageName));
  ASSERT_TRUE(result.measurements.contains("left_wrist_error")) << result.measurements.dump();
  ASSERT_TRUE(db.Complete(*claim, "test", "h", result, 0.0));

  ChromeDriver driver(dir / "chromedriver.log");
  review::ReviewServer server(db_path, {.port = 0, .reviewer = "vera"});
  server.Start();
  WebDriverSession session(driver, 1400, 900, kWebGlFlags);
  EXPECT_EQ(OpenVerifyQueue(session, server), 1);
  if (const char* shots = std::getenv("DOASIDO_SHOTS_DIR")) {
    session.Screenshot(std::filesystem::path(shots) / "verify_two_hands.png");
  }
  for (const std::string prefix : {retarget::kLeftPrefix, retarget::kRightPrefix}) {
    const int bodies = session.Execute(
        "return window.doasidoVerify.scene.bodies.filter(b => b.name.startsWith(arguments[0])"
        " && b.geoms.length).length;", Json::array({prefix})).get<int>();
    EXPECT_GT(bodies, 10) << prefix << " hand bodies with geometry";
    SnapshotView(session, "both_" + prefix);
    session.Execute(
        "const s = window.doasidoVerify; s.scene.bodies.forEach((b, i) => {"
        " if (b.name.startsWith(arguments[0])) s.groups[i].visible = false; }); s.render();",
        Json::array({prefix}));
    const int pixels = ChangedPixels(session, "both_" + prefix);
    std::printf("hiding the %s hand changes %d pixels\n", prefix.c_str(), pixels);
    EXPECT_GT(pixels, 200) << prefix;
    session.Execute("window.doasidoVerify.groups.forEach(g => { g.visible = true; }); window.doasidoVerify.render();");
  }
}

}  // namespace
}  // namespace doasido
