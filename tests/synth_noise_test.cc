// The model-like noise matches its documented statistics, and the rendering
// cache changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "synth/episode.h"
#include "synth/generator.h"
#include "synth/model_noise.h"
#include "synth/objects.h"
#include "synth/render.h"

namespace doasido::synth {
namespace {

double Mean(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0) / v.size();
}
double Std(const std::vector<double>& v) {
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / (v.size() - 1));
}

TEST(DepthNoise, PerFrameScaleHasTheDocumentedSpread) {
  std::vector<cv::Mat> depth;
  for (int t = 0; t < 400; ++t) {
    cv::Mat d(8, 8, CV_32F, cv::Scalar(1.0f));
    d.at<float>(0, 0) = std::numeric_limits<float>::infinity();
    depth.push_back(d);
  }
  DepthNoiseConfig cfg;
  cfg.pixel_sigma = 0.0;
  std::mt19937_64 rng(3);
  const std::vector<double> s = ApplyDepthNoise(depth, cfg, rng);
  std::vector<double> logs;
  for (size_t t = 0; t < s.size(); ++t) {
    logs.push_back(std::log(s[t]));
    EXPECT_FLOAT_EQ(depth[t].at<float>(4, 4), static_cast<float>(s[t]));
    EXPECT_TRUE(std::isinf(depth[t].at<float>(0, 0)));  // invalid stays invalid
  }
  EXPECT_NEAR(Mean(logs), 0.0, 0.01);
  EXPECT_NEAR(Std(logs), cfg.scale_sigma, 0.15 * cfg.scale_sigma);
}

TEST(HandNoise, JointErrorsHaveTheDocumentedSize) {
  recon::HandTrack hand;
  for (int t = 0; t < 300; ++t) {
    recon::Joints21 j;
    for (int k = 0; k < 21; ++k) j.row(k) = Vec3(0.01 * k, 0.0, 0.5).transpose();
    hand.joints.push_back(j);
    hand.valid.push_back(true);
  }
  const recon::HandTrack truth = hand;
  HandNoiseConfig cfg;
  cfg.depth_sigma = 0.0;
  cfg.jitter_sigma = 0.0;
  std::mt19937_64 rng(4);
  ApplyHandNoise(hand, cfg, rng);
  std::vector<double> err;
  for (size_t t = 0; t < hand.joints.size(); ++t) {
    const recon::Joints21 d = hand.joints[t] - truth.joints[t];
    for (int i = 0; i < d.size(); ++i) err.push_back(d.data()[i]);
  }
  EXPECT_NEAR(Mean(err), 0.0, 0.0005);
  EXPECT_NEAR(Std(err), cfg.joint_sigma, 0.05 * cfg.joint_sigma);
  // Jitter alone: one rigid offset per frame, correlated over time.
  hand = truth;
  cfg.joint_sigma = 0.0;
  cfg.jitter_sigma = 0.003;
  ApplyHandNoise(hand, cfg, rng);
  std::vector<double> x0, x1;
  for (size_t t = 0; t + 1 < hand.joints.size(); ++t) {
    const double a = hand.joints[t](0, 0) - truth.joints[t](0, 0);
    const double b = hand.joints[t + 1](0, 0) - truth.joints[t + 1](0, 0);
    x0.push_back(a);
    x1.push_back(b);
    EXPECT_NEAR(hand.joints[t](5, 0) - truth.joints[t](5, 0), a, 1e-12);  // rigid
  }
  const double m0 = Mean(x0), m1 = Mean(x1);
  double cov = 0;
  for (size_t i = 0; i < x0.size(); ++i) cov += (x0[i] - m0) * (x1[i] - m1);
  cov /= x0.size() - 1;
  EXPECT_NEAR(cov / (Std(x0) * Std(x1)), cfg.jitter_rho, 0.12);
}

