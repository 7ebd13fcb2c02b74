// The guided tracker's parts against exact answers: the Gaussian-mixture
// flow's closed forms, the guided Euler sampler at alpha = 0 (the mixture)
// and alpha = 1 (the reference), likelihood by the change of variables
// against the closed-form density, the 2D rigid fit and alpha_p, the
// silhouette IoU, and clustering selection.
#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "recon/track/adaptive_guidance.h"
#include "recon/track/gaussian_mixture_flow.h"
#include "recon/track/guided_flow.h"
#include "recon/track/object_tracker.h"
#include "recon/track/pose_selection.h"
#include "recon/track/silhouette.h"
#include "synth/objects.h"

namespace doasido::recon {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Two pose modes 20 cm apart (weights 0.7 / 0.3) over a 2-value shape block.
GaussianMixtureFlow TwoModes(double sigma = 0.02) {
  FlowLayout layout{.shape_dim = 2};
  Eigen::VectorXd a(9), b(9);
  a << 0.3, -0.2, 0.1, 0.0, 0.5, 1, 0, 0, 0;
  b << 0.3, -0.2, -0.1, 0.0, 0.5, 0, 0, 0, 1;
  return GaussianMixtureFlow(layout, {{{0.7, a, sigma}, {0.3, b, sigma}}});
}

StateMatrix RandomStates(int n, int dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  StateMatrix x(n, dim);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = normal(rng);
  return x;
}

TEST(GaussianMixtureFlow, DivergenceIsTheTraceOfTheVelocityJacobian) {
  GaussianMixtureFlow model = TwoModes(0.2);
  const StateMatrix x = RandomStates(5, 9, 3) * 0.5;
  for (double t : {0.1, 0.5, 0.9}) {
    Eigen::VectorXd div;
    model.PoseDivergence(0, t, x, &div);
    for (int i = 0; i < 5; ++i) {
      double trace = 0;
      for (int d = 2; d < 9; ++d) {  // the pose block only
        StateMatrix plus = x.row(i), minus = x.row(i), vp, vm;
        const double h = 1e-6;
        plus(0, d) += h;
        minus(0, d) -= h;
        model.Velocity(0, t, plus, &vp);
        model.Velocity(0, t, minus, &vm);
        trace += (vp(0, d) - vm(0, d)) / (2 * h);
      }
      EXPECT_NEAR(div[i], trace, 1e-5 * (1 + std::abs(trace))) << "t " << t << " row " << i;
    }
  }
}

TEST(GuidedFlow, WithoutGuidanceTheSamplerDrawsTheMixture) {
  GaussianMixtureFlow model = TwoModes();
  GuidedTargets none{.shape = Eigen::VectorXd::Zero(2), .pose = Eigen::VectorXd::Zero(7),
                     .shape_guidance = 0, .pose_guidance = 0};
  const int n = 4000;
  const StateMatrix x = SampleGuided(model, 0, none, n, 200, 11);
  int near_a = 0;
  Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(9);
  for (int i = 0; i < n; ++i) {
    near_a += x(i, 2) > 0;  // the modes differ in the pose's x by +-0.1
    mean += x.row(i) / n;
  }
  // Mode weights within 3 standard errors of 0.7 (sd of a share: 0.0072).
  EXPECT_NEAR(near_a / double(n), 0.7, 0.022);
  Eigen::RowVectorXd expected(9);
  expected << 0.3, -0.2, 0.7 * 0.1 - 0.3 * 0.1, 0.0, 0.5, 0.7, 0, 0, 0.3;
  EXPECT_LT((mean - expected).cwiseAbs().maxCoeff(), 0.02) << mean;
  // Each sample sits on a mode, with the mode's spread (sigma 0.02).
  double within = 0;
  for (int i = 0; i < n; ++i) within += std::abs(x(i, 3)) < 3 * 0.02;
  EXPECT_GT(within / n, 0.98);
}

TEST(GuidedFlow, FullGuidanceReturnsTheReference) {
  GaussianMixtureFlow model = TwoModes();
  GuidedTargets full{.shape = Eigen::Vector2d(1.5, 2.5), .pose = Eigen::VectorXd::LinSpaced(7, -1, 1),
                     .shape_guidance = 1, .pose_guidance = 1};
  const StateMatrix x = SampleGuided(model, 0, full, 7, 25, 5);
  for (int i = 0; i < 7; ++i) {
    EXPECT_LT((x.row(i).head(2).transpose() - full.shape).norm(), 1e-12);
    EXPECT_LT((x.row(i).tail(7).transpose() - full.pose).norm(), 1e-12);
  }
  // The same seed gives the same candidates; another seed others.
  EXPECT_EQ(SampleGuided(model, 0, {.shape = full.shape, .pose = full.pose, .shape_guidance = 0.5,
                                    .pose_guidance = 0.2}, 3, 25, 5),
            SampleGuided(model, 0, {.shape = full.shape, .pose = full.pose, .shape_guidance = 0.5,
                                    .pose_guidance = 0.2}, 3, 25, 5));
}

TEST(GuidedFlow, PartialPoseGuidancePullsTowardThePreviousPose) {
  GaussianMixtureFlow model = TwoModes();
  // The previous pose sits on the 0.3 mode: guidance makes it the likely one.
  GuidedTargets toward_b{.shape = Eigen::Vector2d(0.3, -0.2), .pose = TwoModes().mixture(0)[1].mean.tail(7),
                         .shape_guidance = 0.95, .pose_guidance = 0.5};
  const StateMatrix x = SampleGuided(model, 0, toward_b, 400, 25, 2);
  int near_b = 0;
  for (int i = 0; i < 400; ++i) near_b += x(i, 2) < 0;
  EXPECT_GT(near_b, 0.9 * 400);
}

TEST(GuidedFlow, LikelihoodByChangeOfVariablesMatchesTheClosedForm) {
  // Pose block only, so that the pose density is the whole density.
  FlowLayout layout{.shape_dim = 0};
  Eigen::VectorXd a(7), b(7);
  a << 0.1, 0, 0.5, 1, 0, 0, 0;
  b << -0.1, 0, 0.5, 0, 0, 0, 1;
  GaussianMixtureFlow model(layout, {{{0.6, a, 0.3}, {0.4, b, 0.3}}});
  StateMatrix x(4, 7);
  x.row(0) = a.transpose();
  x.row(1) = b.transpose();
  x.row(2) = 0.5 * (a + b).transpose();
  x.row(3) = a.transpose() + Eigen::RowVectorXd::Constant(7, 0.2);
  const Eigen::VectorXd log_p = PoseLogLikelihood(model, 0, x, 2000);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(log_p[i], model.LogDensity(0, x.row(i)), 0.02) << "row " << i;
  }
  EXPECT_GT(log_p[0], log_p[1]);  // the heavier mode
  EXPECT_GT(log_p[1], log_p[3]);
}

