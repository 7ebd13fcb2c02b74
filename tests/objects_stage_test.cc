// The objects stage on the synthetic world: a scripted grasp of the
// built-in mug (eval/mug_mesh.h) and of a plain cylinder, filmed by a known
// camera. The box keypoints are the exact projections of the object's
// bounding box (what a perfect box-landmark model would give; the models
// themselves are tested on renders by the model half), the hands stage's
// output is the synthetic world's exact hands. The stage's object bundle
// must be read by recon's bundle reader, merged by the bundle stage into
// the hand-only bundle, and reconstructed by recon with the object.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "eval/mug_mesh.h"
#include "objects/box_lifting.h"
#include "objects/object_categories.h"
#include "objects/object_detection.h"
#include "objects/objects_config.h"
#include "recon/bundle/bundle.h"
#include "recon/reconstruction.h"
#include "stages/bundle_stage.h"
#include "stages/objects_stage.h"
#include "stages/recon_stage.h"
#include "synth/episode.h"
#include "synth/objects.h"
#include "tests/test_util.h"

namespace doasido::objects {
namespace {

using doasido::testing::TempDir;

constexpr int kWidth = 640, kHeight = 480;
constexpr double kFps = 30;

struct Scene {
  std::vector<Pose> box;        // box frame -> camera, per frame
  Vec3 box_size;                // the object's bounding box in the box frame's axes
  std::vector<Vec3> wrist;      // camera frame
  recon::ClipBundle hands;      // the hands stage's bundle: exact right hand
  Json observations;            // the box keypoints, objects.json format
};

Mat3 K() {
  Mat3 k;
  k << 560, 0, 319.5, 0, 560, 239.5, 0, 0, 1;
  return k;
}

// World (+z up) -> camera, the camera at `eye` looking at `target`.
Pose WorldToCamera(const Vec3& eye, const Vec3& target) {
  const Vec3 f = (target - eye).normalized();
  const Vec3 x = f.cross(Vec3::UnitZ()).normalized();
  const Vec3 y = f.cross(x);
  Mat3 R;
  R << x.transpose(), y.transpose(), f.transpose();
  return {Quat(R), -(R * eye)};
}

// The episode seen by the camera; the object's box: its mesh's bounding
// box, the box's y along the object's up (+z), its z along -y.
Scene MakeScene(const TriMesh& mesh, synth::GraspType grasp) {
  synth::EpisodeSpec spec;
  spec.frames = 60;
  spec.grasp = grasp;
  const synth::Episode episode = synth::ScriptEpisode(spec, mesh);
  const Pose camera = WorldToCamera(Vec3(0.05, -0.40, 0.30), Vec3(0, 0.05, 0.06));
  const Vec3 lo = mesh.vertices.colwise().minCoeff().transpose();
  const Vec3 hi = mesh.vertices.colwise().maxCoeff().transpose();
  Mat3 box_axes;
  box_axes << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // columns: object x, z, -y
  const Pose box_in_object{Quat(box_axes), (lo + hi) / 2};
  Scene s;
  s.box_size = Vec3(hi.x() - lo.x(), hi.z() - lo.z(), hi.y() - lo.y());
  s.hands.width = kWidth;
  s.hands.height = kHeight;
  s.hands.frames = spec.frames;
  s.hands.fps = kFps;
  s.hands.K = {K()};
  s.hands.producers = {{"hands", "synthetic world"}};
  recon::HandTrack right;
  Json frames = Json::array();
  for (int t = 0; t < spec.frames; ++t) {
    const synth::EpisodeFrame& f = episode.frames[t];
    s.box.push_back(camera * f.object_pose * box_in_object);
    const auto& hand = f.hands[static_cast<int>(synth::Side::kRight)];
    recon::Joints21 joints = recon::Joints21::Constant(std::nan(""));
    if (hand) {
      const synth::HandJoints world = synth::HandJointPositions(*hand, synth::Side::kRight);
      for (int j = 0; j < 21; ++j) joints.row(j) = (camera * Vec3(world.row(j).transpose())).transpose();
    }
    right.valid.push_back(hand.has_value());
    right.joints.push_back(joints);
    s.wrist.push_back(joints.row(0).transpose());
    Json keypoints = Json::array();
    // The record's pixels start at the top-left pixel's corner, K's at its centre.
    for (const Vec2& p : ProjectBox(s.box.back(), s.box_size, K())) {
      keypoints.push_back({p.x() + 0.5, p.y() + 0.5});
    }
    frames.push_back({{"frame", t},
                      {"objects", {{{"category", kCategoryCup}, {"score", 0.99}, {"track", 0},
                                    {"keypoints_2d", keypoints}}}}});
  }
  s.hands.hand_right = right;
  s.observations = {{"first_frame", 0}, {"frames", frames}};
  return s;
}

ClipContext Context(const TempDir& root, const std::string& stage) {
  ClipContext c;
  c.clip.id = 1;
  c.clip.external_id = "c1";
  c.artifact_dir = root / ("artifacts/1/" + stage);
  c.video.path = root / "clip.mp4";  // its stem names the observations file; never opened
  return c;
}

// The stage's config: the synthetic hand's fingertip joints lie a capsule
// radius (8.2-11 mm, HandShape::radius) from the skin that touches.
ObjectsConfig Config(const TempDir& root) {
  ObjectsConfig c;
  c.observations_dir = (root / "observations").string();
  c.fingertip_offset_m = 0.0095;
  return c;
}

struct Errors {
  double size_rel = 0;       // largest relative error of the three extents
  double centre_p90_m = 0;   // 90th percentile of the box centre's error
  double axis_p90_deg = 0;   // of the box's y axis (round objects: the axis)
};

double P90(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() * 9 / 10];
}

// Runs the objects stage on `scene` and measures its object against the truth.
// `carry_max_frames` >= 0 sets [objects.carry] max_frames.
Errors RunObjects(const TempDir& root, const Scene& scene, StageResult& result,
                  int carry_max_frames = -1) {
  recon::WriteBundle(scene.hands, root / "artifacts/1/hands");
  testing::WriteFile(root / "artifacts/1/hands/keypoints.json", "{\"first_frame\": 0}\n");
  testing::WriteFile(root / "observations/clip.json", scene.observations.dump());
  ObjectsConfig config = Config(root);
  if (carry_max_frames >= 0) config.carry.max_frames = carry_max_frames;
  stages::ObjectsStage stage(config);
  result = stage.Run(Context(root, "objects"));
  const recon::ClipBundle b = recon::ReadBundle(root / "artifacts/1/objects");
  EXPECT_TRUE(b.object_mesh.has_value());
  EXPECT_EQ(static_cast<int>(b.object_poses.size()), scene.hands.frames);
  const Json& m = result.measurements;
  const Vec3 size(m[stages::kMeasureObjectSize][0], m[stages::kMeasureObjectSize][1],
                  m[stages::kMeasureObjectSize][2]);
  Errors e;
  // A cup is a cylinder: its diameter against the mean of the box's widths.
  const double diameter = (scene.box_size.x() + scene.box_size.z()) / 2;
  const Vec3 truth(diameter, scene.box_size.y(), diameter);
  e.size_rel = (size.array() / truth.array() - 1).abs().maxCoeff();
  std::vector<double> centre, axis;
  for (int t = 0; t < scene.hands.frames; ++t) {
    centre.push_back((b.object_poses[t].t - scene.box[t].t).norm());
    const double c = b.object_poses[t].R().col(1).dot(scene.box[t].R().col(1));
    axis.push_back(std::acos(std::min(1.0, c)) * 180 / M_PI);
  }
  e.centre_p90_m = P90(centre);
  e.axis_p90_deg = P90(axis);
  return e;
}

TEST(ObjectsStage, ACylinderHeldByTheHandGetsItsSizeAndPoseFromTheFingertips) {
  TempDir root;
  const Scene scene = MakeScene(synth::MakeCylinder(0.035, 0.10, 48), synth::GraspType::kPinch);
  StageResult result;
  const Errors e = RunObjects(root, scene, result);
  EXPECT_EQ(result.verdict, Verdict::kPass);
  EXPECT_EQ(result.reason, "");
  EXPECT_EQ(result.measurements[stages::kMeasureScaleSource], kScaleFromHand);
  EXPECT_FALSE(result.measurements[stages::kMeasureScaleAssumed].get<bool>());
  // Measured: see docs/objects.md "Measured"; the bounds hold them with margin.
  std::printf("cylinder: size %.4f, centre p90 %.4f m, axis p90 %.3f deg, contact frames %d, %.3f s\n",
              e.size_rel, e.centre_p90_m, e.axis_p90_deg,
              result.measurements[stages::kMeasureContactFrames].get<int>(),
              result.measurements["seconds"].get<double>());
  EXPECT_LT(e.size_rel, 0.05);
  EXPECT_LT(e.centre_p90_m, 0.01);
  EXPECT_LT(e.axis_p90_deg, 1.0);
}

TEST(ObjectsStage, TheMugGoesThroughTheBundleStageIntoRecon) {
  TempDir root;
  const Scene scene = MakeScene(retarget::MakeMug(), synth::GraspType::kWrap);
  StageResult result;
  const Errors e = RunObjects(root, scene, result);
  std::printf("mug: size %.4f, centre p90 %.4f m, axis p90 %.3f deg, scale %s\n", e.size_rel,
              e.centre_p90_m, e.axis_p90_deg,
              result.measurements[stages::kMeasureScaleSource].get<std::string>().c_str());
  // Measured 1.7 cm and 0.09 degrees: the handle widens the box on one
  // side, so the cylinder (the mean width across) is wider than the body the
  // fingertips touch, and its size, hence its depth, comes out 2.6 % off.
  EXPECT_LT(e.centre_p90_m, 0.025);
  EXPECT_LT(e.axis_p90_deg, 1.0);

  const StageResult bundle = stages::BundleStage().Run(Context(root, "bundle"));
  EXPECT_EQ(bundle.measurements["source"], recon::kBundleFromHands);
  EXPECT_EQ(bundle.measurements["object_source"], recon::kObjectsStageFolder);

  const StageResult reconstructed = stages::ReconStage().Run(Context(root, "recon"));
  ASSERT_EQ(reconstructed.verdict, Verdict::kPass) << reconstructed.reason;
  EXPECT_EQ(reconstructed.measurements[recon::kMeasureAlignedFrames], scene.hands.frames);
  const recon::Reconstruction r = recon::ReadReconstruction(root / "artifacts/1/recon");
  ASSERT_EQ(r.frames(), scene.hands.frames);
  // Recon turns the camera frame to gravity's and moves the floor: the
  // distance from the wrist to the object's centre is kept, frame by frame.
  std::vector<double> error;
  for (int t = 0; t < r.frames(); ++t) {
    ASSERT_TRUE(r.object_valid[t]);
    if (!r.right_valid[t]) continue;
    const double got = (r.object_poses[t].t - Vec3(r.right_joints[t].row(0).transpose())).norm();
    const double want = (scene.box[t].t - scene.wrist[t]).norm();
    error.push_back(std::abs(got - want));
  }
  std::printf("mug through recon: wrist to object centre, error p90 %.4f m\n", P90(error));
  EXPECT_LT(P90(error), 0.025);  // the centre's error above
}

TEST(ObjectsStage, NoKnownObjectLeavesTheClipHandOnly) {
  TempDir root;
  Scene scene = MakeScene(synth::MakeCylinder(0.035, 0.10, 16), synth::GraspType::kPinch);
  for (Json& f : scene.observations["frames"]) f["objects"][0]["category"] = "teapot";
  StageResult result;
  recon::WriteBundle(scene.hands, root / "artifacts/1/hands");
  testing::WriteFile(root / "observations/clip.json", scene.observations.dump());
  result = stages::ObjectsStage(Config(root)).Run(Context(root, "objects"));
  EXPECT_EQ(result.verdict, Verdict::kPass);
  EXPECT_EQ(result.reason, stages::kReasonNoKnownObject);
  EXPECT_EQ(result.measurements[stages::kMeasureUnknownCategories], Json::array({"teapot"}));
  EXPECT_FALSE(std::filesystem::exists(root / "artifacts/1/objects/meta.json"));
  const StageResult bundle = stages::BundleStage().Run(Context(root, "bundle"));
  EXPECT_EQ(bundle.measurements["object_source"], "none");
}

TEST(ObjectsStage, WithoutTheHandTheCategoryPriorSetsTheSizeAndSaysSo) {
  TempDir root;
  Scene scene = MakeScene(synth::MakeCylinder(0.035, 0.10, 48), synth::GraspType::kPinch);
  scene.hands.hand_right->valid.assign(scene.hands.frames, false);
  for (auto& j : scene.hands.hand_right->joints) j.setConstant(std::nan(""));
  StageResult result;
  RunObjects(root, scene, result);
  EXPECT_EQ(result.measurements[stages::kMeasureScaleSource], kScaleFromPrior);
  EXPECT_TRUE(result.measurements[stages::kMeasureScaleAssumed].get<bool>());
  // The prior's geometric mean (an 11 oz mug) is the object's.
  const Json& s = result.measurements[stages::kMeasureObjectSize];
  const double g = std::cbrt(s[0].get<double>() * s[1].get<double>() * s[2].get<double>());
  EXPECT_NEAR(g, CharacteristicSize(FindCategory(kCategoryCup)->size_m), 1e-9);
  const Json objects = Json::parse(testing::ReadFile(root / "artifacts/1/objects/objects.json"));
  EXPECT_TRUE(objects["tracks"][0]["scale_assumed"].get<bool>());
}

TEST(ObjectsStage, MissingFramesAreFilledAndMarked) {
  TempDir root;
  Scene scene = MakeScene(synth::MakeCylinder(0.035, 0.10, 48), synth::GraspType::kPinch);
  for (int t = 20; t < 26; ++t) scene.observations["frames"][t]["objects"] = Json::array();
  StageResult result;
  const Errors e = RunObjects(root, scene, result);
  EXPECT_EQ(result.measurements[stages::kMeasureFilledFrames], 6);
  const Json objects = Json::parse(testing::ReadFile(root / "artifacts/1/objects/objects.json"));
  EXPECT_EQ(objects["tracks"][0]["filled_frames"], Json::array({20, 21, 22, 23, 24, 25}));
  EXPECT_TRUE(objects["frames"][22]["objects"][0]["filled"].get<bool>());
  EXPECT_TRUE(objects["frames"][22]["objects"][0]["keypoints_2d"].is_null());
  EXPECT_LT(e.centre_p90_m, 0.01);
}

// The object carried by the hand (moving, its true centre over 2 cm from
// where it started): after 3 frames seen in the hand, no keypoints for the
// rest of the carry, as the box-landmark model lost the cup lifted on 02_cups
// 286-291. The hand carries it there: centre within 1 cm of the truth,
// where without the carry it stays where it was last seen.
TEST(ObjectsStage, AHeldObjectIsCarriedByItsHandWhereTheModelLosesIt) {
  Scene scene = MakeScene(synth::MakeCylinder(0.035, 0.10, 48), synth::GraspType::kPinch);
  std::vector<int> lifted;
  // Moving frames: the hand carries it (a placed object rests).
  for (int t = 1; t < scene.hands.frames; ++t) {
    const bool moving = (scene.box[t].t - scene.box[t - 1].t).norm() > 1e-4;
    if (moving && (scene.box[t].t - scene.box[0].t).norm() > 0.02 &&
        scene.hands.hand_right->valid[t] && (lifted.empty() || lifted.back() == t - 1)) {
      lifted.push_back(t);
    }
  }
  ASSERT_GE(lifted.size(), 13u);
  const std::vector<int> wrong(lifted.begin() + 3, lifted.end());
  for (int t : wrong) scene.observations["frames"][t]["objects"] = Json::array();
  const auto error_on_wrong = [&](const TempDir& root) {
    const recon::ClipBundle b = recon::ReadBundle(root / "artifacts/1/objects");
    double worst = 0;
    for (int t : wrong) worst = std::max(worst, (b.object_poses[t].t - scene.box[t].t).norm());
    return worst;
  };
  TempDir carried_root, smoothed_root;
  StageResult carried, smoothed;
  RunObjects(carried_root, scene, carried);
  RunObjects(smoothed_root, scene, smoothed, 0);
  const double carried_error = error_on_wrong(carried_root);
  const double smoothed_error = error_on_wrong(smoothed_root);
  std::printf("frames lost while held: worst centre error %.4f m carried, %.4f m without\n",
              carried_error, smoothed_error);
  EXPECT_LT(carried_error, 0.01);
  EXPECT_GT(smoothed_error, 0.05);
  EXPECT_GE(carried.measurements[stages::kMeasureCarriedFrames].get<int>(), static_cast<int>(wrong.size()));
  EXPECT_EQ(smoothed.measurements[stages::kMeasureCarriedFrames].get<int>(), 0);
}

TEST(ObjectObservations, TheFileNamesItsFieldWhenWrong) {
  Json j = {{"frames", {{{"frame", 3}, {"objects", {{{"category", "cup"}, {"score", 0.9}, {"track", 0},
                                                     {"keypoints_2d", {{1, 2}}}}}}}}}};
  try {
    ObservationsFromJson(j, {.first_frame = 0, .frames = 10}, "obs.json");
    FAIL() << "accepted 1 keypoint";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_observations");
    EXPECT_EQ(e.site().field, "keypoints_2d");
    EXPECT_EQ(e.site().file, "obs.json");
  }
  // Frames are the video's, shifted to the span's.
  j["frames"][0]["objects"][0]["keypoints_2d"] = Json::array();
  for (int i = 0; i < 9; ++i) j["frames"][0]["objects"][0]["keypoints_2d"].push_back({i, i});
  EXPECT_EQ(ObservationsFromJson(j, {.first_frame = 2, .frames = 10}, "f").at(0).frame, 1);
  EXPECT_TRUE(ObservationsFromJson(j, {.first_frame = 4, .frames = 10}, "f").empty());
}

}  // namespace
}  // namespace doasido::objects
