// The LeRobot v3.0 export of a hand-made version (three episodes with
// distinct values, two tasks, two splits, spans of a test-pattern video made
// by ffmpeg), read back by independent readers: every Parquet file by
// hyparquet (npm, through node), the MP4 by ffprobe.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include <gtest/gtest.h>

#include "dataset/lerobot_export.h"
#include "dataset/resample.h"
#include "dataset/version.h"
#include "robot/trajectory/format.h"
#include "tests/parquet_read.h"
#include "tests/test_util.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;
using doasido::testing::ReadParquet;
using doasido::testing::ShellOk;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

float F(double v) { return static_cast<float>(v); }

struct Made {
  Manifest manifest;
  std::vector<retarget::HandTrajectory> trajectories;  // by manifest index
};

Made MakeVersion(const fs::path& dir) {
  ShellOk("ffmpeg -v error -f lavfi -i testsrc=size=96x64:rate=30 -frames:v 90 -pix_fmt yuv420p " +
      (dir / "src.mp4").string());
  Made made;
  Manifest& m = made.manifest;
  m.name = "t";
  m.version = "v1";
  m.selection = Selection::kAll;
  m.split_fractions = {{"train", 0.5}, {"test", 0.5}};
  m.trajectory_stage = "retarget_kinematic";
  const char* tasks[] = {"pour water", "stir", "pour water"};
  const char* splits[] = {"train", "test", "train"};
  for (int k = 0; k < 3; ++k) {
    retarget::HandTrajectory t;
    t.embodiment = "test_hand";
    t.fps = 30;
    for (int j = 0; j < 5; ++j) t.qpos_names.push_back("q" + std::to_string(j));
    const int frames = 10 + 5 * k;
    for (int f = 0; f < frames; ++f) {
      Eigen::VectorXd q(5);
      for (int j = 0; j < 5; ++j) q[j] = 100.0 * k + f + 0.001 * j + 1.0 / 3.0;
      t.qpos.push_back(q);
      t.valid.push_back(true);
      t.fingertip_error.push_back(0.001);
      t.object_poses.push_back({Quat(1, 0, 0, 0), Vec3(0.01 * f, -0.5 * k, 0.25 + 0.001 * f)});
    }
    Episode e;
    e.id = "clip-00000" + std::to_string(k + 1);
    e.index = k;
    e.clip_id = k + 1;
    e.external_id = "c" + std::to_string(k);
    e.video = e.video_key = (dir / "src.mp4").string();
    e.start_frame = 20 * k;
    e.end_frame = 20 * k + frames - 1;
    e.task = tasks[k];
    e.split = splits[k];
    e.trajectory_stage = m.trajectory_stage;
    e.frames = frames;
    e.fps = 30;
    m.episodes.push_back(e);
    fs::create_directories(dir / "v1/episodes" / e.id);
    retarget::WriteTrajectoryJson(t, dir / "v1/episodes" / e.id / "trajectory.json");
    made.trajectories.push_back(t);
  }
  WriteFile(dir / "v1/manifest.json", ToJson(m).dump());
  return made;
}

