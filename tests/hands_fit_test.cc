// The hands module without the models: tracks from per-frame hands (gaps
// filled or split, one side per track) and the skeleton fit against a hand
// with exact answers (testing/synthetic_hand_track.h: a real hand's motion
// from ../shared/data/retarget, carried in front of a known camera).
#include <gtest/gtest.h>

#include <numeric>

#include "hands/hand_reconstruction.h"
#include "hands/hand_tracker.h"
#include "testing/synthetic_hand_track.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

using testing::MakeSyntheticHand;
using testing::Mpjpe;

const std::vector<Joints>& DexRows() {
  static const auto rows =
      testing::ReadDexKeypoints((testing::SharedData() / "retarget/human_hand_keypoints_right.csv").string());
  return rows;
}

std::vector<FrameObservations> OneHand(const testing::SyntheticHand& h) {
  std::vector<FrameObservations> frames;
  for (const auto& o : h.seen) frames.push_back({o});
  return frames;
}

double RootError(const FittedTrack& fit, const std::vector<Joints>& truth) {
  double sum = 0;
  for (size_t f = 0; f < fit.joints.size(); ++f) sum += (fit.joints[f][0] - truth[fit.first_frame + f][0]).norm();
  return sum / fit.joints.size();
}

TEST(HandsFit, NoisyKeypointsGiveTheTrueJointsWithinCentimetres) {
  ASSERT_GT(DexRows().size(), 100u);
  const auto h = MakeSyntheticHand(DexRows(), 60, 100, 1.5, 0.003, 0.9, 7);
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, FitConfig{});
  ASSERT_EQ(fit.joints.size(), 60u);
  const auto all = [](size_t) { return true; };
  const double before = Mpjpe(fit, h.truth, true, all), after = Mpjpe(fit, h.truth, false, all);
  std::printf("MPJPE PnP %.2f cm, fit %.2f cm, root %.2f cm, reprojection %.2f px\n", 100 * before,
              100 * after, 100 * RootError(fit, h.truth), fit.reprojection_rms_px);
  EXPECT_LT(after, 0.012);
  EXPECT_LT(after, before);  // the fit improves on per-frame PnP
  EXPECT_LT(RootError(fit, h.truth), 0.015);
  EXPECT_LT(fit.reprojection_rms_px, 3.0);
  // Bones keep one length: their spread over the clip is about the bone
  // sigma (2 mm), and well below that of the per-frame landmarks (3 mm noise).
  auto spread = [&](const std::vector<Joints>& xs, int j) {
    double lo = 1, hi = 0;
    for (const Joints& x : xs) {
      const double l = (x[j] - x[kParent[j]]).norm();
      lo = std::min(lo, l);
      hi = std::max(hi, l);
    }
    return hi - lo;
  };
  for (int j = 1; j < kJoints; ++j) {
    EXPECT_LT(spread(fit.joints, j), 0.004) << "bone to joint " << j;
    EXPECT_LT(spread(fit.joints, j), spread(fit.pnp_joints, j)) << "bone to joint " << j;
  }
}

TEST(HandsFit, ExactInputIsReproduced) {
  const auto h = MakeSyntheticHand(DexRows(), 20, 0, 0.0, 0.0, 0.9, 1);
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, FitConfig{});
  // Only the acceleration prior pulls away from the truth (the CSV's fingers move fast).
  EXPECT_LT(Mpjpe(fit, h.truth, false, [](size_t) { return true; }), 0.003);
  EXPECT_LT(Mpjpe(fit, h.truth, true, [](size_t) { return true; }), 1e-6);  // PnP on exact input
}

TEST(HandsFit, ShortGapsAreFilledAndMarkedLongGapsSplit) {
  const auto h = MakeSyntheticHand(DexRows(), 80, 200, 1.0, 0.002, 0.9, 3);
  auto frames = OneHand(h);
  for (int f = 20; f < 23; ++f) frames[f].clear();  // 3 frames: filled
  for (int f = 50; f < 60; ++f) frames[f].clear();  // 10 frames: split
  TrackerConfig config;
  config.max_gap_frames = 5;
  const auto tracks = BuildTracks(frames, config);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(tracks[0].first_frame, 0);
  EXPECT_EQ(tracks[0].last_frame(), 49);
  EXPECT_EQ(tracks[1].first_frame, 60);
  EXPECT_EQ(tracks[1].last_frame(), 79);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, FitConfig{});
  for (int f = 0; f < 50; ++f) EXPECT_EQ(fit.filled[f], f >= 20 && f < 23) << f;
  const double gap = Mpjpe(fit, h.truth, false, [](size_t f) { return f >= 20 && f < 23; });
  std::printf("MPJPE on filled frames %.2f cm\n", 100 * gap);
  EXPECT_LT(gap, 0.02);
}

