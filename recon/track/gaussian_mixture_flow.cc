#include "recon/track/gaussian_mixture_flow.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/geometry.h"

namespace doasido::recon {
namespace {

}  // namespace

GaussianMixtureFlow::GaussianMixtureFlow(FlowLayout layout, std::vector<Mixture> frames)
    : layout_(layout), frames_(std::move(frames)) {
  for (size_t f = 0; f < frames_.size(); ++f) {
    const std::string where = "frame " + std::to_string(f);
    if (frames_[f].empty()) throw Error("bad_model", where + " has no mixture mode");
    double total = 0;
    for (const MixtureMode& m : frames_[f]) {
      if (m.mean.size() != layout_.dim()) {
        throw Error("bad_model", where + ": a mode mean has " + std::to_string(m.mean.size()) +
                                     " values, the state " + std::to_string(layout_.dim()));
      }
      if (!(m.weight > 0) || !(m.sigma > 0) || !m.mean.allFinite()) {
        throw Error("bad_model", where + ": mode weights and sigmas must be > 0 and means finite");
      }
      total += m.weight;
    }
    for (MixtureMode& m : frames_[f]) m.weight /= total;
  }
}

const Mixture& GaussianMixtureFlow::mixture(int frame) const {
  if (frame < 0 || frame >= frames()) {
    throw Error("bad_model", "frame " + std::to_string(frame) + " is outside the model's " +
                                 std::to_string(frames()) + " frames");
  }
  return frames_[frame];
}

void GaussianMixtureFlow::Posterior(const Mixture& m, double t,
                                    const Eigen::Ref<const Eigen::RowVectorXd>& x,
                                    Eigen::VectorXd* w, Eigen::VectorXd* var) const {
  const int K = static_cast<int>(m.size());
  w->resize(K);
  var->resize(K);
  const double D = layout_.dim();
  for (int k = 0; k < K; ++k) {
    const double s2 = m[k].sigma * m[k].sigma;
    (*var)[k] = (1 - t) * (1 - t) + t * t * s2;
    const double r2 = (x.transpose() - t * m[k].mean).squaredNorm();
    (*w)[k] = std::log(m[k].weight) - 0.5 * D * std::log((*var)[k]) - 0.5 * r2 / (*var)[k];
  }
  const double top = w->maxCoeff();
  *w = (w->array() - top).exp();
  *w /= w->sum();
}

void GaussianMixtureFlow::Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) {
  const Mixture& m = mixture(frame);
  v->setZero(x.rows(), layout_.dim());
  Eigen::VectorXd w, var;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Posterior(m, t, x.row(i), &w, &var);
    for (size_t k = 0; k < m.size(); ++k) {
      const double c = (t * m[k].sigma * m[k].sigma - (1 - t)) / var[k];
      v->row(i) += w[k] * (m[k].mean.transpose() + c * (x.row(i) - t * m[k].mean.transpose()));
    }
  }
}

// d v / d x = sum_k w_k c_k I + sum_k u_k (grad w_k)^T with
// grad w_k = w_k (g_k - sum_j w_j g_j), g_k = -(x - t mu_k) / var_k; the
// trace over the pose block follows.
void GaussianMixtureFlow::PoseDivergence(int frame, double t, const StateMatrix& x,
                                         Eigen::VectorXd* div) {
  const Mixture& m = mixture(frame);
  const int K = static_cast<int>(m.size()), p0 = layout_.shape_dim, P = layout_.pose_dim;
  div->setZero(x.rows());
  Eigen::VectorXd w, var;
  Eigen::MatrixXd u(K, P), g(K, P);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Posterior(m, t, x.row(i), &w, &var);
    const Eigen::RowVectorXd xp = x.row(i).segment(p0, P);
    Eigen::RowVectorXd g_mean = Eigen::RowVectorXd::Zero(P);
    double scalar = 0;
    for (int k = 0; k < K; ++k) {
      const Eigen::RowVectorXd mu = m[k].mean.segment(p0, P).transpose();
      const double c = (t * m[k].sigma * m[k].sigma - (1 - t)) / var[k];
      u.row(k) = mu + c * (xp - t * mu);
      g.row(k) = -(xp - t * mu) / var[k];
      g_mean += w[k] * g.row(k);
      scalar += w[k] * c;
    }
    double cross = 0;
    for (int k = 0; k < K; ++k) cross += w[k] * u.row(k).dot(g.row(k) - g_mean);
    (*div)[i] = P * scalar + cross;
  }
}

double GaussianMixtureFlow::LogDensity(int frame,
                                       const Eigen::Ref<const Eigen::RowVectorXd>& x) const {
  const Mixture& m = mixture(frame);
  const double D = layout_.dim();
  double top = -INFINITY;
  std::vector<double> terms;
  for (const MixtureMode& mode : m) {
    const double s2 = mode.sigma * mode.sigma;
    terms.push_back(std::log(mode.weight) - 0.5 * D * (kLog2Pi + std::log(s2)) -
                    0.5 * (x.transpose() - mode.mean).squaredNorm() / s2);
    top = std::max(top, terms.back());
  }
  double sum = 0;
  for (double v : terms) sum += std::exp(v - top);
  return top + std::log(sum);
}

}  // namespace doasido::recon