TEST(LeRobotExport, ParquetAndVideoReadBackByIndependentReaders) {
  TempDir dir;
  const Made made = MakeVersion(dir.path());
  const ExportSummary s = ExportLeRobot(dir / "v1", dir / "out", {});
  EXPECT_EQ(s.episodes, 3);
  EXPECT_EQ(s.frames, 10 + 15 + 20);

  // Export order: train (manifest episodes 0, 2), then test (1).
  const std::vector<int> order = {0, 2, 1};
  const std::map<std::string, int> task_index = {{"pour water", 0}, {"stir", 1}};

  const Json data = ReadParquet(dir.path(), dir / "out/data/chunk-000/file-000.parquet");
  EXPECT_EQ(data["groups"], (Json{10, 20, 15}));  // one row group per episode
  size_t row = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    const auto& t = made.trajectories[order[i]];
    const size_t n = t.qpos.size();
    for (size_t f = 0; f < n; ++f, ++row) {
      const Json& r = data["rows"][row];
      ASSERT_EQ(r["timestamp"].get<double>(), F(f / 30.0)) << row;
      ASSERT_EQ(r["frame_index"], f);
      ASSERT_EQ(r["episode_index"], i);
      ASSERT_EQ(r["index"], row);
      ASSERT_EQ(r["task_index"], task_index.at(made.manifest.episodes[order[i]].task));
      for (int j = 0; j < 5; ++j) {
        ASSERT_EQ(r["observation.state"][j].get<double>(), F(t.qpos[f][j]));
        ASSERT_EQ(r["action"][j].get<double>(), F(t.qpos[std::min(f + 1, n - 1)][j]));
      }
      ASSERT_EQ(r["observation.object_pose"][0].get<double>(), F(t.object_poses[f].t.x()));
      ASSERT_EQ(r["observation.object_pose"][1].get<double>(), F(t.object_poses[f].t.y()));
      ASSERT_EQ(r["observation.object_pose"][3].get<double>(), 1.0f);
    }
  }
  EXPECT_EQ(data["rows"].size(), row);

  std::ifstream info_file(dir / "out/meta/info.json");
  const Json info = Json::parse(info_file);
  EXPECT_EQ(info["codebase_version"], "v3.0");
  EXPECT_EQ(info["robot_type"], "test_hand");
  EXPECT_EQ(info["total_frames"], data["rows"].size());
  EXPECT_EQ(info["splits"], (Json{{"train", "0:2"}, {"test", "2:3"}}));
  EXPECT_EQ(info["features"]["observation.state"]["shape"], Json{5});
  EXPECT_EQ(info["features"]["observation.state"]["names"][4], "q4");

  const Json episodes = ReadParquet(dir.path(), dir / "out/meta/episodes/chunk-000/file-000.parquet");
  ASSERT_EQ(episodes["rows"].size(), 3u);
  EXPECT_EQ(info["total_episodes"], episodes["rows"].size());
  std::int64_t from = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    const Json& e = episodes["rows"][i];
    const auto& t = made.trajectories[order[i]];
    const auto n = static_cast<std::int64_t>(t.qpos.size());
    EXPECT_EQ(e["episode_index"], i);
    EXPECT_EQ(e["tasks"], Json{made.manifest.episodes[order[i]].task});
    EXPECT_EQ(e["length"], n);
    EXPECT_EQ(e["dataset_from_index"], from);
    EXPECT_EQ(e["dataset_to_index"], from + n);
    EXPECT_DOUBLE_EQ(e["videos/observation.images.source/from_timestamp"].get<double>(), from / 30.0);
    EXPECT_DOUBLE_EQ(e["videos/observation.images.source/to_timestamp"].get<double>(), (from + n) / 30.0);
    EXPECT_EQ(e["doasido/episode_id"], made.manifest.episodes[order[i]].id);
    // Per-episode stats against the stored (float32) values.
    double sum = 0, lo = 1e300, hi = -1e300;
    for (const auto& q : t.qpos) sum += F(q[2]), lo = std::min<double>(lo, F(q[2])), hi = std::max<double>(hi, F(q[2]));
    EXPECT_NEAR(e["stats/observation.state/mean"][2].get<double>(), sum / n, 1e-9);
    EXPECT_EQ(e["stats/observation.state/min"][2].get<double>(), lo);
    EXPECT_EQ(e["stats/observation.state/max"][2].get<double>(), hi);
    EXPECT_EQ(e["stats/observation.state/count"], Json{n});
    from += n;
  }

  const Json tasks = ReadParquet(dir.path(), dir / "out/meta/tasks.parquet");
  EXPECT_EQ(tasks["rows"], (Json{{{"task", "pour water"}, {"task_index", 0}},
                                 {{"task", "stir"}, {"task_index", 1}}}));
  // pandas (LeRobot's reader) makes the task string the index.
  EXPECT_EQ(Json::parse(tasks["kv"]["pandas"].get<std::string>())["index_columns"], Json{"task"});
  EXPECT_EQ(info["total_tasks"], tasks["rows"].size());

  std::ifstream stats_file(dir / "out/meta/stats.json");
  const Json stats = Json::parse(stats_file);
  EXPECT_EQ(stats["observation.state"]["min"][0].get<double>(), F(1.0 / 3.0));
  EXPECT_EQ(stats["observation.state"]["max"][0].get<double>(), F(200 + 19 + 1.0 / 3.0));
  EXPECT_EQ(stats["index"]["count"], Json{45});
  EXPECT_EQ(stats["index"]["q50"][0].get<double>(), 22.0);

  const Json probe = Json::parse(ShellOk(
      "ffprobe -v error -count_frames -show_entries stream=nb_read_frames,width,height,codec_name "
      "-of json " + (dir / "out/videos/observation.images.source/chunk-000/file-000.mp4").string()));
  EXPECT_EQ(probe["streams"][0]["nb_read_frames"], std::to_string(45));
  EXPECT_EQ(probe["streams"][0]["width"], 96);
  EXPECT_EQ(info["features"]["observation.images.source"]["shape"], (Json{64, 96, 3}));
}

