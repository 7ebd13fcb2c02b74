// Clip-bundle I/O cost for a 90-frame 640x480 clip with depth, three masks,
// per-frame K, poses and 64 tracks: WriteBundle and ReadBundle (with full
// validation) against the peer of dumping the same pixel bytes as raw files,
// the floor any container format pays. Prints the ratios.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "recon/bundle/bundle.h"

namespace doasido::recon {
namespace {

constexpr int kW = 640, kH = 480, kT = 90;

const ClipBundle& Clip() {
  static const ClipBundle clip = [] {
    ClipBundle b;
    b.width = kW;
    b.height = kH;
    b.frames = kT;
    b.fps = 30;
    cv::RNG rng(1);
    for (int t = 0; t < kT; ++t) {
      Mat3 k;
      k << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
      b.K.push_back(k);
      // A smooth depth ramp with a background of +inf, as a renderer makes.
      cv::Mat z(kH, kW, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
      z(cv::Rect(100, 80, 400, 300)).forEach<float>([t](float& v, const int* p) {
        v = 0.5f + 0.001f * static_cast<float>(p[0] + p[1] + t);
      });
      b.depth.push_back(z);
      for (auto* masks : {&b.mask_object, &b.mask_hand_left, &b.mask_hand_right}) {
        cv::Mat m = cv::Mat::zeros(kH, kW, CV_8U);
        cv::circle(m, {rng.uniform(100, 540), rng.uniform(100, 380)}, 60, 255, -1);
        masks->push_back(m);
      }
      b.object_poses.push_back({Quat::Identity(), Vec3(0, 0, 0.6)});
      b.gravity_up.push_back(Vec3(0, -1, 0));
    }
    PointTracks tr;
    tr.x = Eigen::MatrixXf::Random(64, kT) * 300 + Eigen::MatrixXf::Constant(64, kT, 320);
    tr.y = Eigen::MatrixXf::Random(64, kT) * 200 + Eigen::MatrixXf::Constant(64, kT, 240);
    tr.visible = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic>::Ones(64, kT);
    tr.query = Eigen::MatrixX3f::Zero(64, 3);
    b.tracks = tr;
    return b;
  }();
  return clip;
}

std::filesystem::path Dir(const char* name) {
  return std::filesystem::temp_directory_path() / (std::string("doasido_bench_") + name);
}

void RawDump(const ClipBundle& b, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  for (int t = 0; t < b.frames; ++t) {
    for (const cv::Mat* m : {&b.depth[t], &b.mask_object[t], &b.mask_hand_left[t],
                             &b.mask_hand_right[t]}) {
      std::ofstream out(dir / (std::to_string(t) + "_" + std::to_string(m->type())),
                        std::ios::binary);
      out.write(reinterpret_cast<const char*>(m->data),
                static_cast<std::streamsize>(m->total() * m->elemSize()));
    }
  }
}

void RawLoad(const ClipBundle& b, const std::filesystem::path& dir) {
  for (int t = 0; t < b.frames; ++t) {
    for (const cv::Mat* m : {&b.depth[t], &b.mask_object[t], &b.mask_hand_left[t],
                             &b.mask_hand_right[t]}) {
      cv::Mat copy(m->size(), m->type());
      std::ifstream in(dir / (std::to_string(t) + "_" + std::to_string(m->type())),
                       std::ios::binary);
      in.read(reinterpret_cast<char*>(copy.data),
              static_cast<std::streamsize>(copy.total() * copy.elemSize()));
      benchmark::DoNotOptimize(copy.data);
    }
  }
}

void BM_WriteBundle(benchmark::State& state) {
  for (auto _ : state) WriteBundle(Clip(), Dir("bundle"));
}
BENCHMARK(BM_WriteBundle)->Unit(benchmark::kMillisecond);

void BM_ReadBundle(benchmark::State& state) {
  WriteBundle(Clip(), Dir("bundle"));
  for (auto _ : state) benchmark::DoNotOptimize(ReadBundle(Dir("bundle")));
}
BENCHMARK(BM_ReadBundle)->Unit(benchmark::kMillisecond);

void BM_RawDump(benchmark::State& state) {
  for (auto _ : state) RawDump(Clip(), Dir("raw"));
}
BENCHMARK(BM_RawDump)->Unit(benchmark::kMillisecond);

template <typename F>
double Seconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::uintmax_t FolderBytes(const std::filesystem::path& dir) {
  std::uintmax_t n = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) n += e.file_size();
  }
  return n;
}

}  // namespace
}  // namespace doasido::recon

int main(int argc, char** argv) {
  using namespace doasido::recon;
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  const ClipBundle& b = Clip();
  const double w = Seconds([&] { WriteBundle(b, Dir("bundle")); });
  const double r = Seconds([&] { benchmark::DoNotOptimize(ReadBundle(Dir("bundle"))); });
  const double rw = Seconds([&] { RawDump(b, Dir("raw")); });
  const double rr = Seconds([&] { RawLoad(b, Dir("raw")); });
  std::printf("90 frames 640x480: write %.0f ms (x%.1f raw dump), read+validate %.0f ms "
              "(x%.1f raw load), %.1f MB on disk vs %.1f MB raw\n",
              1e3 * w, w / rw, 1e3 * r, r / rr, FolderBytes(Dir("bundle")) / 1e6,
              FolderBytes(Dir("raw")) / 1e6);
  std::filesystem::remove_all(Dir("bundle"));
  std::filesystem::remove_all(Dir("raw"));
  benchmark::Shutdown();
  return 0;
}
