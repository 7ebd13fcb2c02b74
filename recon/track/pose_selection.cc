#include "recon/track/pose_selection.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/config_check.h"
#include "core/error.h"

namespace doasido::recon {

void CheckConfig(const PoseSelectionConfig& c, const std::string& section) {
  RequireOneOf(section, "method", c.method, {kSelectClustering, kSelectLikelihood, kSelectRandom});
  RequireInRange(section, "translation_weight", c.translation_weight, 0, 1e6);
  RequireInRange(section, "rotation_weight", c.rotation_weight, 0, 1e6);
  RequireInRange(section, "link_distance", c.link_distance, 1e-9, 1e6);
  RequireInRange(section, "min_cluster_size", c.min_cluster_size, 1, 1 << 20);
  RequireInRange(section, "iou_tolerance", c.iou_tolerance, 0, 1);
  RequireInRange(section, "silhouette_stride", c.silhouette_stride, 1, 64);
}

double PoseDistance(const Pose& a, const Pose& b, const PoseSelectionConfig& c) {
  const double dot = std::min(1.0, std::abs(a.q.normalized().dot(b.q.normalized())));
  return c.translation_weight * (a.t - b.t).norm() + c.rotation_weight * 2 * std::acos(dot);
}

std::vector<std::vector<int>> ClusterPoses(const std::vector<Pose>& poses,
                                           const PoseSelectionConfig& c) {
  const int n = static_cast<int>(poses.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const std::function<int(int)> root = [&](int i) {
    return parent[i] == i ? i : parent[i] = root(parent[i]);
  };
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (PoseDistance(poses[i], poses[j], c) <= c.link_distance) parent[root(i)] = root(j);
    }
  }
  std::vector<std::vector<int>> by_root(n);
  for (int i = 0; i < n; ++i) by_root[root(i)].push_back(i);
  std::vector<std::vector<int>> clusters;
  for (auto& members : by_root) {
    if (!members.empty()) clusters.push_back(std::move(members));
  }
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return clusters;
}

int Medoid(const std::vector<Pose>& poses, const std::vector<int>& cluster,
           const PoseSelectionConfig& c) {
  int best = cluster.at(0);
  double best_sum = INFINITY;
  for (int i : cluster) {
    double sum = 0;
    for (int j : cluster) sum += PoseDistance(poses[i], poses[j], c);
    if (sum < best_sum) {
      best_sum = sum;
      best = i;
    }
  }
  return best;
}

PoseChoice SelectByClustering(const std::vector<Pose>& poses, const PoseSelectionConfig& c,
                              const std::function<double(const Pose&)>& silhouette_iou,
                              TaskPool* pool) {
  if (poses.empty()) throw Error("bad_candidates", "no candidate pose to select from");
  const auto clusters = ClusterPoses(poses, c);
  struct Ranked {
    int medoid;
    double iou;
    int size;
  };
  std::vector<Ranked> ranked;
  double best_iou = -INFINITY;
  for (const auto& cluster : clusters) {
    if (static_cast<int>(cluster.size()) < c.min_cluster_size) continue;
    ranked.push_back({Medoid(poses, cluster, c), 0.0, static_cast<int>(cluster.size())});
  }
  const auto score = [&](int i, int) { ranked[i].iou = silhouette_iou(poses[ranked[i].medoid]); };
  if (pool) {
    pool->Run(static_cast<int>(ranked.size()), score);
  } else {
    for (size_t i = 0; i < ranked.size(); ++i) score(static_cast<int>(i), 0);
  }
  for (const Ranked& r : ranked) best_iou = std::max(best_iou, r.iou);
  PoseChoice out;
  // Clusters come largest first: the first within the tolerance wins.
  for (const Ranked& r : ranked) {
    if (r.iou >= best_iou - c.iou_tolerance) {
      out = {r.medoid, r.iou, r.size, 0, false};
      break;
    }
  }
  out.clusters = static_cast<int>(ranked.size());
  if (out.index < 0) {
    const int medoid = Medoid(poses, clusters.front(), c);
    out = {medoid, silhouette_iou(poses[medoid]), static_cast<int>(clusters.front().size()), 0,
           true};
  }
  return out;
}

PoseChoice SelectByLikelihood(const Eigen::VectorXd& log_likelihood) {
  if (log_likelihood.size() == 0) throw Error("bad_candidates", "no candidate pose to select from");
  PoseChoice out;
  Eigen::Index best = 0;
  out.score = log_likelihood.maxCoeff(&best);
  out.index = static_cast<int>(best);
  return out;
}

PoseChoice SelectRandom(int n, std::uint64_t seed, int frame) {
  if (n < 1) throw Error("bad_candidates", "no candidate pose to select from");
  std::mt19937_64 rng(seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(frame));
  PoseChoice out;
  out.index = std::uniform_int_distribution<int>(0, n - 1)(rng);
  return out;
}

}  // namespace doasido::recon
