// The hand-made labels of real frames (bench/hand_labels/, made with
// scripts/label_hands.py) and the keypoint accuracy the hands stage reaches
// on them: every label file parses and covers what issues 38 and 54 ask
// (58 frames from 7 videos); on asl_hand's first labelled frames the
// models, the tracker and the fit stay above a PCK floor; on 02_cups 279
// the tracker keeps the person's sides, and follows the lifting hand after.
#include <gtest/gtest.h>

#include <set>

#include "filters/hand_landmarker.h"
#include "hands/hand_labels.h"
#include "hands/hand_reconstruction.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> LabelFiles() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(testing::SourceDir() / "bench/hand_labels")) {
    if (e.path().extension() == ".json") files.push_back(e.path());
  }
  return files;
}

TEST(HandLabels, EveryFileParsesAndTheSetCoversSevenVideos) {
  std::set<std::string> videos;
  int frames = 0;
  for (const fs::path& file : LabelFiles()) {
    const HandLabels labels = ReadHandLabels(file);
    EXPECT_TRUE(fs::exists(testing::SharedData() / labels.video)) << file;
    EXPECT_FALSE(labels.labeller.empty()) << file;
    videos.insert(labels.video);
    frames += static_cast<int>(labels.frames.size());
    for (const LabelledFrame& f : labels.frames) {
      ASSERT_FALSE(f.hands.empty()) << file << " frame " << f.frame;
      for (const LabelledHand& h : f.hands) {
        int visible = 0;
        for (int j = 0; j < kJoints; ++j) {
          visible += h.visible[j] ? 1 : 0;
          EXPECT_GE(h.uv[j].minCoeff(), 0.0) << file << " frame " << f.frame << " joint " << j;
        }
        EXPECT_GE(visible, 8) << file << " frame " << f.frame;  // a hand, not a guess
      }
    }
  }
  EXPECT_GE(videos.size(), 7u);
  EXPECT_GE(frames, 58);
}

// asl_hand frames 0 and 93 (one right hand, palm to the camera): measured
// PCK@0.2 is 1.0 for the models, the tracker and the fit, PCK@0.1 about
// 0.8-0.9 (docs/benchmarks.md). The labels' own spread between two passes is
// 0.026 hand boxes at the 90th percentile (bench/hand_labels/README.md), so
// at 0.2 the labels cost nothing: a floor of 0.9 fails on a real regression
// (a mirrored or swapped hand scores about 0.2, a lost hand 0), and on no
// label noise.
TEST(HandLabels, AslHandStaysAboveTheFloorForModelsTrackerAndFit) {
  std::string why;
  if (!filters::HandLandmarkerAvailable(&why)) GTEST_SKIP() << "hand models unavailable: " << why;
  HandLabels labels = ReadHandLabels(testing::SourceDir() / "bench/hand_labels/asl_hand.json");
  std::erase_if(labels.frames, [](const LabelledFrame& f) { return f.frame > 93; });
  ASSERT_EQ(labels.frames.size(), 2u);
  const HandsConfig config;
  filters::HandLandmarker landmarker({.max_hands = config.max_hands,
                                      .max_side = config.max_side,
                                      .palm_every = config.palm_every,
                                      .lost_search = config.palm_every});
  const std::string video = (testing::SharedData() / labels.video).string();
  const DetectedFrames detected =
      DetectVideo(video, {.last_frame = 93, .clip = video}, config.max_side, landmarker);
  const Intrinsics in{.K = KFromFov(detected.width, detected.height, config.default_fov_deg),
                      .assumed = true,
                      .source = kIntrinsicsFromDefault};
  const LabelScores s = ScoreLabels(labels, detected, ReconstructHands(detected, in, config));
  std::printf("asl_hand 0, 93: PCK@0.1/0.2 models %.3f/%.3f, tracker %.3f/%.3f, fit %.3f/%.3f\n",
              s.models.Pck01(), s.models.Pck02(), s.tracker.Pck01(), s.tracker.Pck02(),
              s.fit.Pck01(), s.fit.Pck02());
  EXPECT_EQ(s.labelled_frames, 2);
  for (const PckScore* p : {&s.models, &s.tracker, &s.fit}) {
    EXPECT_EQ(p->missed, 0);
    EXPECT_EQ(p->swaps, 0);
    EXPECT_GE(p->Pck02(), 0.9);
  }
}

