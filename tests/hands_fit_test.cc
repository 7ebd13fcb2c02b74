// The hands module without the models: tracks from per-frame hands (gaps
// filled or split, one side per track) and the skeleton fit against a hand
// with exact answers (testing/synthetic_hand_track.h: a real hand's motion
// from ../shared/data/retarget, carried in front of a known camera).
#include <gtest/gtest.h>

#include <numeric>

#include "hands/hand_outliers.h"
#include "hands/hand_reconstruction.h"
#include "hands/hand_tracker.h"
#include "eval/umetrack_hand.h"
#include "testing/synthetic_hand_track.h"
#include "test_util.h"

namespace doasido::hands {
namespace {

using testing::MakeSyntheticHand;
using testing::Mpjpe;

const std::vector<Joints>& DexRows() {
  static const auto rows = testing::ReadDexKeypoints(
      (testing::SharedData() / "retarget/human_hand_keypoints_right.csv").string());
  return rows;
}

std::vector<FrameObservations> OneHand(const testing::SyntheticHand& h) {
  std::vector<FrameObservations> frames;
  for (const auto& o : h.seen) frames.push_back({o});
  return frames;
}

// The synthetic landmarks carry the true size: these tests fit with the
// model's own size; the adult prior has tests of its own below.
FitConfig ModelSize() {
  FitConfig c;
  c.size_prior = "model";
  return c;
}

double RootError(const FittedTrack& fit, const std::vector<Joints>& truth) {
  double sum = 0;
  for (size_t f = 0; f < fit.joints.size(); ++f)
    sum += (fit.joints[f][0] - truth[fit.first_frame + f][0]).norm();
  return sum / fit.joints.size();
}

TEST(HandsFit, NoisyKeypointsGiveTheTrueJointsWithinCentimetres) {
  ASSERT_GT(DexRows().size(), 100u);
  const auto h = MakeSyntheticHand(DexRows(), 60, 100, 1.5, 0.003, 0.9, 7);
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, ModelSize());
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

// The landmark model's world landmarks as the fit's shape and pose prior
// (FitConfig::world_prior, the default): one view does not show how deep
// the fingers are, and without them only reprojection, bones and the
// hand's motion shape the hand. On the hand with exact answers above the
// fit with them is nearer the truth (hands_bench synth measures both).
TEST(HandsFit, TheWorldLandmarkPriorBringsTheJointsNearerTheTruth) {
  const auto h = MakeSyntheticHand(DexRows(), 60, 100, 1.5, 0.003, 0.9, 7);
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  FitConfig without = ModelSize();
  without.world_prior = false;
  const auto all = [](size_t) { return true; };
  const double with_prior =
      Mpjpe(FitTrack(tracks[0], h.K, h.fps, ModelSize()), h.truth, false, all);
  const double without_prior =
      Mpjpe(FitTrack(tracks[0], h.K, h.fps, without), h.truth, false, all);
  std::printf("MPJPE with the world prior %.2f cm, without %.2f cm\n", 100 * with_prior,
              100 * without_prior);
  EXPECT_LT(with_prior, without_prior);
}

TEST(HandsFit, ExactInputIsReproduced) {
  const auto h = MakeSyntheticHand(DexRows(), 20, 0, 0.0, 0.0, 0.9, 1);
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, ModelSize());
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
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, ModelSize());
  for (int f = 0; f < 50; ++f) EXPECT_EQ(fit.filled[f], f >= 20 && f < 23) << f;
  const double gap = Mpjpe(fit, h.truth, false, [](size_t f) { return f >= 20 && f < 23; });
  std::printf("MPJPE on filled frames %.2f cm\n", 100 * gap);
  EXPECT_LT(gap, 0.02);
}

// The rows scaled to a hand `length` long (wrist - middle base - tip).
std::vector<Joints> RowsOfLength(double length) {
  std::vector<Joints> rows = DexRows();
  const Joints& r = rows[0];
  const double own = (r[9] - r[0]).norm() + (r[10] - r[9]).norm() + (r[11] - r[10]).norm() +
                     (r[12] - r[11]).norm();
  for (Joints& row : rows) {
    for (Vec3& j : row) j *= length / own;
  }
  return rows;
}