TEST(LeRobotExport, RefusesNonEmptyOutputAndMixedRates) {
  TempDir dir;
  MakeVersion(dir.path());
  WriteFile(dir / "out/x", "x");
  try {
    ExportLeRobot(dir / "v1", dir / "out", {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "output_exists");
  }
  retarget::HandTrajectory t = retarget::ReadTrajectoryJson(dir / "v1/episodes/clip-000002/trajectory.json");
  t.fps = 25;
  retarget::WriteTrajectoryJson(t, dir / "v1/episodes/clip-000002/trajectory.json");
  try {
    ExportLeRobot(dir / "v1", dir / "out2", {.videos = false});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "mixed_trajectories");
    EXPECT_EQ(e.site().field, "fps");
    EXPECT_EQ(e.site().clip, "c1");
  }
}

// A version mixing a hand-only episode (no object poses) with hand-object
// ones, as the demo's: the whole export drops observation.object_pose; with
// hand_object_only the hand-only episode is left out and the object poses
// are exported, row for row; a version of hand-only episodes alone then has
// nothing to export.
TEST(LeRobotExport, HandObjectOnlyLeavesOutTheHandOnlyEpisodesAndKeepsTheObjectPoses) {
  TempDir dir;
  Made made = MakeVersion(dir.path());
  const fs::path traj = dir / "v1/episodes/clip-000002/trajectory.json";
  retarget::HandTrajectory t = retarget::ReadTrajectoryJson(traj);
  t.object_poses.clear();
  fs::remove(traj);
  retarget::WriteTrajectoryJson(t, traj);
  made.manifest.episodes[1].hand_only = true;
  WriteFile(dir / "v1/manifest.json", ToJson(made.manifest).dump());
  auto info = [&](const fs::path& out) { return Json::parse(testing::ReadFile(out / "meta/info.json")); };
  ExportLeRobot(dir / "v1", dir / "all", {.videos = false});
  EXPECT_FALSE(info(dir / "all")["features"].contains("observation.object_pose"));
  EXPECT_EQ(info(dir / "all")["total_episodes"], 3);
  ExportLeRobot(dir / "v1", dir / "held", {.videos = false, .hand_object_only = true});
  const Json held = info(dir / "held");
  EXPECT_TRUE(held["features"].contains("observation.object_pose"));
  EXPECT_EQ(held["total_episodes"], 2);
  EXPECT_EQ(held["total_frames"], made.trajectories[0].qpos.size() + made.trajectories[2].qpos.size());

  for (Episode& e : made.manifest.episodes) e.hand_only = true;
  WriteFile(dir / "v1/manifest.json", ToJson(made.manifest).dump());
  try {
    ExportLeRobot(dir / "v1", dir / "none", {.videos = false, .hand_object_only = true});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "empty_version");
  }
}

// Actuator targets for the given episodes' trajectories (3 actuators,
// values distinct from every joint position).
void AddControls(const fs::path& dir, const std::vector<std::string>& episodes) {
  for (const std::string& id : episodes) {
    const fs::path path = dir / "v1/episodes" / id / "trajectory.json";
    retarget::HandTrajectory t = retarget::ReadTrajectoryJson(path);
    t.ctrl_names = {"a0", "a1", "a2"};
    for (size_t f = 0; f < t.qpos.size(); ++f) t.ctrl.push_back(Eigen::Vector3d(-1.0 - f, -2.0, -3.0));
    fs::remove(path);
    retarget::WriteTrajectoryJson(t, path);
  }
}