TEST(AdaptiveGuidance, RigidFitAndTheSeedsAlpha) {
  std::vector<Vec2> a = {{10, 10}, {40, 12}, {25, 50}, {5, 33}}, b;
  const double angle = 7.5 * kPi / 180;
  const Eigen::Rotation2Dd R(angle);
  for (const Vec2& p : a) b.push_back(R * p + Vec2(3, -4));
  const RigidMotion2D fit = FitRigid2D(a, b);
  EXPECT_NEAR(fit.angle_deg, 7.5, 1e-9);
  EXPECT_NEAR((fit.translation - Vec2(3, -4)).norm(), 0, 1e-9);
  AdaptiveGuidanceConfig c;
  EXPECT_DOUBLE_EQ(PoseGuidance(0, c), 0.7);
  EXPECT_NEAR(PoseGuidance(-2, c), 0.52, 1e-12);
  EXPECT_DOUBLE_EQ(PoseGuidance(6.7, c), 0.1);
  EXPECT_DOUBLE_EQ(PoseGuidance(40, c), 0.1);
}

TEST(AdaptiveGuidance, AMaskTurningAtKnownRatesGivesTheirAlpha) {
  // An ellipse turning about its centre by 0, 2, 5 and 12 degrees per frame.
  const std::vector<double> turn = {0, 2, 5, 12};
  std::vector<cv::Mat> masks;
  double angle = 0;
  for (size_t k = 0; k <= turn.size(); ++k) {
    cv::Mat m(200, 240, CV_8U, cv::Scalar(0));
    cv::ellipse(m, cv::Point(120, 100), cv::Size(70, 30), angle, 0, 360, 255, cv::FILLED);
    masks.push_back(m);
    if (k < turn.size()) angle += turn[k];
  }
  const Vec2 centre(120, 100);
  auto follow = [&](int k, const std::vector<Vec2>& points) {
    std::vector<PointFollow> out;
    const Eigen::Rotation2Dd R(turn[k] * kPi / 180);  // cv::ellipse turns clockwise on screen
    for (const Vec2& p : points) out.push_back({p, centre + R * (p - centre), true});
    return out;
  };
  const GuidanceEstimate g = EstimatePoseGuidance(masks, follow, {});
  ASSERT_EQ(g.alpha_p.size(), 5u);
  for (size_t k = 1; k < 5; ++k) {
    EXPECT_NEAR(g.dtheta_deg[k], turn[k - 1], 1e-9) << k;
    EXPECT_NEAR(g.alpha_p[k], std::max(0.1, 0.7 - 0.09 * turn[k - 1]), 1e-9);
    EXPECT_GE(g.points_kept[k], 15);  // of 20: most land inside the next mask
  }
}