double MaxRootJump(const FittedTrack& fit) {
  double jump = 0;
  for (size_t f = 1; f < fit.joints.size(); ++f)
    jump = std::max(jump, (fit.joints[f][0] - fit.joints[f - 1][0]).norm());
  return jump;
}

TEST(HandsSize, TheAdultPriorRestoresTheDepthWhereTheModelsHandIsSmall) {
  // An adult hand (0.182 m, the prior's centre) whose landmark model sees it
  // at 0.6 of its size, as on the bundled real clips (0.5-0.95), over four
  // stretches of its motion. The template (HOT3D's hand) is not this hand
  // (dex-retargeting's): their proportions differ (palm 5.9 vs 6.4 cm at
  // this length), which costs depth where the pose shows the palm most.
  double model_root = 0, adult_root = 0, adult_mpjpe = 0;
  const auto all = [](size_t) { return true; };
  for (int k = 0; k < 4; ++k) {
    auto h = MakeSyntheticHand(RowsOfLength(0.182), 45, 150 * k, 1.5, 0.003, 0.9, 21 + k);
    for (auto& o : h.seen) {
      for (auto& w : o.world) w *= 0.6;
    }
    const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
    ASSERT_EQ(tracks.size(), 1u);
    const FittedTrack model = FitTrack(tracks[0], h.K, h.fps, ModelSize());
    const FittedTrack adult = FitTrack(tracks[0], h.K, h.fps, FitConfig{});
    std::printf(
        "rows from %d: model size root %.2f cm; adult prior root %.2f cm, MPJPE %.2f cm, length "
        "%.3f m\n",
        150 * k, 100 * RootError(model, h.truth), 100 * RootError(adult, h.truth),
        100 * Mpjpe(adult, h.truth, false, all), HandLength(adult.link_length));
    model_root += RootError(model, h.truth) / 4;
    adult_root += RootError(adult, h.truth) / 4;
    adult_mpjpe += Mpjpe(adult, h.truth, false, all) / 4;
    EXPECT_TRUE(adult.size_prior);
    EXPECT_NEAR(HandLength(adult.link_length), 0.182, 0.182 * 0.03);
    EXPECT_NEAR(adult.model_hand_length_m, 0.6 * 0.182, 0.02);
    // The template's palm at that length (61.6 / 189.6 of it).
    EXPECT_NEAR(adult.link_length.back(), 0.182 * 61.59 / 189.55, 0.003);
  }
  EXPECT_GT(model_root, 0.15);  // 40 % too near
  EXPECT_LT(adult_root, 0.03);
  EXPECT_LT(adult_mpjpe, 0.03);
}

TEST(HandsSize, TheTemplateIsHot3dsMeasuredHand) {
  // The template's links are those of HOT3D P0003's UmeTrack hand at rest.
  const auto profile =
      testing::SharedData() / "hot3d_sample/Aria/P0003_c701bd11/umetrack_hand_user_profile.json";
  const recon::UmeTrackHand hand = recon::ReadUmeTrackHand(profile);
  std::array<double, recon::kUmeTrackJoints> rest{};
  const recon::Joints21 j =
      recon::UmeTrackOpenPose21(hand, rest, Pose::Identity(), recon::HandSide::kRight);
  const std::vector<double> links = TemplateLinkLengths(kTemplateHandLengthM);
  const auto pairs = SkeletonLinks();
  ASSERT_EQ(links.size(), pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_NEAR(links[k], (j.row(pairs[k].first) - j.row(pairs[k].second)).norm(), 5e-5) << k;
  }
  EXPECT_NEAR(HandLength(TemplateLinkLengths(0.18)), 0.18, 1e-12);
}

