#include "deploy/placement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/progress.h"
#include "deploy/time_scaling.h"

namespace doasido::deploy {
namespace {

struct Score {
  int reached = -1;
  double cost = std::numeric_limits<double>::infinity();
  double error = std::numeric_limits<double>::infinity();
  double slowdown = 0, manipulability = 0;

  bool Beats(const Score& o) const {
    if (reached != o.reached) return reached > o.reached;
    if (std::abs(cost - o.cost) > 1e-9) return cost < o.cost;
    return error < o.error - 1e-9;
  }
};

Score ScoreCandidate(const Pose& place, const std::vector<Pose>& wrists, double fps, const PlanConfig& config,
                     ArmIk& ik) {
  const WorkspaceConfig& w = config.workspace;
  const int frames = std::min<int>(w.search_frames, wrists.size());
  const ArmLimits& limits = ik.limits();
  Score score;
  score.reached = 0;
  score.error = 0;
  score.manipulability = std::numeric_limits<double>::infinity();
  ArmQ q = Eigen::Map<const ArmQ>(config.home.data());
  std::vector<double> knots;
  std::vector<Eigen::VectorXd> path;
  for (int s = 0; s < frames; ++s) {
    const size_t f = frames == 1 ? 0 : s * (wrists.size() - 1) / (frames - 1);
    const IkResult r = ik.Solve(place * wrists[f], q);
    score.reached += r.reached;
    score.error += r.position_error + ik.config().rot_scale * r.rotation_error;
    if (r.reached) q = r.q;
    if (!knots.empty() && f / fps <= knots.back()) continue;
    knots.push_back(f / fps);
    path.push_back(r.q);
    score.manipulability = std::min(score.manipulability, Manipulability(r.q));
  }
  const Eigen::VectorXd vmax = Eigen::Map<const Eigen::VectorXd>(limits.max_speed.data(), 6);
  const Eigen::VectorXd amax = Eigen::Map<const Eigen::VectorXd>(limits.max_acceleration.data(), 6);
  score.slowdown = RetimePath(JointSpline(knots, path), vmax, amax, config.rate_hz, config.time_scaling,
                              config.time_scaling.margin).slowdown;
  const double floor = w.manipulability_floor;
  const double penalty = floor > 0 ? std::max(0.0, floor - score.manipulability) / floor : 0.0;
  score.cost = std::max(score.slowdown, 1.0) * (1 + penalty);
  return score;
}

}  // namespace

std::vector<Placement> RankPlacements(const std::vector<Pose>& wrists, double fps, const PlanConfig& config) {
  const WorkspaceConfig& w = config.workspace;
  IkConfig ik_config = config.ik;
  ik_config.restarts = w.search_restarts;
  ArmIk ik(ik_config);
  std::vector<std::pair<Score, Placement>> scored;
  const int frames = std::min<int>(w.search_frames, wrists.size());
  Progress progress("placement", w.yaw_steps * w.offset_steps * w.offset_steps);
  const auto offset = [&](int i) {
    return w.offset_steps == 1 ? 0.0 : w.offset_range * (2.0 * i / (w.offset_steps - 1) - 1);
  };
  for (int k = 0; k < w.yaw_steps; ++k) {
    // Yaws alternate around the default: 0, +step, -step, +2 step, ...
    const int signed_k = (k + 1) / 2 * (k % 2 ? 1 : -1);
    const double yaw = w.yaw + signed_k * 2 * std::numbers::pi / w.yaw_steps;
    for (int ix = 0; ix < w.offset_steps; ++ix) {
      for (int iy = 0; iy < w.offset_steps; ++iy) {
        const double x = w.x + offset(ix), y = w.y + offset(iy);
        const Pose place = PlacementPose(yaw, x, y, wrists, w.base_height);
        const Score score = ScoreCandidate(place, wrists, fps, config, ik);
        progress.Add();
        scored.push_back({score, {.yaw = yaw, .x = x, .y = y, .world_to_base = place,
                                  .reachable_fraction = static_cast<double>(score.reached) / frames,
                                  .search_slowdown = score.slowdown, .manipulability = score.manipulability}});
      }
    }
  }
  progress.Finish();
  // Best first: the first candidate no later one beats (ties go to the
  // default-nearer), then the rest by score.
  size_t best = 0;
  for (size_t i = 1; i < scored.size(); ++i) {
    if (scored[i].first.Beats(scored[best].first)) best = i;
  }
  std::rotate(scored.begin(), scored.begin() + best, scored.begin() + best + 1);
  std::stable_sort(scored.begin() + 1, scored.end(), [](const auto& a, const auto& b) { return a.first.Beats(b.first); });
  std::vector<Placement> ranked;
  for (auto& [score, placement] : scored) {
    placement.candidates = static_cast<int>(scored.size());
    ranked.push_back(placement);
  }
  return ranked;
}

Placement SearchPlacement(const std::vector<Pose>& wrists, double fps, const PlanConfig& config) {
  return RankPlacements(wrists, fps, config).front();
}

}  // namespace doasido::deploy
