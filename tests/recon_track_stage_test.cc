// The track stage on a rendered synthetic clip: the bundle's pose
// candidates as the model, guidance from its point tracks, clustering by
// silhouette -> poses near the true ones, which recon then uses; a velocity
// server through the stage; a bundle without a model is passed on.
#include "stages/track_stage.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include <opencv2/videoio.hpp>

#include "eval/mixture_file.h"
#include "recon/bundle/bundle.h"
#include "recon/bundle/npy.h"
#include "stages/recon_stage.h"
#include "recon/track/velocity_server.h"
#include "synth/tracking_scene.h"
#include "tests/small_clip.h"
#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using ::testing::HasSubstr;
using doasido::testing::TempDir;

const ClipBundle& Clip() { return testing::SmallClip().bundle; }

ClipContext Context(const TempDir& root, const ClipBundle& b, const std::string& stage) {
  WriteBundle(b, root / "artifacts/1/bundle");
  ClipContext c;
  c.clip.id = 1;
  c.clip.external_id = "c1";
  c.artifact_dir = root / "artifacts/1" / stage;
  return c;
}

TEST(TrackStage, CandidatesTracksAndSilhouettesGiveTheTruePoses) {
  TempDir root;
  ASSERT_FALSE(Clip().candidates.empty());
  ASSERT_TRUE(Clip().tracks.has_value());
  const StageResult r = stages::TrackStage().Run(Context(root, Clip(), stages::kTrackStageName));
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.measurements[stages::kMeasureTrackSource], "candidates");
  EXPECT_EQ(r.measurements[stages::kMeasureGuidanceSource], "tracks");
  EXPECT_EQ(r.measurements[stages::kMeasureTrackedFrames], 24);
  std::vector<Pose> poses;
  std::vector<bool> valid;
  stages::ReadTrackPoses(root / "artifacts/1/track" / stages::kTrackPosesFile, 24, poses, valid);
  // The clean bundle's poses are the truth; its candidates scatter around
  // it with flips and outliers.
  std::vector<double> t_err, r_err;
  for (int k = 0; k < 24; ++k) {
    ASSERT_TRUE(valid[k]);
    t_err.push_back((poses[k].t - Clip().object_poses[k].t).norm());
    r_err.push_back(RotationAngle(poses[k].q, Clip().object_poses[k].q));
  }
  std::sort(t_err.begin(), t_err.end());
  std::sort(r_err.begin(), r_err.end());
  EXPECT_LT(t_err[12], 0.01) << "median translation error";
  EXPECT_LT(r_err[12], 0.15) << "median rotation error";
  EXPECT_LT(r_err[21], 1.0) << "more than 2 frames flipped";

  const StageResult recon = stages::ReconStage().Run(Context(root, Clip(), kReconStageName));
  EXPECT_EQ(recon.measurements[kMeasurePoseSource], "track");
}

// Without point tracks, OpenCV's Lucas-Kanade on the clip's video guides
// the sampling; its turns agree with the tracks' (both measure the same
// motion) and the poses stay near the truth.
TEST(TrackStage, LucasKanadeOnTheVideoWhenTheBundleHasNoTracks) {
  TempDir root;
  const synth::RenderedClip& rendered = testing::SmallClip();
  const auto video = root / "clip.avi";
  cv::VideoWriter writer(video.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'),
                         30, rendered.bgr[0].size());
  ASSERT_TRUE(writer.isOpened());
  for (const cv::Mat& f : rendered.bgr) writer.write(f);
  writer.release();
  ClipBundle no_tracks = rendered.bundle;
  no_tracks.tracks.reset();
  ClipContext c = Context(root, no_tracks, stages::kTrackStageName);
  c.video.path = video.string();
  const StageResult r = stages::TrackStage().Run(c);
  EXPECT_EQ(r.measurements[stages::kMeasureGuidanceSource], "lucas_kanade");
  const double lk_alpha = r.measurements[stages::kMeasureMeanPoseGuidance].get<double>();
  auto near_truth = [&] {
    std::vector<Pose> poses;
    std::vector<bool> valid;
    stages::ReadTrackPoses(c.artifact_dir / stages::kTrackPosesFile, 24, poses, valid);
    int near = 0;
    for (int k = 0; k < 24; ++k) near += (poses[k].t - rendered.bundle.object_poses[k].t).norm() < 0.01;
    return near;
  };
  const int lk_near = near_truth();
  const StageResult with_tracks = stages::TrackStage().Run(Context(root, rendered.bundle, stages::kTrackStageName));
  EXPECT_NEAR(lk_alpha, with_tracks.measurements[stages::kMeasureMeanPoseGuidance].get<double>(), 0.1);
  EXPECT_GE(lk_near, near_truth() - 3) << "Lucas-Kanade guidance far worse than the tracks'";
  EXPECT_GE(lk_near, 12);
}

TEST(TrackStage, AVelocityServerIsTheModelWhenConfigured) {
  TempDir root;
  synth::TrackingSceneOptions o;
  o.frames = 24;
  const synth::TrackingScene scene = synth::MakeTrackingScene(4, o);
  const ClipContext c = Context(root, Clip(), stages::kTrackStageName);
  WriteMixtureNpz(root / "artifacts/1/bundle/flow_modes.npz", *scene.model);
  stages::TrackStageConfig config;
  config.server = std::string("/usr/bin/python3 ") + DOASIDO_SOURCE_DIR +
                  "/tools/velocity_server.py {bundle}/flow_modes.npz";
  config.selection.method = kSelectLikelihood;
  const StageResult r = stages::TrackStage(config).Run(c);
  EXPECT_EQ(r.measurements[stages::kMeasureTrackSource], "server");
  std::vector<Pose> poses;
  std::vector<bool> valid;
  stages::ReadTrackPoses(c.artifact_dir / stages::kTrackPosesFile, 24, poses, valid);
  // The scene's model puts its heaviest mode near its own truth.
  int near = 0;
  for (int k = 0; k < 24; ++k) near += (poses[k].t - scene.truth[k].t).norm() < 0.02;
  EXPECT_GE(near, 22);

  config.server += " --misbehave die";
  try {
    stages::TrackStage(config).Run(c);
    ADD_FAILURE() << "a dying server went unnoticed";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), kServerDied) << e.what();
    EXPECT_THAT(e.what(), HasSubstr("track.log"));
  }
}

TEST(TrackStage, ABundleWithoutAModelIsPassedOn) {
  TempDir root;
  ClipBundle plain = Clip();
  plain.candidates.clear();
  const ClipContext c = Context(root, plain, stages::kTrackStageName);
  const StageResult r = stages::TrackStage().Run(c);
  EXPECT_EQ(r.verdict, Verdict::kPass);
  EXPECT_EQ(r.measurements[stages::kMeasureTrackSource], "none");
  EXPECT_FALSE(std::filesystem::exists(c.artifact_dir / stages::kTrackPosesFile));
  EXPECT_EQ(stages::ReconStage().Run(Context(root, plain, kReconStageName)).measurements[kMeasurePoseSource],
            "bundle");
}

}  // namespace
}  // namespace doasido::recon
