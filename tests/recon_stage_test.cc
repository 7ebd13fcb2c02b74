// The recon stage on a rendered synthetic clip: exact bundle -> scale 1 and
// a readable reconstruction; the tracker's poses are used when present;
// verdicts reject a clip without an object or without alignment evidence
// and flag inconsistent scales on re-decision.
#include "stages/recon_stage.h"

#include <cmath>
#include <optional>

#include <gtest/gtest.h>

#include "recon/bundle/bundle.h"
#include "recon/bundle/npy.h"
#include "tests/small_clip.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using doasido::testing::TempDir;

const ClipBundle& Clip() { return testing::SmallClip().bundle; }

ClipContext Context(const TempDir& root, const ClipBundle& b) {
  WriteBundle(b, root / "artifacts/1/bundle");
  ClipContext c;
  c.clip.id = 1;
  c.clip.external_id = "c1";
  c.artifact_dir = root / "artifacts/1/recon";
  return c;
}

TEST(ReconStage, ExactBundleGivesScaleOneAndAReadableReconstruction) {
  TempDir root;
  const ClipContext c = Context(root, Clip());
  const StageResult r = stages::ReconStage().Run(c);
  EXPECT_EQ(r.verdict, Verdict::kPass) << r.reason;
  EXPECT_GT(r.measurements[kMeasureEvidenceShare].get<double>(), 0.9);
  EXPECT_NEAR(r.measurements[kMeasureScaleMedian].get<double>(), 1.0, 0.003);
  EXPECT_EQ(r.measurements[kMeasureGravitySource], kGravityFromBundle);
  EXPECT_EQ(r.measurements[kMeasurePoseSource], "bundle");
  EXPECT_EQ(r.measurements[kMeasureHandObjectDistance].size(), 24u);
  const Reconstruction rec = ReadReconstruction(c.artifact_dir);
  EXPECT_EQ(rec.frames(), 24);
  EXPECT_FALSE(rec.object_mesh.empty());
  EXPECT_EQ(rec.info["object_pose_source"], "bundle");
}

// An object held still in the air, then set down (02_cups' lowered cup):
// the first frames are a resting pose 10 cm up (against the bundle's
// gravity), the rest the clip's own path. The floor goes under the lowest
// the object gets, so no posed frame puts any vertex below it; under the
// in-air resting pose alone the later frames would be 10 cm through it.
TEST(ReconStage, AnObjectSetDownFromTheAirIsNeverBelowTheFloor) {
  TempDir root;
  ClipBundle b = Clip();
  ASSERT_FALSE(b.gravity_up.empty());
  for (int t = 0; t < 6; ++t) {
    b.object_poses[t] = b.object_poses[6];
    b.object_poses[t].t += 0.10 * b.gravity_up[6].normalized();
  }
  const ClipContext c = Context(root, b);
  const StageResult r = stages::ReconStage().Run(c);
  ASSERT_EQ(r.verdict, Verdict::kPass) << r.reason;
  const Reconstruction rec = ReadReconstruction(c.artifact_dir);
  double lowest = 1e9, first = 1e9;
  for (int t = 0; t < rec.frames(); ++t) {
    if (!rec.object_valid[t]) continue;
    for (int v = 0; v < b.object_mesh->num_vertices(); ++v) {
      const double z = (rec.object_poses[t] * Vec3(b.object_mesh->vertices.row(v).transpose())).z();
      lowest = std::min(lowest, z);
      if (t == 0) first = std::min(first, z);
    }
  }
  EXPECT_NEAR(lowest, 0.0, 1e-6);
  EXPECT_GT(first, 0.05);  // the held pose is above the floor, not on it
  EXPECT_GT(rec.info["floor"]["lowest_frame"].get<int>(), 5);
}

