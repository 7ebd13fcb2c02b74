// Picking one of a frame's N candidate poses (seed appendix, "Sampling
// Per-frame Poses"):
//   clustering  candidates linked under the weighted SE(3) distance
//               d = w_t |t_i - t_j| + w_r 2 acos |<q_i, q_j>|   (eq. 3)
//               (single linkage at `link_distance`); clusters smaller than
//               `min_cluster_size` are outliers; the remaining clusters are
//               ranked by the silhouette IoU of their medoid pose against
//               the object mask; the best cluster's medoid is the pose.
//               IoUs within `iou_tolerance` of the best count as a tie,
//               won by the larger cluster: a symmetric object's flip differs
//               from the true pose by a handle's few pixels, less than the
//               masks' own noise, and the seed's observation that confident
//               samples concentrate on one mode makes size the tie-break.
//   likelihood  the candidate of highest log p(pose | shape, frame)
//               (recon/track/guided_flow.h PoseLogLikelihood): the principled
//               choice, ~(1 + pose_dim) times the sampling's model calls.
//   random      one candidate uniformly at random (the ablation's floor).
// The seed gives neither the weights nor the cluster parameters; ours: one
// radian counts as 5 cm, clusters link within 2 cm, and need 3 of 25.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "core/task_pool.h"

namespace doasido::recon {

inline constexpr const char* kSelectClustering = "clustering";
inline constexpr const char* kSelectLikelihood = "likelihood";
inline constexpr const char* kSelectRandom = "random";

struct PoseSelectionConfig {
  std::string method = kSelectClustering;
  double translation_weight = 1.0;   // w_t per metre
  double rotation_weight = 0.05;     // w_r per radian (metres per radian)
  double link_distance = 0.02;       // single-linkage threshold, in d's units
  int min_cluster_size = 3;
  double iou_tolerance = 0.02;       // IoUs this close to the best tie (larger cluster wins)
  int silhouette_stride = 2;         // pixels between silhouette rays
  std::uint64_t seed = 0;            // for `random`
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(PoseSelectionConfig, method, translation_weight,
                                                rotation_weight, link_distance, min_cluster_size,
                                                iou_tolerance, silhouette_stride, seed)

void CheckConfig(const PoseSelectionConfig& c, const std::string& section);

// Eq. 3 (q and -q are the same rotation).
double PoseDistance(const Pose& a, const Pose& b, const PoseSelectionConfig& c);

// Single-linkage clusters of `poses` (indices), largest first.
std::vector<std::vector<int>> ClusterPoses(const std::vector<Pose>& poses,
                                           const PoseSelectionConfig& c);

// The member of `cluster` with the least summed distance to the others.
int Medoid(const std::vector<Pose>& poses, const std::vector<int>& cluster,
           const PoseSelectionConfig& c);

struct PoseChoice {
  int index = -1;          // the chosen candidate
  double score = 0;        // silhouette IoU / log-likelihood / 0
  int cluster_size = 0;    // clustering: members of the chosen cluster
  int clusters = 0;        // clustering: clusters of at least min size
  bool outliers_only = false;  // clustering: no cluster was large enough; the largest was used
};

// Clustering selection; `silhouette_iou(pose)` scores a medoid. With `pool`
// the medoids are scored on its threads (so silhouette_iou must be safe to
// call concurrently); the choice is the same.
PoseChoice SelectByClustering(const std::vector<Pose>& poses, const PoseSelectionConfig& c,
                              const std::function<double(const Pose&)>& silhouette_iou,
                              TaskPool* pool = nullptr);

// The candidate of highest log-likelihood.
PoseChoice SelectByLikelihood(const Eigen::VectorXd& log_likelihood);

// One of `n` candidates at random, deterministic for (seed, frame).
PoseChoice SelectRandom(int n, std::uint64_t seed, int frame);

}  // namespace doasido::recon