// A version mixing a simulated episode (actuator targets) with kinematic
// ones (none), as the demo's hand-object and hand-only episodes: one
// meaning of `action` for the dataset, the next frame's joints, for all.
// With targets in every episode the action is the targets.
TEST(LeRobotExport, ActionsAreTheNextJointsUnlessEveryEpisodeHasActuatorTargets) {
  TempDir dir;
  const Made made = MakeVersion(dir.path());
  AddControls(dir.path(), {"clip-000002"});
  ExportLeRobot(dir / "v1", dir / "mixed", {.videos = false});
  const Json mixed = ReadParquet(dir.path(), dir / "mixed/data/chunk-000/file-000.parquet");
  const auto& first = made.trajectories[0];  // export order: train first
  ASSERT_EQ(mixed["rows"][0]["action"].size(), 5u);
  EXPECT_EQ(mixed["rows"][0]["action"][0].get<double>(), F(first.qpos[1][0]));
  std::ifstream mixed_info(dir / "mixed/meta/info.json");
  EXPECT_EQ(Json::parse(mixed_info)["features"]["action"]["names"][0], "q0");

  AddControls(dir.path(), {"clip-000001", "clip-000003"});
  ExportLeRobot(dir / "v1", dir / "all", {.videos = false});
  const Json all = ReadParquet(dir.path(), dir / "all/data/chunk-000/file-000.parquet");
  ASSERT_EQ(all["rows"][1]["action"].size(), 3u);
  EXPECT_EQ(all["rows"][1]["action"][0].get<double>(), -2.0f);
  std::ifstream all_info(dir / "all/meta/info.json");
  EXPECT_EQ(Json::parse(all_info)["features"]["action"]["names"][0], "a0");
}

// A joint moving at a constant rate lands exactly on the line at the new
// rate's times; a frame is valid when both neighbours are.
TEST(LeRobotExport, ResamplingKeepsALinearMotionOnItsLine) {
  retarget::HandTrajectory t;
  t.fps = 25;
  for (int f = 0; f < 11; ++f) {
    t.qpos.push_back(Eigen::VectorXd::Constant(2, 0.1 * f));
    t.valid.push_back(f != 4);
    t.fingertip_error.push_back(f);
  }
  const retarget::HandTrajectory r = ResampleTrajectory(t, 30);
  EXPECT_EQ(r.fps, 30);
  ASSERT_EQ(r.qpos.size(), 13u);  // 0 .. 12 / 30 s within the 10 / 25 s of the source
  for (size_t k = 0; k < r.qpos.size(); ++k) {
    const double source = k * 25.0 / 30.0;
    EXPECT_NEAR(r.qpos[k][1], 0.1 * source, 1e-12) << k;
    EXPECT_EQ(r.valid[k], std::floor(source) != 4 && std::floor(source) + 1 != 4) << k;
  }
}

TEST(LeRobotExport, EpisodesOfDifferentRatesExportAtOneRate) {
  TempDir dir;
  MakeVersion(dir.path());
  retarget::HandTrajectory t = retarget::ReadTrajectoryJson(dir / "v1/episodes/clip-000002/trajectory.json");
  t.fps = 25;
  retarget::WriteTrajectoryJson(t, dir / "v1/episodes/clip-000002/trajectory.json");
  const ExportSummary s = ExportLeRobot(dir / "v1", dir / "out", {.videos = true, .fps = 30});
  std::ifstream info_file(dir / "out/meta/info.json");
  const Json info = Json::parse(info_file);
  EXPECT_EQ(info["fps"], 30.0);
  const int resampled = static_cast<int>(std::floor((t.qpos.size() - 1) * 30.0 / 25.0 + 1e-9)) + 1;
  EXPECT_EQ(s.frames, 45 - static_cast<int>(t.qpos.size()) + resampled);
  const Json probe = Json::parse(ShellOk(
      "ffprobe -v error -count_frames -show_entries stream=nb_read_frames -of json " +
      (dir / "out/videos/observation.images.source/chunk-000/file-000.mp4").string()));
  EXPECT_EQ(probe["streams"][0]["nb_read_frames"], std::to_string(s.frames));
}

}  // namespace
}  // namespace doasido::dataset
