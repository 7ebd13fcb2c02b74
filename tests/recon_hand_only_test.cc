// Hand-only bundles through the reconstruction side: which bundle every
// stage after `bundle` sees (list, command or the hands stage's, with the
// hands stage's hands filling a bundle that has none), the bundle stage's
// record of it, the track stage passing a bundle without object, and recon
// reconstructing the hands alone with gravity from the bundle (exact
// synthetic ground truth) or camera-up recorded as assumed.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error_codes.h"
#include "recon/bundle/bundle.h"
#include "stages/clip_inputs.h"
#include "stages/bundle_stage.h"
#include "stages/recon_stage.h"
#include "recon/reconstruction.h"
#include "stages/track_stage.h"
#include "tests/hand_only_bundle.h"
#include "tests/small_clip.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using doasido::testing::HandOnlyCopy;
using doasido::testing::TempDir;
using doasido::testing::WriteHandsStageBundle;

const ClipBundle& Clip() { return testing::SmallClip().bundle; }

// The clip's exact hand-only bundle with its one hand as the right hand
// (the rendered clip may show either).
ClipBundle Hands() {
  ClipBundle b = HandOnlyCopy(Clip());
  if (!b.hand_right) b.hand_right = b.hand_left;
  b.hand_left.reset();
  return b;
}

ClipContext Context(const TempDir& root, const std::string& stage) {
  ClipContext c;
  c.clip.id = 1;
  c.clip.external_id = "c1";
  c.artifact_dir = root / "artifacts/1" / stage;
  c.video.path = root / "clip.mp4";  // named to a model command, never opened here
  return c;
}

std::filesystem::path HandsDir(const TempDir& root) { return root / "artifacts/1" / kHandsStageFolder; }

ClipBundle WithoutHands(ClipBundle b) {
  b.hand_left.reset();
  b.hand_right.reset();
  b.mask_hand_left.clear();
  b.mask_hand_right.clear();
  return b;
}

// The permanent error `f` throws, as "code field".
std::string PermanentCode(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    if (IsPermanentError(e.code())) return e.code() + " " + e.site().field;
    return "transient " + e.code();
  }
  return "none";
}

TEST(HandOnlyBundle, TheHandsStageBundleIsTheClipsBundleWhenThereIsNoOther) {
  TempDir root;
  const ClipContext c = Context(root, kReconStageName);
  EXPECT_EQ(PermanentCode([&] { stages::LoadClipBundle(c); }), std::string(kErrorNoBundle) + " ");
  WriteHandsStageBundle(Hands(), HandsDir(root), false);
  const stages::ResolvedBundle r = stages::LoadClipBundle(c);
  EXPECT_EQ(r.source, kBundleFromHands);
  EXPECT_EQ(r.hands_source, kBundleFromHands);
  EXPECT_EQ(r.dir, HandsDir(root));
  EXPECT_EQ(r.hands_meta["intrinsics_assumed"], false);
  ASSERT_TRUE(r.bundle.hand_right);
  EXPECT_TRUE(IsHandOnly(r.bundle));
  EXPECT_FALSE(IsHandOnly(Clip()));
}

TEST(HandOnlyBundle, AModelBundleWithoutHandsGetsTheHandsStagesHands) {
  TempDir root;
  WriteBundle(WithoutHands(Clip()), root / "artifacts/1" / kBundleStageName);
  ClipBundle hands = Hands();
  for (auto& j : hands.hand_right->joints) j.array() += 0.01;  // tell them apart
  WriteHandsStageBundle(hands, HandsDir(root), true);
  const stages::ResolvedBundle r = stages::LoadClipBundle(Context(root, kReconStageName));
  EXPECT_EQ(r.source, kBundleFromCommand);
  EXPECT_EQ(r.hands_source, kBundleFromHands);
  ASSERT_TRUE(r.bundle.hand_right);
  EXPECT_TRUE(r.bundle.object_mesh.has_value());
  EXPECT_TRUE(r.bundle.present.count("hand_right"));
  EXPECT_NEAR((r.bundle.hand_right->joints[5] - hands.hand_right->joints[5]).norm(), 0, 1e-12);
  EXPECT_TRUE(r.bundle.producers.contains("hands"));

  // A bundle with its own hands keeps them.
  TempDir root2;
  WriteBundle(Clip(), root2 / "artifacts/1" / kBundleStageName);
  WriteHandsStageBundle(hands, HandsDir(root2), true);
  const stages::ResolvedBundle own = stages::LoadClipBundle(Context(root2, kReconStageName));
  EXPECT_EQ(own.hands_source, "bundle");
  const auto& truth = Clip().hand_right ? Clip().hand_right : Clip().hand_left;
  const auto& kept = Clip().hand_right ? own.bundle.hand_right : own.bundle.hand_left;
  ASSERT_TRUE(kept);
  EXPECT_NEAR((kept->joints[5] - truth->joints[5]).norm(), 0, 1e-12);
}