TEST(PoseCandidates, ModesAreWhereTheyShouldBe) {
  std::vector<Pose> truth;
  for (int t = 0; t < 50; ++t) {
    truth.push_back({Quat(Eigen::AngleAxisd(0.05 * t, Vec3(0.2, 1, 0.1).normalized())),
                     Vec3(0.01 * t, 0.02, 0.6)});
  }
  CandidateConfig cfg;
  std::mt19937_64 rng(5);
  std::vector<std::vector<CandidateMode>> modes;
  const Vec3 centre(0, 0, 0.05);
  const auto c = SamplePoseCandidates(truth, centre, cfg, rng, &modes);
  ASSERT_EQ(c.size(), truth.size());
  int n_near = 0, n_flip = 0, n_out = 0, first_near = 0;
  for (size_t t = 0; t < c.size(); ++t) {
    ASSERT_EQ(static_cast<int>(c[t].size()), cfg.samples);
    first_near += modes[t][0] == CandidateMode::kNear;
    for (int i = 0; i < cfg.samples; ++i) {
      const Pose& p = c[t][i].pose;
      const double rot = RotationAngle(p.q, truth[t].q);
      const double centre_err = (p * centre - truth[t] * centre).norm();
      switch (modes[t][i]) {
        case CandidateMode::kNear:
          ++n_near;
          EXPECT_LT(rot, 5 * cfg.near_rot_sigma);
          EXPECT_LT((p.t - truth[t].t).norm(), 6 * cfg.near_trans_sigma);
          break;
        case CandidateMode::kFlip:
          ++n_flip;
          EXPECT_GT(rot, M_PI - 5 * cfg.near_rot_sigma);  // a half turn away
          EXPECT_LT(centre_err, 6 * cfg.near_trans_sigma + 0.05 * 5 * cfg.near_rot_sigma);
          break;
        case CandidateMode::kOutlier:
          ++n_out;
          break;
      }
      EXPECT_NEAR(p.q.norm(), 1.0, 1e-12);
      EXPECT_GT(c[t][i].scale, 0.0);
    }
  }
  const int total = static_cast<int>(truth.size()) * cfg.samples;
  EXPECT_EQ(n_near, total / 2);
  EXPECT_EQ(n_flip, total / 4);
  EXPECT_EQ(n_out, total - n_near - n_flip);
  // Shuffled: the first sample is not always the near mode.
  EXPECT_LT(first_near, static_cast<int>(truth.size()));
  EXPECT_GT(first_near, 0);
}

TEST(ModelLikeBundle, CorruptsDepthAndHandsButNotTheRest) {
  SynthConfig cfg;
  cfg.width = 160;
  cfg.height = 120;
  cfg.frames = 24;
  cfg.track_points = 4;
  const RenderedClip clip = RenderClip(cfg, 0, DefectKind::kClean);
  const recon::ClipBundle m = ModelLikeBundle(cfg, 0, clip.bundle);
  const recon::ClipBundle& g = clip.bundle;
  ASSERT_EQ(m.depth.size(), g.depth.size());
  // Per frame, valid depth is the truth times one scale (plus 1% pixel noise).
  for (size_t t = 0; t < g.depth.size(); t += 5) {
    cv::Mat ratio = m.depth[t] / g.depth[t];
    const double mean_ratio = cv::mean(ratio)[0];
    EXPECT_GT(mean_ratio, 0.7);
    EXPECT_LT(mean_ratio, 1.3);
    EXPECT_GT(cv::norm(m.depth[t], g.depth[t], cv::NORM_INF), 0.0);
  }
  const recon::HandTrack& hg = g.hand_right ? *g.hand_right : *g.hand_left;
  const recon::HandTrack& hm = m.hand_right ? *m.hand_right : *m.hand_left;
  double err = 0;
  for (size_t t = 0; t < hg.joints.size(); ++t) err += (hm.joints[t] - hg.joints[t]).norm();
  EXPECT_GT(err / hg.joints.size(), 0.005);
  EXPECT_LT(err / hg.joints.size(), 0.5);
  EXPECT_EQ(cv::norm(m.mask_object[3], g.mask_object[3], cv::NORM_INF), 0.0);
  EXPECT_EQ(m.object_poses[3].t, g.object_poses[3].t);
  EXPECT_EQ(m.producers["depth"], "doasido synth MoGe-like depth noise");
}

TEST(RenderCache, CachedBackgroundGivesIdenticalFrames) {
  World world;
  world.style = RandomStyle(9);
  const TriMesh mug = MakeMug(0.04, 0.1);
  EpisodeSpec spec;
  spec.frames = 24;
  const Episode ep = ScriptEpisode(spec, mug);
  BackgroundCache cache;
  for (int t : {0, 8, 16}) {
    FrameState st;
    st.camera = {160, 120, 140, 140, 79.5, 59.5};
    st.camera_from_world = LookAt(Vec3(0, -0.4, 0.35), Vec3(0, 0.05, 0.05));
    st.object_pose = ep.frames[t].object_pose;
    st.hands[1] = PoseHand(*ep.frames[t].hands[1], Side::kRight);
    st.hand_wrist[1] = ep.frames[t].hands[1]->wrist;
    const RenderedFrame a = RenderFrame(world, mug, st);
    const RenderedFrame b = RenderFrame(world, mug, st, {}, &cache);
    EXPECT_EQ(cv::norm(a.bgr, b.bgr, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.raster.surface, b.raster.surface, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.raster.depth, b.raster.depth, cv::NORM_INF), 0.0);
    EXPECT_GT(cv::countNonZero(SurfaceMask(a.raster, kSurfaceHandRight)), 50);
  }
}

}  // namespace
}  // namespace doasido::synth
