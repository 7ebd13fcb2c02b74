// Alignment before reconstruction metrics (REFERENCE.md §4 alignment
// modes): none (camera frame, as given), hand-root frame (each surface
// expressed relative to its own hand's wrist), rigid ICP, and multi-start
// Sim(3) ICP (rotation, translation and scale, started from the 24
// axis-aligned rotations so a flipped or turned prediction is still found).
// Metrics are then taken on the aligned prediction; per-frame results are
// summarised by mean and median.
#pragma once

#include <string>
#include <vector>

#include "core/config.h"
#include "core/geometry.h"
#include "core/mesh.h"
#include "recon/recon_metrics.h"

namespace doasido::recon {

// x -> s * R * x + t.
struct Similarity {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  double s = 1.0;

  Vec3 operator*(const Vec3& x) const { return s * (R * x) + t; }
  Points3 Apply(const Points3& points) const;
};

// Least-squares similarity (Umeyama 1991) taking src[i] onto dst[i]:
// minimises sum |dst_i - (s R src_i + t)|^2 over rotations R (det +1),
// translations t and, when `with_scale`, scales s > 0 (else s = 1).
// Requires equal row counts >= 3 and non-degenerate (non-collinear) src.
Similarity Umeyama(const Points3& src, const Points3& dst, bool with_scale);

struct IcpConfig {
  int max_iterations = 60;
  double tolerance = 1e-9;  // stop when the RMS distance improves by less (metres)
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(IcpConfig, max_iterations, tolerance)

struct IcpResult {
  Similarity transform;  // takes src onto dst
  double rms = 0;        // RMS nearest-neighbour distance after alignment, metres
  int iterations = 0;
};

// Point-to-point ICP of src onto dst from `init`, rigid or with scale. Each
// iteration pairs every src point with its nearest dst point and every dst
// point with its nearest moved src point (k-d trees), then solves Umeyama on
// all pairs; the two-way pairing keeps a free scale from collapsing. `rms`
// is over both pair sets. Stops when the RMS stops improving by
// config.tolerance.
IcpResult Icp(const Points3& src, const Points3& dst, const Similarity& init, bool with_scale,
              const IcpConfig& config = {});

// Sim(3) ICP started from each of the 24 proper axis-aligned rotations about
// the centroids with the RMS-radius scale ratio (on subsamples of ~1500
// points, 20 iterations each), the best start refined on all points.
IcpResult MultiStartSim3(const Points3& src, const Points3& dst, const IcpConfig& config = {});

enum class AlignMode { kNone, kHandRoot, kIcp, kSim3 };
// "none", "hand_root", "icp", "sim3"; Parse throws Error("bad_config").
std::string AlignModeName(AlignMode mode);
AlignMode ParseAlignMode(const std::string& name);

// Metrics of `pred` against `gt` after alignment. For kHandRoot,
// `pred_root` and `gt_root` are the wrist poses (wrist -> camera) of the
// predicted and true hand: each surface is moved into its own wrist frame.
// Sampling follows `config` (pred seed, gt seed + 1), and ICP runs on the
// samples.
ReconMetrics CompareAligned(const TriMesh& pred, const TriMesh& gt, AlignMode mode,
                            const ReconMetricsConfig& config = {},
                            const Pose& pred_root = Pose::Identity(),
                            const Pose& gt_root = Pose::Identity());

// Per-field mean and median over frames:
// {"f_5mm": {"mean": ..., "median": ...}, ..., "frames": N}.
Json SummariseMetrics(const std::vector<ReconMetrics>& per_frame);

}  // namespace doasido::recon