// 02_cups' labels on frame 279 and the hands stage's models, tracker and
// fit on frames 274..`last_frame` with `config`.
struct CupsLift {
  HandLabels labels;
  DetectedFrames detected;
  HandsResult result;
};
CupsLift RunCupsLift(const HandsConfig& config, int last_frame) {
  CupsLift out;
  out.labels = ReadHandLabels(testing::SourceDir() / "bench/hand_labels/02_cups.json");
  std::erase_if(out.labels.frames, [](const LabelledFrame& f) { return f.frame != 279; });
  filters::HandLandmarker landmarker({.max_hands = config.max_hands,
                                      .max_side = config.max_side,
                                      .palm_every = config.palm_every,
                                      .lost_search = config.palm_every,
                                      .wide_every = config.wide_search_every,
                                      .lost_wide = config.lost_wide_search});
  const std::string video = (testing::SharedData() / out.labels.video).string();
  out.detected = DetectVideo(video, {.first_frame = 274, .last_frame = last_frame, .clip = video},
                             config.max_side, landmarker);
  const Intrinsics in{.K = KFromFov(out.detected.width, out.detected.height, config.default_fov_deg),
                      .assumed = true,
                      .source = kIntrinsicsFromDefault};
  out.result = ReconstructHands(out.detected, in, config);
  return out;
}

// 02_cups frames 274-299 (the person's left hand lifts the right cup): the
// landmark model calls both hands left on most of these frames (p_right
// 0.00-0.02), and the longer track, the person's right hand, kept left, so
// the hand lifting the cup came out right. The two hands' place in the
// image (fingers down: the person faces the camera, the right hand at the
// image's left; hands/hand_tracker.h) gives them the sides the labeller
// gave on frame 279: no swap for the tracker or the fit.
TEST(HandLabels, CupsLiftKeepsThePersonsSidesWhereTheModelCallsBothLeft) {
  std::string why;
  if (!filters::HandLandmarkerAvailable(&why)) GTEST_SKIP() << "hand models unavailable: " << why;
  const CupsLift run = RunCupsLift(HandsConfig{}, 299);
  ASSERT_EQ(run.labels.frames.size(), 1u);
  ASSERT_EQ(run.labels.frames[0].hands.size(), 2u);
  const LabelScores s = ScoreLabels(run.labels, run.detected, run.result);
  std::printf("02_cups 279 in 274-299: swaps models %d, tracker %d, fit %d; PCK@0.2 fit %.3f\n",
              s.models.swaps, s.tracker.swaps, s.fit.swaps, s.fit.Pck02());
  EXPECT_EQ(s.labelled_frames, 1);
  for (const PckScore* p : {&s.tracker, &s.fit}) {
    EXPECT_EQ(p->missed, 0);
    EXPECT_EQ(p->swaps, 0);
  }
}

// The person's left hand lifting the cup on 02_cups 285-294 (blurred, half
// behind the cup, at the frame's top): lost at 286 by its last crop and by
// the palm detector on the whole frame. With [hands] lost_wide_search the
// wide search runs on the frames after the loss and the track the labeller
// called left on frame 279 goes on, observed, through the lift; without
// it that track ends at 285. (Started at 279 instead, the tracker swapped
// the two hands' sides in a run: the place rule settles only votes that
// agree; the demo's row starts at 274.)
int LiftObservedFrames(int lost_wide_search) {
  HandsConfig config;
  config.lost_wide_search = lost_wide_search;
  const CupsLift run = RunCupsLift(config, 294);
  EXPECT_EQ(ScoreLabels(run.labels, run.detected, run.result).tracker.swaps, 0);
  // The labelled left hand's wrist on frame 279 (the span's frame 5).
  Eigen::Vector2d wrist(-1, -1);
  for (const LabelledHand& h : run.labels.frames[0].hands) {
    if (h.side == Side::kLeft) wrist = h.uv[0];
  }
  for (const FittedTrack& t : run.result.tracks) {
    const int at_279 = 5 - t.first_frame;
    if (at_279 < 0 || at_279 >= static_cast<int>(t.observations.size()) || !t.observations[at_279]) {
      continue;
    }
    if ((t.observations[at_279]->uv[0] - wrist).norm() > 60) continue;
    EXPECT_EQ(t.side, Side::kLeft);
    int lifted = 0;  // of frames 286-294 (the span's 12-20)
    for (int f = 12; f <= 20; ++f) {
      const int k = f - t.first_frame;
      lifted += k < static_cast<int>(t.observations.size()) && t.observations[k].has_value();
    }
    return lifted;
  }
  ADD_FAILURE() << "no track at the labelled left hand on frame 279";
  return 0;
}

TEST(HandLabels, CupsLiftFollowsTheLiftingHandWithTheWideSearchAfterALoss) {
  std::string why;
  if (!filters::HandLandmarkerAvailable(&why)) GTEST_SKIP() << "hand models unavailable: " << why;
  const int with = LiftObservedFrames(3), without = LiftObservedFrames(0);
  std::printf("02_cups 286-294: the lifting hand observed on %d of 9 frames (%d without)\n", with,
              without);
  EXPECT_GE(with, 8);
  EXPECT_LE(without, 2);
}

}  // namespace
}  // namespace doasido::hands