TEST(Silhouette, IoUAgainstRenderedMasks) {
  const TriMesh box = synth::MakeBox(0.1, 0.06, 0.04);
  const SilhouetteRenderer renderer(box);
  const Camera camera{.width = 160, .height = 120, .fx = 150, .fy = 150, .cx = 80, .cy = 60};
  const Pose at{Quat(Eigen::AngleAxisd(0.4, Vec3(0.3, 1, 0.2).normalized())), Vec3(0.02, 0, 0.5)};
  const cv::Mat mask = renderer.Render(at, camera);
  EXPECT_GT(cv::countNonZero(mask), 500);
  EXPECT_DOUBLE_EQ(renderer.IoU(at, camera, mask), 1.0);
  const Pose moved{at.q, at.t + Vec3(0.03, 0, 0)};
  const cv::Mat other = renderer.Render(moved, camera);
  cv::Mat both, either;
  cv::bitwise_and(mask, other, both);
  cv::bitwise_or(mask, other, either);
  EXPECT_NEAR(renderer.IoU(moved, camera, mask),
              cv::countNonZero(both) / double(cv::countNonZero(either)), 1e-12);
  EXPECT_LT(renderer.IoU(moved, camera, mask), 0.9);
}

TEST(PoseSelection, ClustersAreFoundAndTheBestSilhouetteWins) {
  PoseSelectionConfig c;
  std::mt19937_64 rng(4);
  std::normal_distribution<double> jitter(0, 0.002);
  const Pose true_pose{Quat::Identity(), Vec3(0, 0, 0.5)};
  const Pose flip{Quat(Eigen::AngleAxisd(kPi, Vec3::UnitY())), Vec3(0, 0, 0.5)};
  std::vector<Pose> poses;
  for (int i = 0; i < 10; ++i) poses.push_back({flip.q, flip.t + Vec3(jitter(rng), jitter(rng), 0)});
  for (int i = 0; i < 8; ++i) poses.push_back({true_pose.q, true_pose.t + Vec3(jitter(rng), 0, 0)});
  for (int i = 0; i < 7; ++i) poses.push_back({Quat::UnitRandom(), Vec3(0.3 * i, 0.1, 0.5)});
  EXPECT_NEAR(PoseDistance(true_pose, flip, c), 0.05 * kPi, 1e-9);
  const auto clusters = ClusterPoses(poses, c);
  ASSERT_GE(clusters.size(), 2u + 7u);
  EXPECT_EQ(clusters[0].size(), 10u);
  EXPECT_EQ(clusters[1].size(), 8u);
  // The silhouette prefers the true pose over the (larger) flip cluster.
  const PoseChoice choice = SelectByClustering(poses, c, [&](const Pose& p) {
    return PoseDistance(p, true_pose, c) < 0.02 ? 0.9 : 0.6;
  });
  EXPECT_GE(choice.index, 10);
  EXPECT_LT(choice.index, 18);
  EXPECT_EQ(choice.cluster_size, 8);
  EXPECT_EQ(choice.clusters, 2);
  EXPECT_FALSE(choice.outliers_only);
  EXPECT_EQ(SelectByLikelihood(Eigen::Vector3d(-3, 2, 1)).index, 1);
  EXPECT_EQ(SelectRandom(25, 7, 3).index, SelectRandom(25, 7, 3).index);
}

