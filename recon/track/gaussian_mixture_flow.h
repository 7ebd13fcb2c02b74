// The in-process stand-in for the object model: per frame, a mixture of
// isotropic Gaussians over the whole state (shape and pose blocks), whose
// flow along the linear path has a closed-form marginal velocity and
// divergence. The synthetic world (synth/tracking_scene.h) places the modes
// from ground truth: the true pose, its symmetric flip, clutter.
//
// For x_1 ~ sum_k pi_k N(mu_k, s_k^2 I) and x_0 ~ N(0, I), the marginal at t
// is sum_k pi_k N(t mu_k, var_k I) with var_k = (1-t)^2 + t^2 s_k^2, and
//   v(x, t) = sum_k w_k(x, t) (mu_k + c_k (x - t mu_k)),
//   c_k = (t s_k^2 - (1 - t)) / var_k,
// w_k the posterior weight of mode k at (x, t): E[x_1 - x_0 | x_t = x].
#pragma once

#include <vector>

#include "recon/track/velocity_field.h"

namespace doasido::recon {

struct MixtureMode {
  double weight = 1;      // > 0; the modes of a frame are normalised together
  Eigen::VectorXd mean;   // Layout().dim() values
  double sigma = 0.01;    // > 0, the same on every coordinate
};

using Mixture = std::vector<MixtureMode>;

class GaussianMixtureFlow : public VelocityField {
 public:
  // One mixture per frame. Throws Error("bad_model") for an empty mixture, a
  // mean of the wrong size, or a weight or sigma that is not > 0.
  GaussianMixtureFlow(FlowLayout layout, std::vector<Mixture> frames);

  FlowLayout Layout() const override { return layout_; }
  void Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) override;
  void PoseDivergence(int frame, double t, const StateMatrix& x, Eigen::VectorXd* div) override;
  bool ConcurrentRows() const override { return true; }

  // log p_1(x) of the whole state, in closed form (what likelihood ranking
  // estimates by integrating the flow backward).
  double LogDensity(int frame, const Eigen::Ref<const Eigen::RowVectorXd>& x) const;

  int frames() const { return static_cast<int>(frames_.size()); }
  const Mixture& mixture(int frame) const;

 private:
  // Posterior weights w_k of one state at t, and var_k.
  void Posterior(const Mixture& m, double t, const Eigen::Ref<const Eigen::RowVectorXd>& x,
                 Eigen::VectorXd* w, Eigen::VectorXd* var) const;

  FlowLayout layout_;
  std::vector<Mixture> frames_;
};

}  // namespace doasido::recon
