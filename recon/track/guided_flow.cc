#include "recon/track/guided_flow.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/config_check.h"
#include "core/error.h"
#include "core/geometry.h"
#include "core/stage_progress.h"

namespace doasido::recon {
namespace {

std::uint64_t Mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a * 0x9e3779b97f4a7c15ULL + b + 0x632be59bd9b4e019ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A model with ConcurrentRows is called on blocks of this many rows, on
// the pool's threads or one after another: the same blocks for any thread
// count, so the same floating-point results (a batched product's rounding
// may depend on the batch's size).
constexpr Eigen::Index kRowBlock = 8;

template <typename Call>
void ByRowBlocks(const VelocityField& model, TaskPool* pool, Eigen::Index rows, const Call& call) {
  if (!model.ConcurrentRows() || rows <= kRowBlock) {
    call(0, rows);
    return;
  }
  const int blocks = static_cast<int>((rows + kRowBlock - 1) / kRowBlock);
  const auto block = [&](int b, int) {
    const Eigen::Index begin = b * kRowBlock;
    call(begin, std::min(kRowBlock, rows - begin));
  };
  if (pool && pool->threads() > 1) {
    pool->Run(blocks, block);
  } else {
    for (int b = 0; b < blocks; ++b) block(b, 0);
  }
}

void Velocity(VelocityField& model, TaskPool* pool, int frame, double t, const StateMatrix& x,
              StateMatrix* v) {
  v->resize(x.rows(), x.cols());
  ByRowBlocks(model, pool, x.rows(), [&](Eigen::Index begin, Eigen::Index n) {
    if (n == x.rows()) return model.Velocity(frame, t, x, v);
    StateMatrix part;
    model.Velocity(frame, t, x.middleRows(begin, n), &part);
    v->middleRows(begin, n) = part;
  });
}

void PoseDivergence(VelocityField& model, TaskPool* pool, int frame, double t,
                    const StateMatrix& x, Eigen::VectorXd* div) {
  div->resize(x.rows());
  ByRowBlocks(model, pool, x.rows(), [&](Eigen::Index begin, Eigen::Index n) {
    if (n == x.rows()) return model.PoseDivergence(frame, t, x, div);
    Eigen::VectorXd part;
    model.PoseDivergence(frame, t, x.middleRows(begin, n), &part);
    div->segment(begin, n) = part;
  });
}

}  // namespace

void CheckConfig(const GuidedFlowConfig& c, const std::string& section) {
  RequireInRange(section, "candidates", c.candidates, 1, 4096);
  RequireInRange(section, "steps", c.steps, 1, 10000);
  RequireInRange(section, "shape_guidance", c.shape_guidance, 0, 1);
  RequireInRange(section, "threads", c.threads, 1, 256);
}

StateMatrix SampleGuided(VelocityField& model, int frame, const GuidedTargets& targets,
                         int candidates, int steps, std::uint64_t seed, TaskPool* pool) {
  const FlowLayout layout = model.Layout();
  if (targets.shape.size() != layout.shape_dim || targets.pose.size() != layout.pose_dim) {
    throw Error("bad_model", "the guidance targets have " + std::to_string(targets.shape.size()) +
                                 " shape and " + std::to_string(targets.pose.size()) +
                                 " pose values; the model " + std::to_string(layout.shape_dim) +
                                 " and " + std::to_string(layout.pose_dim));
  }
  std::mt19937_64 rng(Mix(seed, static_cast<std::uint64_t>(frame)));
  std::normal_distribution<double> normal;
  StateMatrix eps(candidates, layout.dim());
  for (Eigen::Index i = 0; i < eps.size(); ++i) eps.data()[i] = normal(rng);
  Eigen::RowVectorXd target(layout.dim());
  target << targets.shape.transpose(), targets.pose.transpose();
  Eigen::RowVectorXd alpha(layout.dim());
  alpha.head(layout.shape_dim).setConstant(targets.shape_guidance);
  alpha.tail(layout.pose_dim).setConstant(targets.pose_guidance);

  StateMatrix x = eps, v;
  const double dt = 1.0 / steps;
  for (int j = 1; j <= steps; ++j) {
    const double t = j * dt;
    Velocity(model, pool, frame, t - dt, x, &v);
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const Eigen::RowVectorXd free = x.row(i) + dt * v.row(i);
      const Eigen::RowVectorXd ref = (1 - t) * eps.row(i) + t * target;
      x.row(i) = (1 - alpha.array()) * free.array() + alpha.array() * ref.array();
    }
    ReportStageProgress();
  }
  return x;
}

Eigen::VectorXd PoseLogLikelihood(VelocityField& model, int frame, const StateMatrix& x1,
                                  int steps, TaskPool* pool) {
  const FlowLayout layout = model.Layout();
  StateMatrix x = x1, v;
  Eigen::VectorXd div, integral = Eigen::VectorXd::Zero(x.rows());
  const double dt = 1.0 / steps;
  for (int j = steps; j >= 1; --j) {
    const double t = j * dt;
    Velocity(model, pool, frame, t, x, &v);
    PoseDivergence(model, pool, frame, t, x, &div);
    integral += dt * div;
    x -= dt * v;
    ReportStageProgress();
  }
  Eigen::VectorXd out(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double r2 = x.row(i).tail(layout.pose_dim).squaredNorm();
    out[i] = -0.5 * (layout.pose_dim * kLog2Pi + r2) - integral[i];
  }
  return out;
}

}  // namespace doasido::recon