TEST(HandsTracker, EachTrackKeepsOneSideThroughHandednessFlips) {
  // Two hands side by side; the model's handedness flips on some frames of each.
  auto right = MakeSyntheticHand(DexRows(), 60, 0, 1.0, 0.002, 0.85, 5);
  auto left = MakeSyntheticHand(DexRows(), 60, 300, 1.0, 0.002, 0.15, 6);
  std::vector<FrameObservations> frames(60);
  for (int f = 0; f < 60; ++f) {
    HandObservation r = right.seen[f], l = left.seen[f];
    for (auto& p : l.uv) p.x() -= 250;  // the left hand stays left in the image
    if (f % 7 == 3) std::swap(r.p_right, l.p_right);  // the model's occasional swap
    // Detection order changes too: the tracker must not care.
    frames[f] = f % 2 ? FrameObservations{r, l} : FrameObservations{l, r};
  }
  TrackingSummary summary;
  const auto tracks = BuildTracks(frames, TrackerConfig{}, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(summary.detections, 120);
  for (const Track& t : tracks) {
    EXPECT_EQ(t.observed(), 60);
    // Each track holds one hand only: its x never jumps between the hands.
    const bool is_left = t.frames[0]->uv[0].x() < right.seen[0].uv[0].x() - 100;
    EXPECT_EQ(t.side, is_left ? Side::kLeft : Side::kRight);
    for (const auto& o : t.frames) {
      EXPECT_EQ(o->uv[0].x() < right.seen[0].uv[0].x() - 100, is_left);
    }
  }
  EXPECT_NE(tracks[0].side, tracks[1].side);
}

TEST(HandsTracker, OverlappingTracksThatVoteAlikeGetDifferentSides) {
  auto a = MakeSyntheticHand(DexRows(), 30, 0, 1.0, 0.002, 0.9, 8);
  auto b = MakeSyntheticHand(DexRows(), 30, 100, 1.0, 0.002, 0.6, 9);
  std::vector<FrameObservations> frames(30);
  for (int f = 0; f < 30; ++f) {
    HandObservation second = b.seen[f];
    for (auto& p : second.uv) p.x() -= 250;
    frames[f] = {a.seen[f], second};
  }
  TrackingSummary summary;
  const auto tracks = BuildTracks(frames, TrackerConfig{}, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(summary.side_changes, 1);
  // The surer vote (0.9) keeps right; the other becomes left.
  for (const Track& t : tracks) {
    EXPECT_EQ(t.side, t.side_vote > 0.8 ? Side::kRight : Side::kLeft);
  }
}

TEST(HandsTracker, ShortSpuriousTracksAreDropped) {
  auto h = MakeSyntheticHand(DexRows(), 30, 0, 1.0, 0.002, 0.9, 4);
  auto frames = OneHand(h);
  HandObservation ghost = h.seen[10];
  for (auto& p : ghost.uv) p += Eigen::Vector2d(300, 200);
  frames[10].push_back(ghost);
  frames[11].push_back(ghost);
  HandObservation weak = h.seen[12];
  weak.score = 0.2;
  for (auto& p : weak.uv) p += Eigen::Vector2d(-300, 100);
  frames[12].push_back(weak);
  TrackingSummary summary;
  const auto tracks = BuildTracks(frames, TrackerConfig{}, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(tracks[0].observed(), 30);
  EXPECT_EQ(summary.dropped_tracks, 1);  // the two-frame ghost; the weak one is no detection
  EXPECT_EQ(summary.detections, 32);
}

TEST(HandsConfig, OutOfRangeValuesAreRefusedByName) {
  HandsConfig c;
  c.default_fov_deg = 200;
  try {
    CheckConfig(c, "hands");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_config");
    EXPECT_NE(std::string(e.what()).find("hands.default_fov_deg"), std::string::npos) << e.what();
  }
  c = HandsConfig{};
  c.fit.bone_sigma_m = 0;
  EXPECT_THROW(CheckConfig(c, "hands"), Error);
}

TEST(HandsIntrinsics, ListColumnsAndFieldOfView) {
  const Mat3 K = KFromFov(640, 480, 90);
  EXPECT_NEAR(K(0, 0), 320, 1e-9);
  EXPECT_NEAR(K(0, 2), 319.5, 1e-9);
  const auto listed = IntrinsicsFromList(Json{{"fx", "600"}, {"cy", 200}}, 640, 480, "c1");
  ASSERT_TRUE(listed);
  EXPECT_FALSE(listed->assumed);
  EXPECT_EQ(listed->K(1, 1), 600);
  EXPECT_EQ(listed->K(1, 2), 200);
  EXPECT_EQ(listed->K(0, 2), 319.5);
  EXPECT_FALSE(IntrinsicsFromList(Json{{"narration", "x"}}, 640, 480, "c1"));
  try {
    IntrinsicsFromList(Json{{"fov", "wide"}}, 640, 480, "c7");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_intrinsics");
    EXPECT_EQ(e.site().clip, "c7");
    EXPECT_EQ(e.site().field, "fov");
  }
  EXPECT_THROW(IntrinsicsFromList(Json{{"fx", -3}}, 640, 480, "c7"), Error);
}

}  // namespace
}  // namespace doasido::hands