TEST(HandsFit, AFlippedPnPPoseIsDroppedAndTheWristDoesNotJump) {
  // Two frames whose model landmarks are mirrored (the model's own
  // palm/back confusion): PnP's best pose for them turns the hand over.
  auto h = MakeSyntheticHand(DexRows(), 60, 300, 1.0, 0.002, 0.9, 13);
  for (int f : {30, 31}) {
    for (auto& w : h.seen[f].world) w.z() = -w.z();
  }
  const auto tracks = BuildTracks(OneHand(h), TrackerConfig{});
  ASSERT_EQ(tracks.size(), 1u);
  // The flip test alone: every frame trusted (HandsOutliers below test
  // what the stage does first with a mirrored 3D hand).
  FitConfig trusting = ModelSize();
  trusting.max_untrusted_run = 0;
  FitConfig keep = trusting;
  keep.max_pnp_turn_deg = 180;  // nothing dropped
  const FittedTrack kept = FitTrack(tracks[0], h.K, h.fps, keep);
  const FittedTrack fit = FitTrack(tracks[0], h.K, h.fps, trusting);
  const auto flipped = [](size_t f) { return f == 30 || f == 31; };
  std::printf(
      "flips kept: jump %.2f cm, MPJPE there %.2f cm; dropped (%d): jump %.2f cm, MPJPE there %.2f "
      "cm\n",
      100 * MaxRootJump(kept), 100 * Mpjpe(kept, h.truth, false, flipped), fit.flipped_poses,
      100 * MaxRootJump(fit), 100 * Mpjpe(fit, h.truth, false, flipped));
  EXPECT_EQ(fit.flipped_poses, 2);
  EXPECT_FALSE(fit.has_pnp[30]);
  EXPECT_FALSE(fit.filled[30]);  // observed: its keypoints still count
  EXPECT_LT(Mpjpe(fit, h.truth, false, flipped), 0.012);
  EXPECT_LT(Mpjpe(fit, h.truth, false, flipped), Mpjpe(kept, h.truth, false, flipped));
  double truth_jump = 0;
  for (size_t f = 1; f < h.truth.size(); ++f)
    truth_jump = std::max(truth_jump, (h.truth[f][0] - h.truth[f - 1][0]).norm());
  EXPECT_LT(MaxRootJump(fit), truth_jump + 0.01);
}

// The synthetic hand of these tests with the model's 3D hand mirrored
// (z -> -z: the landmark model's 3D hand turned over, as on 02_cups) on
// frames [first, last], through the stage's whole fit with its true K,
// with every frame trusted and as the stage runs.
struct MirroredRun {
  testing::SyntheticHand h;
  DetectedFrames d;
  HandsResult trusting, result;
};

MirroredRun FitMirroredRun(int first, int last, int jump_first = -1) {
  MirroredRun m{.h = MakeSyntheticHand(DexRows(), 60, 300, 1.0, 0.002, 0.9, 13)};
  for (int f = first; f <= last; ++f) {
    for (auto& w : m.h.seen[f].world) w.z() = -w.z();
  }
  // Two frames whose keypoints lie 30 cm to the side (a find of something
  // else, 9 m/s away and back).
  for (int f = jump_first; f >= 0 && f <= jump_first + 1; ++f) {
    for (auto& uv : m.h.seen[f].uv) uv.x() += 0.30 * m.h.K(0, 0) / m.h.truth[f][0].z();
  }
  m.d = {.frames = OneHand(m.h), .width = m.h.width, .height = m.h.height, .fps = m.h.fps};
  const Intrinsics in{.K = m.h.K, .assumed = false, .source = kIntrinsicsFromOption};
  HandsConfig config;
  config.fit = ModelSize();
  m.result = ReconstructHands(m.d, in, config);
  config.fit.max_untrusted_run = 0;
  m.trusting = ReconstructHands(m.d, in, config);
  return m;
}

// The largest palm turn between consecutive frames of a fitted hand up to
// frame `last`, degrees.
double MaxTurn(const std::vector<Joints>& joints, size_t last = 1000) {
  double turn = 0;
  for (size_t f = 1; f < joints.size() && f <= last; ++f)
    turn = std::max(turn, HandTurnDeg(joints[f - 1], joints[f]));
  return turn;
}