TEST(HandOnlyBundle, AListBundleOfAnotherLengthThanTheHandsIsRefusedNamingBoth) {
  TempDir root;
  WriteBundle(WithoutHands(Clip()), root / "listed");
  ClipBundle shorter = Hands();
  shorter.frames = 10;
  shorter.hand_right->valid.resize(10);
  shorter.hand_right->joints.resize(10);
  if (shorter.hand_left) {
    shorter.hand_left->valid.resize(10);
    shorter.hand_left->joints.resize(10);
  }
  shorter.gravity_up.resize(10);
  WriteHandsStageBundle(shorter, HandsDir(root), false);
  ClipContext c = Context(root, kReconStageName);
  c.clip.metadata["bundle"] = (root / "listed").string();
  EXPECT_EQ(PermanentCode([&] { stages::LoadClipBundle(c); }), "bad_bundle frames");
}

TEST(HandOnlyBundle, TheBundleStageRecordsWhereTheBundleAndHandsCameFrom) {
  TempDir root;
  WriteHandsStageBundle(Hands(), HandsDir(root), false);
  const StageResult r = stages::BundleStage().Run(Context(root, kBundleStageName));
  EXPECT_EQ(r.measurements["source"], kBundleFromHands);
  EXPECT_EQ(r.measurements["hands_source"], kBundleFromHands);
  EXPECT_TRUE(r.measurements["producers"].contains("hands"));
  EXPECT_EQ(r.measurements["frames"], Clip().frames);

  // A command that exits 0 writing nothing has no output for the clip:
  // the hands stage's bundle stands in. One that writes files but no
  // meta.json wrote a broken bundle.
  stages::BundleStageConfig silent;
  silent.command = "true";
  EXPECT_EQ(stages::BundleStage(silent).Run(Context(root, kBundleStageName)).measurements["source"], kBundleFromHands);
  stages::BundleStageConfig broken;
  broken.command = "touch {output}/hands.npz";
  EXPECT_EQ(PermanentCode([&] { stages::BundleStage(broken).Run(Context(root, kBundleStageName)); }),
            "bad_bundle ");
}

TEST(HandOnlyBundle, TrackPassesABundleWithoutObjectEvenWithAServer) {
  TempDir root;
  WriteHandsStageBundle(Hands(), HandsDir(root), false);
  stages::TrackStageConfig config;
  config.server = "false";  // would fail if it were started
  const StageResult r = stages::TrackStage(config).Run(Context(root, stages::kTrackStageName));
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.measurements[stages::kMeasureTrackSource], stages::kTrackSourceNoObject);
  EXPECT_FALSE(std::filesystem::exists(root / "artifacts/1/track" / stages::kTrackPosesFile));
}

// Height differences in the world frame are the camera-frame differences
// along the up vector: checked on every pair (wrist, joint) of every frame.
double WorstHeightError(const Reconstruction& rec, const HandTrack& camera, const Vec3& up) {
  double worst = 0;
  for (int t = 0; t < rec.frames(); ++t) {
    if (!rec.right_valid[t]) continue;
    for (int j = 1; j < 21; ++j) {
      const double world = rec.right_joints[t](j, 2) - rec.right_joints[t](0, 2);
      const double cam = up.dot((camera.joints[t].row(j) - camera.joints[t].row(0)).transpose());
      worst = std::max(worst, std::abs(world - cam));
    }
  }
  return worst;
}

