// Keypoint accuracy against labels (hands/hand_labels.h) on a synthetic
// hand whose labels are the exact projections of its true joints: the
// fit, the models' noisy keypoints, a shifted prediction, a swapped side,
// a missed hand; and the label file's reader.
#include <gtest/gtest.h>

#include "hands/hand_labels.h"
#include "hands/hand_reconstruction.h"
#include "testing/synthetic_hand_track.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

const std::vector<Joints>& DexRows() {
  static const auto rows = testing::ReadDexKeypoints(
      (testing::SharedData() / "retarget/human_hand_keypoints_right.csv").string());
  return rows;
}

LabelledFrame ExactLabels(const testing::SyntheticHand& h, int f) {
  LabelledFrame l;
  l.frame = f;
  LabelledHand hand;
  hand.side = Side::kRight;
  for (int j = 0; j < kJoints; ++j) {
    const Vec3 p = h.K * h.truth[f][j];
    hand.uv[j] = {p.x() / p.z(), p.y() / p.z()};
    hand.visible[j] = true;
  }
  l.hands.push_back(hand);
  return l;
}

PredictedHand Predicted(const std::array<Eigen::Vector2d, kJoints>& uv, Side side = Side::kRight) {
  return {.side = side, .uv = uv};
}

TEST(HandsPck, ExactLabelsScoreTheFitTheModelsAndWrongPredictions) {
  const auto h = testing::MakeSyntheticHand(DexRows(), 40, 50, 1.5, 0.003, 0.9, 31);
  std::vector<FrameObservations> frames;
  for (const auto& o : h.seen) frames.push_back({o});
  const auto tracks = BuildTracks(frames, TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  FitConfig c;
  c.size_prior = "model";
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, c);
  const Camera cam = Camera::FromK(h.K, 0, 0);
  PckScore models, fitted, shifted, swapped, missed;
  for (int f = 0; f < 40; ++f) {
    const LabelledFrame labels = ExactLabels(h, f);
    // The labels themselves score 1.
    const PckScore self = ScoreFrame(labels, {Predicted(labels.hands[0].uv)});
    EXPECT_EQ(self.within_01, kJoints);
    models.Add(ScoreFrame(labels, {Predicted(h.seen[f].uv)}));
    std::array<Eigen::Vector2d, kJoints> uv, moved;
    double lo = 1e9, hi = -1e9, lo_y = 1e9, hi_y = -1e9;
    for (int j = 0; j < kJoints; ++j) {
      uv[j] = cam.Project(fit.joints[f][j]);
      lo = std::min(lo, labels.hands[0].uv[j].x());
      hi = std::max(hi, labels.hands[0].uv[j].x());
      lo_y = std::min(lo_y, labels.hands[0].uv[j].y());
      hi_y = std::max(hi_y, labels.hands[0].uv[j].y());
    }
    const double box = std::max(hi - lo, hi_y - lo_y);
    for (int j = 0; j < kJoints; ++j)
      moved[j] = labels.hands[0].uv[j] + Eigen::Vector2d(0.15 * box, 0);
    fitted.Add(ScoreFrame(labels, {Predicted(uv)}));
    shifted.Add(ScoreFrame(labels, {Predicted(moved)}));
    swapped.Add(ScoreFrame(labels, {Predicted(uv, Side::kLeft)}));
    missed.Add(ScoreFrame(labels, {}));
  }
  std::printf("PCK@0.1 / @0.2: models %.3f / %.3f, fit %.3f / %.3f\n", models.Pck01(),
              models.Pck02(), fitted.Pck01(), fitted.Pck02());
  EXPECT_EQ(models.keypoints, 40 * kJoints);
  EXPECT_EQ(models.Pck02(), 1.0);  // 1.5 px noise on a hand of ~100-200 px
  EXPECT_GT(models.Pck01(), 0.95);
  EXPECT_EQ(fitted.Pck02(), 1.0);
  EXPECT_GT(fitted.Pck01(), 0.95);
  EXPECT_EQ(fitted.swaps, 0);
  EXPECT_EQ(shifted.Pck01(), 0.0);
  EXPECT_EQ(shifted.Pck02(), 1.0);
  EXPECT_EQ(swapped.swaps, 40);
  EXPECT_EQ(missed.missed, 40);
  EXPECT_EQ(missed.Pck02(), 0.0);
}

TEST(HandsPck, LabelFilesAreReadAndBadOnesNamed) {
  testing::TempDir tmp;
  Json kp = Json::array();
  for (int j = 0; j < kJoints; ++j) kp.push_back({10.0 * j, 5.0});
  const Json file = {
      {"video", "videos/eyeliner.avi"},
      {"labeller", "a person"},
      {"frames", {{{"frame", 3}, {"hands", {{{"side", "left"}, {"keypoints_2d", kp}}}}}}}};
  testing::WriteFile(tmp.path() / "eyeliner.json", file.dump());
  const HandLabels l = ReadHandLabels(tmp.path() / "eyeliner.json");
  EXPECT_EQ(l.video, "videos/eyeliner.avi");
  ASSERT_EQ(l.frames.size(), 1u);
  EXPECT_EQ(l.frames[0].frame, 3);
  ASSERT_EQ(l.frames[0].hands.size(), 1u);
  EXPECT_EQ(l.frames[0].hands[0].side, Side::kLeft);
  EXPECT_EQ(l.frames[0].hands[0].uv[20].x(), 200.0);
  EXPECT_TRUE(l.frames[0].hands[0].visible[20]);
  Json bad = file;
  bad["frames"][0]["hands"][0]["keypoints_2d"].erase(0);
  testing::WriteFile(tmp.path() / "bad.json", bad.dump());
  try {
    ReadHandLabels(tmp.path() / "bad.json");
    FAIL() << "accepted 20 keypoints";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_labels");
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace doasido::hands
