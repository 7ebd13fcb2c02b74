// Reconstruction-metric cost at the published sample count (10k points per
// surface): the k-d tree nearest-neighbour pass against brute force (Eigen,
// all pairs) on the same points, the whole CompareSurfaces on a YCB mesh, and
// the same after multi-start Sim(3) alignment.
// Prints the speed ratio kd-tree : brute force measured in this run.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <benchmark/benchmark.h>

#include "core/mesh.h"
#include "eval/alignment.h"
#include "recon/recon_metrics.h"

namespace doasido::recon {
namespace {

TriMesh Mustard() {
  return LoadMesh(std::filesystem::path(DOASIDO_SHARED_DATA) / "meshes" / "ycb" /
                  "006_mustard_bottle_textured.obj");
}

std::vector<double> BruteForce(const Points3& set, const Points3& queries) {
  std::vector<double> out(static_cast<size_t>(queries.rows()));
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    out[static_cast<size_t>(q)] =
        std::sqrt((set.rowwise() - queries.row(q)).rowwise().squaredNorm().minCoeff());
  }
  return out;
}

struct Sets {
  Points3 a, b;
};
const Sets& Points() {
  static const Sets sets = [] {
    const TriMesh m = Mustard();
    return Sets{SampleSurface(m, 10000, 1), SampleSurface(m, 10000, 2)};
  }();
  return sets;
}

void BM_NearestKdTree(benchmark::State& state) {
  for (auto _ : state) {
    benchmark::DoNotOptimize(NearestNeighbours(Points().a).Distances(Points().b));
  }
}
BENCHMARK(BM_NearestKdTree)->Unit(benchmark::kMillisecond);

void BM_NearestBruteForce(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(BruteForce(Points().a, Points().b));
}
BENCHMARK(BM_NearestBruteForce)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_CompareSurfaces10k(benchmark::State& state) {
  const TriMesh m = Mustard();
  const TriMesh moved = m.Transformed(Pose{Quat::Identity(), Vec3(0.003, 0, 0)});
  for (auto _ : state) benchmark::DoNotOptimize(CompareSurfaces(moved, m));
}
BENCHMARK(BM_CompareSurfaces10k)->Unit(benchmark::kMillisecond);

// The mustard bottle turned by 2.5 rad, shifted 5 cm and scaled by 1.2.
TriMesh MovedMustard() {
  return Mustard().Transformed(
      Pose{Quat(Eigen::AngleAxisd(2.5, Vec3(1, 1, 0).normalized())), Vec3(0.05, 0, 0)}, 1.2);
}

void BM_CompareAlignedSim3(benchmark::State& state) {
  const TriMesh m = Mustard(), moved = MovedMustard();
  for (auto _ : state) benchmark::DoNotOptimize(CompareAligned(moved, m, AlignMode::kSim3));
}
BENCHMARK(BM_CompareAlignedSim3)->Unit(benchmark::kMillisecond);

template <typename F>
double Seconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace
}  // namespace doasido::recon

int main(int argc, char** argv) {
  using namespace doasido::recon;
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  const auto& p = Points();
  std::vector<double> kd, brute;
  const double t_kd = Seconds([&] { kd = NearestNeighbours(p.a).Distances(p.b); });
  const double t_brute = Seconds([&] { brute = BruteForce(p.a, p.b); });
  double max_diff = 0;
  for (size_t i = 0; i < kd.size(); ++i) max_diff = std::max(max_diff, std::abs(kd[i] - brute[i]));
  std::printf("nearest neighbours, 10k x 10k mustard-bottle samples: kd-tree %.1f ms, brute "
              "force %.1f ms, speed-up x%.1f, max |difference| %.3g m\n",
              1e3 * t_kd, 1e3 * t_brute, t_brute / t_kd, max_diff);
  const doasido::TriMesh m = Mustard(), moved = MovedMustard();
  for (AlignMode mode : {AlignMode::kNone, AlignMode::kIcp, AlignMode::kSim3}) {
    const ReconMetrics r = CompareAligned(moved, m, mode);
    std::printf("moved mustard bottle vs original, align %-5s: F@5mm %.3f F@10mm %.3f "
                "cd_sq_cm2 %.4f cd_l1_cm %.4f\n",
                AlignModeName(mode).c_str(), r.f_5mm, r.f_10mm, r.cd_sq_cm2, r.cd_l1_cm);
  }
  benchmark::Shutdown();
  return 0;
}