double LowestJoint(const Reconstruction& rec) {
  double lowest = 1e30;
  for (int t = 0; t < rec.frames(); ++t) {
    if (rec.right_valid[t]) lowest = std::min(lowest, rec.right_joints[t].col(2).minCoeff());
    if (!rec.left_valid.empty() && rec.left_valid[t]) lowest = std::min(lowest, rec.left_joints[t].col(2).minCoeff());
  }
  return lowest;
}

// recon on `hands` written as the hands stage's bundle.
StageResult ReconHands(const TempDir& root, const ClipBundle& hands, bool intrinsics_assumed) {
  WriteHandsStageBundle(hands, HandsDir(root), intrinsics_assumed);
  return stages::ReconStage().Run(Context(root, kReconStageName));
}

TEST(HandOnlyRecon, HandsAloneWithTheBundlesGravity) {
  TempDir root;
  const ClipBundle hands = Hands();
  ASSERT_FALSE(hands.gravity_up.empty());
  const StageResult r = ReconHands(root, hands, true);
  const ClipContext c = Context(root, kReconStageName);
  EXPECT_EQ(r.verdict, Verdict::kPass) << r.reason;
  EXPECT_EQ(r.measurements[kMeasureObject], kObjectNone);
  EXPECT_EQ(r.measurements[kMeasureGravitySource], kGravityFromBundle);
  EXPECT_EQ(r.measurements[kMeasureGravityAssumed], false);
  EXPECT_EQ(r.measurements[kMeasureIntrinsicsAssumed], true);
  EXPECT_EQ(r.measurements[kMeasureBundleSource], kBundleFromHands);
  const Reconstruction rec = ReadReconstruction(c.artifact_dir);
  EXPECT_TRUE(rec.object_mesh.empty());
  EXPECT_FALSE(std::filesystem::exists(c.artifact_dir / kReconstructionMesh));
  EXPECT_TRUE(std::none_of(rec.object_valid.begin(), rec.object_valid.end(), [](bool v) { return v; }));
  EXPECT_EQ(rec.info["object"], kObjectNone);
  Vec3 up = Vec3::Zero();
  for (const Vec3& g : hands.gravity_up) up += g;
  EXPECT_LT(WorstHeightError(rec, *hands.hand_right, up.normalized()), 1e-9);
  EXPECT_NEAR(LowestJoint(rec), kHandOnlyFloorMargin, 1e-9);
}

TEST(HandOnlyRecon, WithoutGravityCameraUpIsAssumedAndRecorded) {
  TempDir root;
  ClipBundle hands = Hands();
  hands.gravity_up.clear();
  const StageResult r = ReconHands(root, hands, false);
  const ClipContext c = Context(root, kReconStageName);
  EXPECT_EQ(r.verdict, Verdict::kPass) << r.reason;
  EXPECT_EQ(r.measurements[kMeasureGravitySource], kGravityFromCamera);
  EXPECT_EQ(r.measurements[kMeasureGravityAssumed], true);
  const Reconstruction rec = ReadReconstruction(c.artifact_dir);
  EXPECT_EQ(rec.info["gravity"]["assumed"], true);
  EXPECT_LT(WorstHeightError(rec, *hands.hand_right, Vec3(0, -1, 0)), 1e-9);
}

TEST(HandOnlyRecon, NoFrameWithAHandIsRejected) {
  TempDir root;
  ClipBundle hands = Hands();
  for (auto* h : {&hands.hand_left, &hands.hand_right}) {
    if (*h) std::fill((*h)->valid.begin(), (*h)->valid.end(), false);
  }
  const StageResult r = ReconHands(root, hands, false);
  EXPECT_EQ(r.verdict, Verdict::kReject);
  EXPECT_EQ(r.reason, stages::kReasonNoHands);
}

}  // namespace
}  // namespace doasido::recon