double MaxTruthTurn(const std::vector<Joints>& truth) {
  double turn = 0;
  for (size_t f = 1; f < truth.size(); ++f)
    turn = std::max(turn, HandTurnDeg(truth[f - 1], truth[f]));
  return turn;
}

TEST(HandsOutliers, AMirroredRunLosesItsPosesAndStaysNearTheTruth) {
  // Frames 25-34: the model's 3D hand mirrored. They keep their keypoints,
  // lose their (turned over) PnP poses, and stay within 1.5 cm of the
  // truth, the hand turning no faster than the truth. With every frame
  // trusted the flips' majority test keeps the run's poses (most of each
  // frame's neighbours are in the run) and the fit turns the hand over.
  const MirroredRun m = FitMirroredRun(25, 34);
  ASSERT_EQ(m.result.tracks.size(), 1u);
  ASSERT_EQ(m.trusting.tracks.size(), 1u);
  const FittedTrack& fit = m.result.tracks[0];
  const auto mirrored = [](size_t f) { return f >= 25 && f <= 34; };
  for (size_t f = 0; f < fit.joints.size(); ++f) {
    EXPECT_FALSE(fit.filled[f]) << f;
    EXPECT_EQ(fit.has_pnp[f], !mirrored(f)) << f;
  }
  EXPECT_EQ(fit.mirrored_poses, 10);
  EXPECT_EQ(Summarize(m.d, m.result).at("mirrored_poses"), 10);
  std::printf(
      "mirrored frames' MPJPE %.2f cm trusted, %.2f cm without their poses; largest "
      "turn %.1f / %.1f deg (truth %.1f)\n",
      100 * Mpjpe(m.trusting.tracks[0], m.h.truth, false, mirrored),
      100 * Mpjpe(fit, m.h.truth, false, mirrored), MaxTurn(m.trusting.tracks[0].joints),
      MaxTurn(fit.joints), MaxTruthTurn(m.h.truth));
  EXPECT_LT(Mpjpe(fit, m.h.truth, false, mirrored), 0.015);
  EXPECT_LT(Mpjpe(fit, m.h.truth, false, [](size_t) { return true; }), 0.01);
  EXPECT_GT(Mpjpe(m.trusting.tracks[0], m.h.truth, false, mirrored), 0.03);
  EXPECT_LT(MaxTurn(fit.joints), MaxTruthTurn(m.h.truth) + 5);
}

TEST(HandsOutliers, AShortMirroredRunAndAJumpStayNearTheTruth) {
  // Frames 20-22 mirrored, and on frames 40-41 the keypoints 30 cm aside:
  // every frame's joints stay within 1 cm of the truth, 2 cm at the jump
  // (the robust loss, the bones and the acceleration outvote it), and up
  // to the jump the hand turns no faster than the truth.
  const MirroredRun m = FitMirroredRun(20, 22, 40);
  ASSERT_EQ(m.result.tracks.size(), 1u);
  const FittedTrack& fit = m.result.tracks[0];
  ASSERT_EQ(fit.joints.size(), m.h.truth.size());
  EXPECT_EQ(fit.mirrored_poses, 3);
  const auto jumped = [](size_t f) { return f == 40 || f == 41; };
  std::printf("MPJPE %.2f cm, at the jump %.2f cm; largest turn up to it %.1f deg\n",
              100 * Mpjpe(fit, m.h.truth, false, [](size_t) { return true; }),
              100 * Mpjpe(fit, m.h.truth, false, jumped), MaxTurn(fit.joints, 39));
  EXPECT_LT(Mpjpe(fit, m.h.truth, false, [](size_t f) { return f < 40 || f > 41; }), 0.01);
  EXPECT_LT(Mpjpe(fit, m.h.truth, false, jumped), 0.02);
  EXPECT_LT(MaxTurn(fit.joints, 39), MaxTruthTurn(m.h.truth) + 5);
}