TEST(ObjectTracker, FollowsAMovingMode) {
  // The true pose slides 1 cm per frame; a lighter decoy mode sits 0.5 rad
  // away.
  FlowLayout layout{.shape_dim = 2};
  std::vector<Mixture> frames;
  for (int k = 0; k < 12; ++k) {
    Eigen::VectorXd good(9), decoy(9);
    const Quat turned(Eigen::AngleAxisd(0.5, Vec3::UnitZ()));
    good << 0.4, 0.1, 0.01 * k, 0, 0.5, 1, 0, 0, 0;
    decoy << 0.4, 0.1, 0.01 * k, 0, 0.5, turned.w(), turned.x(), turned.y(), turned.z();
    frames.push_back({{1.0, good, 0.01}, {0.3, decoy, 0.01}});
  }
  GaussianMixtureFlow model(layout, frames);
  TrackInputs inputs{.pose_guidance = std::vector<double>(12, 0.5)};
  const auto track = TrackObject(model, 12, inputs, {}, {.method = kSelectLikelihood});
  ASSERT_EQ(track.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    EXPECT_NEAR(track[k].pose.t.x(), 0.01 * k, 0.01) << k;
    EXPECT_LT(RotationAngle(track[k].pose.q, Quat::Identity()), 0.1) << k;
    EXPECT_EQ(track[k].candidates.size(), 25u);
  }
}

// A mixture that notes which threads called it and the largest batch.
class WatchedMixture : public GaussianMixtureFlow {
 public:
  using GaussianMixtureFlow::GaussianMixtureFlow;
  void Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) override {
    {
      std::lock_guard<std::mutex> lock(mutex);
      callers.insert(std::this_thread::get_id());
      largest_batch = std::max<int>(largest_batch, x.rows());
    }
    GaussianMixtureFlow::Velocity(frame, t, x, v);
  }
  std::mutex mutex;
  std::set<std::thread::id> callers;
  int largest_batch = 0;
};

TEST(ObjectTracker, TracksDoNotDependOnTheThreadCount) {
  FlowLayout layout{.shape_dim = 2};
  std::vector<Mixture> frames;
  for (int k = 0; k < 6; ++k) {
    Eigen::VectorXd a(9), b(9);
    a << 0.4, 0.1, 0.01 * k, 0, 0.5, 1, 0, 0, 0;
    b << 0.4, 0.1, 0.01 * k + 0.05, 0, 0.5, 0, 0, 0, 1;
    frames.push_back({{1.0, a, 0.02}, {0.6, b, 0.02}});
  }
  TrackInputs inputs{.pose_guidance = std::vector<double>(6, 0.4)};
  // A stand-in silhouette score: closeness to mode a.
  inputs.silhouette_iou = [](int k, const Pose& p) {
    return 1.0 / (1.0 + (p.t - Vec3(0.01 * k, 0, 0.5)).norm());
  };
  for (const char* method : {kSelectClustering, kSelectLikelihood}) {
    std::vector<std::vector<TrackedFrame>> runs;
    for (int threads : {1, 2, 3}) {
      WatchedMixture model(layout, frames);
      GuidedFlowConfig flow;
      flow.threads = threads;
      flow.seed = 9;
      runs.push_back(TrackObject(model, 6, inputs, flow, {.method = method}));
      // Which threads claim the blocks is up to the scheduler; how the rows
      // are split is not.
      EXPECT_LE(static_cast<int>(model.callers.size()), threads) << method;
      EXPECT_EQ(model.largest_batch, 8) << method << " the same row blocks for any thread count";
    }
    for (size_t r = 1; r < runs.size(); ++r) {
      for (int k = 0; k < 6; ++k) {
        EXPECT_EQ(runs[r][k].choice.index, runs[0][k].choice.index) << method << " frame " << k;
        EXPECT_EQ(runs[r][k].pose.t, runs[0][k].pose.t) << method << " frame " << k;
        EXPECT_EQ(runs[r][k].pose.q.coeffs(), runs[0][k].pose.q.coeffs()) << method << " frame " << k;
        EXPECT_EQ(runs[r][k].choice.score, runs[0][k].choice.score) << method << " frame " << k;
      }
    }
  }
}

}  // namespace
}  // namespace doasido::recon