// Both hands come through in the same frame: here the left hand is the
// clip's hand track moved 30 cm, so every left joint sits the same 30-cm
// vector (turned by gravity alignment) from its right twin.
TEST(ReconStage, BothHandsGetTheSameFrame) {
  TempDir root;
  ClipBundle b = Clip();
  ASSERT_TRUE(b.hand_right || b.hand_left);
  const HandTrack hand = b.hand_right ? *b.hand_right : *b.hand_left;
  b.hand_right = hand;
  b.hand_left = hand;
  for (auto& j : b.hand_left->joints) j.rowwise() += Eigen::RowVector3d(0.3, 0, 0);
  const ClipContext c = Context(root, b);
  EXPECT_EQ(stages::ReconStage().Run(c).verdict, Verdict::kPass);
  const Reconstruction rec = ReadReconstruction(c.artifact_dir);
  ASSERT_EQ(rec.left_valid, rec.right_valid);
  std::optional<Eigen::RowVector3d> offset;
  for (int t = 0; t < rec.frames(); ++t) {
    if (!rec.right_valid[t]) continue;
    for (int k = 0; k < 21; ++k) {
      const Eigen::RowVector3d d = rec.left_joints[t].row(k) - rec.right_joints[t].row(k);
      if (!offset) offset = d;
      EXPECT_LT((d - *offset).norm(), 1e-9) << "frame " << t << " joint " << k;
    }
  }
  ASSERT_TRUE(offset.has_value());
  EXPECT_NEAR(offset->norm(), 0.3, 1e-9);
}

TEST(ReconStage, UsesTheTrackersPosesWhenPresent) {
  TempDir root;
  const ClipContext c = Context(root, Clip());
  std::vector<double> poses;
  for (const Pose& p : Clip().object_poses) {
    const Vec3 t = 1.25 * p.t;  // the tracker's point-map scale
    for (double v : {t.x(), t.y(), t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()}) poses.push_back(v);
  }
  NpzArchive npz;
  npz["poses"] = MakeArray<double>({Clip().frames, 7}, poses);
  std::filesystem::create_directories(root / "artifacts/1/track");
  WriteNpz(root / "artifacts/1/track" / stages::kTrackPosesFile, npz);
  const StageResult r = stages::ReconStage().Run(c);
  EXPECT_EQ(r.measurements[kMeasurePoseSource], "track");
  EXPECT_NEAR(r.measurements[kMeasureScaleMedian].get<double>(), 1 / 1.25, 0.003);
}

TEST(ReconStage, VerdictsNameTheirReasons) {
  TempDir root;
  ClipBundle no_mesh = Clip();
  no_mesh.object_mesh.reset();
  EXPECT_EQ(stages::ReconStage().Run(Context(root, no_mesh)).reason, stages::kReasonNoObject);

  TempDir root2;
  ClipBundle no_evidence = Clip();
  // New buffers: assigning Mat::zeros would write into the shared fixture.
  for (cv::Mat& m : no_evidence.mask_object) m = cv::Mat(m.size(), CV_8U, cv::Scalar(0));
  const StageResult r = stages::ReconStage().Run(Context(root2, no_evidence));
  EXPECT_EQ(r.verdict, Verdict::kReject);
  EXPECT_EQ(r.reason, stages::kReasonTooFewAlignedFrames);

  TempDir root3;
  const StageResult ok = stages::ReconStage().Run(Context(root3, Clip()));
  ReconStageConfig strict;
  strict.max_scale_spread = 0;
  Json m = ok.measurements;
  m[kMeasureScaleSpread] = 0.01;
  const auto flagged = stages::ReconStage(strict).Redecide(m);
  ASSERT_TRUE(flagged);
  EXPECT_EQ(flagged->verdict, Verdict::kFlag);
  EXPECT_EQ(flagged->reason, stages::kReasonScaleInconsistent);
}

TEST(ReconStage, BadConfigIsRefused) {
  ReconStageConfig c;
  c.min_aligned_fraction = 2;
  EXPECT_THROW(stages::ReconStage{c}, Error);
}

}  // namespace
}  // namespace doasido::recon