TEST(HandsOutliers, UntrustedFramesAreShortPiecesBetweenImpossibleSteps) {
  // A path moving 1 cm a frame, one frame 20 cm aside, the last three
  // turned over: bounds 10 cm and 24 degrees a frame, runs of up to 5.
  std::vector<Joints> path(20);
  for (size_t f = 0; f < path.size(); ++f) {
    for (int j = 0; j < kJoints; ++j) path[f][j] = Vec3(0.01 * f, 0.001 * j, 0.02 * (j % 3) + 0.5);
  }
  for (auto& j : path[7]) j.x() += 0.2;  // one frame 20 cm aside
  const Mat3 turn = Eigen::AngleAxisd(M_PI, Vec3::UnitY()).toRotationMatrix();
  for (size_t f = 17; f < 20; ++f) {  // the last three turned over about the wrist
    for (auto& j : path[f]) j = turn * (j - path[f][0]) + path[f][0];
  }
  const std::vector<bool> untrusted = UntrustedFrames(path, 0.1, 24, 5);
  for (size_t f = 0; f < path.size(); ++f) EXPECT_EQ(untrusted[f], f == 7 || f >= 17) << f;
  const std::vector<bool> off = UntrustedFrames(path, 0.1, 24, 0);
  EXPECT_EQ(std::count(off.begin(), off.end(), true), 0);
  Track t;
  t.first_frame = 10;
  for (int f = 0; f < 6; ++f) t.frames.push_back(HandObservation{});
  const Track kept = WithoutFrames(t, {true, false, true, false, false, true});
  EXPECT_EQ(kept.first_frame, 11);
  EXPECT_EQ(kept.frames.size(), 4u);
  EXPECT_FALSE(kept.frames[1].has_value());
  EXPECT_EQ(kept.untrusted, (std::vector<bool>{false, true, false, false}));
}

