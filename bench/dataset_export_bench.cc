// Dataset throughput: `dataset create` (copy every episode's artifacts,
// SHA-256 them, write the manifest and playbook, rename into place) and the
// robomimic and LeRobot exports (LeRobot without the video feature: the
// bench has no source videos), each beside a plain recursive copy of the same bytes
// (the peer) in the same run.
// Usage: dataset_export_bench [episodes] [frames]
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <unistd.h>

#include "core/log.h"
#include "dataset/lerobot_export.h"
#include "dataset/robomimic_export.h"
#include "dataset/version_store.h"
#include "db/database.h"
#include "stages/kinematic_stage.h"
#include "robot/trajectory/format.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace doasido;

namespace {

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::int64_t Bytes(const fs::path& dir) {
  std::int64_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) n += static_cast<std::int64_t>(e.file_size());
  }
  return n;
}

double PlainCopy(const fs::path& from, const fs::path& to) {
  fs::remove_all(to);
  const auto t = Clock::now();
  fs::copy(from, to, fs::copy_options::recursive);
  return Since(t);
}

retarget::HandTrajectory Trajectory(int frames, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 0.3);
  retarget::HandTrajectory t;
  t.embodiment = "sharpa_right";
  for (int j = 0; j < 28; ++j) t.qpos_names.push_back("q" + std::to_string(j));
  for (int f = 0; f < frames; ++f) {
    Eigen::VectorXd q(28);
    for (int j = 0; j < 28; ++j) q[j] = n(rng);
    t.qpos.push_back(q);
    t.valid.push_back(true);
    t.fingertip_error.push_back(0.002);
    t.object_poses.push_back({Quat::Identity(), Vec3(n(rng), n(rng), n(rng))});
    retarget::Keypoints21 k;
    for (int i = 0; i < 21; ++i) k.row(i) = Vec3(n(rng), n(rng), n(rng)).transpose();
    t.reference_keypoints.push_back(k);
  }
  return t;
}

// A database whose `episodes` clips all passed retarget_kinematic, with a
// trajectory and a reconstruction-sized file in their artifact folders.
void MakeDatabase(const fs::path& dir, int episodes, int frames) {
  Database db(dir / "d.db");
  db.SetPipeline({retarget::kKinematicStageName});
  std::mt19937 rng(5);
  std::string recon_bytes(400000, '\0');
  for (char& c : recon_bytes) c = static_cast<char>(rng());
  for (int i = 0; i < episodes; ++i) {
    ClipRecord c;
    c.video_id = db.UpsertVideo((dir / ("v" + std::to_string(i / 2) + ".mp4")).string());
    c.external_id = "c" + std::to_string(i);
    c.start_frame = 100 * (i % 2);
    c.end_frame = c.start_frame.value() + frames - 1;
    const ClipId id = db.InsertClip(c).id;
    const auto claim = db.ClaimNext("bench", {}, 60, 3);
    const fs::path art = db.ArtifactDir(id, retarget::kKinematicStageName);
    fs::create_directories(art);
    const retarget::HandTrajectory t = Trajectory(frames, rng);
    retarget::WriteTrajectoryJson(t, art / "trajectory.json");
    retarget::WriteTrajectoryCsv(t, art / "trajectory.csv");
    fs::create_directories(db.ArtifactDir(id, "recon"));
    std::ofstream(db.ArtifactDir(id, "recon") / "reconstruction.npz", std::ios::binary) << recon_bytes;
    StageResult r;
    db.Complete(*claim, "bench", "h", r, 0.1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  InitLogging("warn");
  const int episodes = argc > 1 ? std::atoi(argv[1]) : 200;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 300;
  const fs::path dir = fs::temp_directory_path() / ("doasido_dataset_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  MakeDatabase(dir, episodes, frames);
  Database db(dir / "d.db");
  const std::int64_t artifact_bytes = Bytes(dir / "artifacts");

  const double copy_s = PlainCopy(dir / "artifacts", dir / "copy");
  dataset::CreateOptions options;
  options.selection = dataset::Selection::kAll;
  options.thumbnails = false;
  auto t = Clock::now();
  dataset::CreateVersion(db, dir / "datasets", options);
  const double create_s = Since(t);
  const fs::path version = dir / "datasets/default/v1";
  const std::int64_t version_bytes = Bytes(version);

  const double copy_again_s = PlainCopy(version / "episodes", dir / "copy2");
  t = Clock::now();
  const dataset::ExportSummary s = dataset::ExportRobomimic(version, dir / "out.hdf5");
  const double export_s = Since(t);

  t = Clock::now();
  const dataset::ExportSummary lr = dataset::ExportLeRobot(version, dir / "lerobot", {.videos = false});
  const double lerobot_s = Since(t);

  std::printf("dataset_export_bench: %d episodes x %d frames, artifacts %.1f MB, version %.1f MB\n",
              episodes, frames, artifact_bytes / 1e6, version_bytes / 1e6);
  std::printf("%-22s %9s %11s %9s %14s\n", "", "seconds", "episodes/s", "MB/s", "vs plain copy");
  std::printf("%-22s %9.3f %11s %9.1f %14s\n", "plain copy (artifacts)", copy_s, "-",
              artifact_bytes / 1e6 / copy_s, "1.00");
  std::printf("%-22s %9.3f %11.1f %9.1f %14.2f\n", "dataset create", create_s, episodes / create_s,
              artifact_bytes / 1e6 / create_s, copy_s / create_s);
  std::printf("%-22s %9.3f %11s %9.1f %14s\n", "plain copy (episodes)", copy_again_s, "-",
              version_bytes / 1e6 / copy_again_s, "1.00");
  std::printf("%-22s %9.3f %11.1f %9.1f %14.2f   (%.1f MB of HDF5)\n", "export robomimic",
              export_s, episodes / export_s, version_bytes / 1e6 / export_s,
              copy_again_s / export_s, s.bytes / 1e6);
  std::printf("%-22s %9.3f %11.1f %9.1f %14.2f   (%.1f MB of Parquet and JSON; no video)\n",
              "export lerobot", lerobot_s, episodes / lerobot_s, version_bytes / 1e6 / lerobot_s,
              copy_again_s / lerobot_s, lr.bytes / 1e6);
  fs::remove_all(dir);
  return 0;
}