TEST(HandsTracker, AHandFoundTwiceMakesOneTrackThatDoesNotAlternate) {
  // The landmarker's second find of one hand, 0.15 hand sizes off and
  // sometimes surer than the first: one track, always the find nearest it.
  auto h = MakeSyntheticHand(DexRows(), 40, 0, 1.0, 0.002, 0.9, 17);
  std::vector<FrameObservations> frames(40);
  int twice = 0;
  for (int f = 0; f < 40; ++f) {
    frames[f] = {h.seen[f]};
    if (f >= 10 && f < 30) {
      HandObservation second = h.seen[f];
      for (auto& p : second.uv) p.x() += 25;
      second.score = f % 2 ? 0.99 : 0.6;
      second.p_right = 0.2;
      frames[f].push_back(second);
      ++twice;
    }
  }
  TrackingSummary summary;
  const auto tracks = BuildTracks(frames, TrackerConfig{}, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(summary.duplicates, twice);
  EXPECT_EQ(tracks[0].observed(), 40);
  for (int f = 0; f < 40; ++f) EXPECT_EQ(tracks[0].frames[f]->uv[0].x(), h.seen[f].uv[0].x()) << f;
  TrackerConfig off;
  off.duplicate_distance = 0;
  EXPECT_EQ(BuildTracks(frames, off).size(), 2u);
}

TEST(HandsTracker, EachTrackKeepsOneSideThroughHandednessFlips) {
  // Two hands side by side; the model's handedness flips on some frames of each.
  auto right = MakeSyntheticHand(DexRows(), 60, 0, 1.0, 0.002, 0.85, 5);
  auto left = MakeSyntheticHand(DexRows(), 60, 300, 1.0, 0.002, 0.15, 6);
  std::vector<FrameObservations> frames(60);
  for (int f = 0; f < 60; ++f) {
    HandObservation r = right.seen[f], l = left.seen[f];
    for (auto& p : l.uv) p.x() -= 250;                // the left hand stays left in the image
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
  TrackerConfig by_vote;
  by_vote.min_arrangement_lean = 0;  // the hands' place not asked
  const auto tracks = BuildTracks(frames, by_vote, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(summary.side_changes, 1);
  // The surer vote (0.9) keeps right; the other becomes left.
  for (const Track& t : tracks) {
    EXPECT_EQ(t.side, t.side_vote > 0.8 ? Side::kRight : Side::kLeft);
  }
}

// Two hands of one person seen together, both voted `p_right`-alike; the
// image turned upside down when `fingers_up` (y -> 479 - y), so the
// fingers point up instead of down. Returns the side of the hand at the
// image's left.
Side SideOfImageLeftHand(bool fingers_up, double vote_left, double vote_right) {
  auto a = MakeSyntheticHand(DexRows(), 30, 0, 1.0, 0.002, vote_right, 8);
  auto b = MakeSyntheticHand(DexRows(), 30, 100, 1.0, 0.002, vote_left, 9);
  std::vector<FrameObservations> frames(30);
  for (int f = 0; f < 30; ++f) {
    HandObservation right_in_image = a.seen[f], left_in_image = b.seen[f];
    for (auto& p : left_in_image.uv) p.x() -= 250;
    for (HandObservation* o : {&right_in_image, &left_in_image}) {
      for (auto& p : o->uv) {
        if (fingers_up) p.y() = 479 - p.y();
      }
    }
    frames[f] = {right_in_image, left_in_image};
  }
  const auto tracks = BuildTracks(frames, TrackerConfig{});
  EXPECT_EQ(tracks.size(), 2u);
  if (tracks.size() != 2) return Side::kRight;
  EXPECT_NE(tracks[0].side, tracks[1].side);
  const bool first_is_left = tracks[0].frames[0]->uv[0].x() < tracks[1].frames[0]->uv[0].x();
  return tracks[first_is_left ? 0 : 1].side;
}

TEST(HandsTracker, TwoHandsVotingAlikeTakeTheirSidesFromTheirPlace) {
  // The synthetic hands' fingers point down the image: a person facing the
  // camera across the hands, whose right hand is at the image's left
  // (02_cups, 03_blocks' labels), whichever hand's vote is surer.
  EXPECT_EQ(SideOfImageLeftHand(false, 0.6, 0.9), Side::kRight);
  EXPECT_EQ(SideOfImageLeftHand(false, 0.9, 0.6), Side::kRight);
  EXPECT_EQ(SideOfImageLeftHand(false, 0.1, 0.4), Side::kRight);
  // Fingers up (one's own view): the right hand at the image's right.
  EXPECT_EQ(SideOfImageLeftHand(true, 0.6, 0.9), Side::kLeft);
  EXPECT_EQ(SideOfImageLeftHand(true, 0.1, 0.4), Side::kLeft);
  // Votes that differ are the model's reading and stand, place or not.
  EXPECT_EQ(SideOfImageLeftHand(false, 0.1, 0.9), Side::kLeft);
  EXPECT_EQ(SideOfImageLeftHand(true, 0.9, 0.1), Side::kRight);
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
  const auto refused = [](HandsConfig bad, const std::string& key) {
    try {
      CheckConfig(bad, "hands");
      ADD_FAILURE() << key << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "bad_config");
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  c = HandsConfig{};
  c.fit.size_prior = "child";
  refused(c, "hands.fit.size_prior");
  c = HandsConfig{};
  c.wide_search_every = -1;
  refused(c, "hands.wide_search_every");
  c = HandsConfig{};
  c.fit.hand_length_m = 1.8;  // centimetres for metres
  refused(c, "hands.fit.hand_length_m");
  c = HandsConfig{};
  c.fit.hand_length_sigma = 0;
  refused(c, "hands.fit.hand_length_sigma");
  c = HandsConfig{};
  c.fit.max_pnp_turn_deg = 0;
  refused(c, "hands.fit.max_pnp_turn_deg");
  c = HandsConfig{};
  c.fit.max_untrusted_run = -1;
  refused(c, "hands.fit.max_untrusted_run");
  c = HandsConfig{};
  c.fit.max_wrist_speed_m_s = 0;
  refused(c, "hands.fit.max_wrist_speed_m_s");
  c = HandsConfig{};
  c.fit.max_wrist_turn_deg_s = 0;
  refused(c, "hands.fit.max_wrist_turn_deg_s");
  c = HandsConfig{};
  c.tracker.duplicate_distance = -1;
  refused(c, "hands.tracker.duplicate_distance");
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
