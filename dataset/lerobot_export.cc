#include "dataset/lerobot_export.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>

#include "core/error.h"
#include "core/tool_version.h"
#include "dataset/feature_stats.h"
#include "dataset/parquet_writer.h"
#include "dataset/resample.h"
#include "dataset/trajectory_uniformity.h"
#include "dataset/version.h"
#include "robot/trajectory/format.h"
#include "video/frame_count.h"
#include "video/mp4_writer.h"
#include "video/video_decoder.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;
using Rows = std::vector<std::vector<double>>;

constexpr const char* kChunk = "chunk-000";
constexpr const char* kFile = "file-000";

struct LoadedEpisode {
  const Episode* episode = nullptr;
  retarget::HandTrajectory trajectory;
  std::int64_t task_index = 0;
  std::int64_t from = 0;  // global index of its first frame
  Rows state, action, object_pose;
  // Per exported frame, the source frame (offset in the span) it shows:
  // 0, 1, 2, ... unless the trajectory was resampled to the export's fps.
  std::vector<std::int64_t> source_frames;
};

Json Feature(const char* dtype, std::vector<int> shape, const Json& names) {
  return {{"dtype", dtype}, {"shape", shape}, {"names", names}};
}

// Episodes in split order (the manifest's split list), then manifest order.
std::vector<const Episode*> ExportOrder(const Manifest& m) {
  std::vector<const Episode*> out;
  for (const auto& [split, fraction] : m.split_fractions) {
    for (const Episode& e : m.episodes) {
      if (e.split == split) out.push_back(&e);
    }
  }
  for (const Episode& e : m.episodes) {  // splits the list does not name
    if (std::find(out.begin(), out.end(), &e) == out.end()) out.push_back(&e);
  }
  return out;
}

void Load(LoadedEpisode& l, const fs::path& version_dir, const LoadedEpisode* first, double fps) {
  const Episode& e = *l.episode;
  const fs::path path = version_dir / kEpisodesFolder / e.id / kTrajectoryFile;
  l.trajectory = retarget::ReadTrajectoryJson(path);
  auto mixed = [&](const std::string& field, const std::string& why) {
    throw Error(kMixedTrajectories, why + " (LeRobot wants one robot and rate per dataset)",
                {.clip = e.external_id, .file = path.string(), .field = field});
  };
  if (l.trajectory.qpos.empty()) mixed("qpos", "the trajectory has no frames");
  const std::vector<double> positions =
      ResamplePositions(l.trajectory.qpos.size(), l.trajectory.fps, fps > 0 ? fps : l.trajectory.fps);
  for (double p : positions) l.source_frames.push_back(std::lround(p));
  if (fps > 0) l.trajectory = ResampleTrajectory(l.trajectory, fps);
  const retarget::HandTrajectory& t = l.trajectory;
  if (first) {
    const Mismatch m = TrajectoryMismatch(t, first->trajectory, first->episode->external_id,
                                          {.object_poses = true, .controls = true});
    if (m.field == "fps") mixed(m.field, m.why + "; --fps resamples every episode to one rate");
    if (!m.field.empty()) mixed(m.field, m.why);
  }
  for (const auto& q : t.qpos) l.state.emplace_back(q.data(), q.data() + q.size());
  for (const auto& p : t.object_poses) {
    l.object_pose.push_back({p.t.x(), p.t.y(), p.t.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()});
  }
}

void WriteJson(const fs::path& path, const Json& j) {
  fs::create_directories(path.parent_path());
  std::ofstream f(path, std::ios::binary);
  f << j.dump(2) << "\n";
  f.close();
  if (!f) throw Error("io", "cannot write", {.file = path.string()});
}

// Decodes each episode's span at full size and appends it to one MP4;
// returns the video feature's info.
Json WriteVideo(const std::vector<LoadedEpisode>& episodes, double fps, const fs::path& path) {
  std::unique_ptr<Mp4Writer> writer;
  fs::create_directories(path.parent_path());
  for (const LoadedEpisode& l : episodes) {
    const Episode& e = *l.episode;
    DecoderOptions options;
    options.analysis_size = 0;
    options.skip_loop_filter = false;
    options.first_frame = e.start_frame.value_or(0);
    options.last_frame = options.first_frame + l.source_frames.back();
    options.clip = e.external_id;
    VideoDecoder decoder(e.video, options);
    AnalysisFrame frame;
    cv::Mat last;
    std::int64_t decoded = -1;  // offset in the span of `last`
    for (const std::int64_t wanted : l.source_frames) {
      while (decoded < wanted && decoder.Next(&frame)) {
        last = frame.bgr;
        ++decoded;
      }
      if (last.empty()) {
        throw Error(kVideoTruncated, "no frame in the episode's span",
                    {.clip = e.external_id, .file = e.video});
      }
      if (!writer) writer = std::make_unique<Mp4Writer>(path, last.cols, last.rows, fps);
      writer->Write(last);  // a span shorter than the trajectory repeats its last frame
    }
  }
  writer->Finish();
  const Mp4Info& v = writer->info();
  return {{"dtype", "video"},
          {"shape", {v.height, v.width, 3}},
          {"names", {"height", "width", "channels"}},
          {"info",
           {{"video.height", v.height},
            {"video.width", v.width},
            {"video.codec", v.codec},
            {"video.pix_fmt", v.pix_fmt},
            {"video.is_depth_map", false},
            {"video.fps", fps},
            {"video.channels", 3},
            {"has_audio", false}}}};
}

// LeRobot reads tasks.parquet with pandas, which makes `task` the index
// (what LeRobot's own writer stores): pandas' schema metadata says so.
Json PandasTaskIndex() {
  auto column = [](const char* name, const char* pandas_type, const char* numpy_type) {
    return Json{{"name", name}, {"field_name", name}, {"pandas_type", pandas_type},
                {"numpy_type", numpy_type}, {"metadata", nullptr}};
  };
  return {{"index_columns", {"task"}},
          {"column_indexes",
           {{{"name", nullptr}, {"field_name", nullptr}, {"pandas_type", "unicode"},
             {"numpy_type", "object"}, {"metadata", {{"encoding", "UTF-8"}}}}}},
          {"columns", {column("task_index", "int64", "int64"), column("task", "unicode", "object")}},
          {"creator", {{"library", "doasido"}, {"version", ToolVersion()}}},
          {"pandas_version", "2.1.4"}};
}

std::string ListType(const char* element, size_t n) {
  return std::string(element) + "[" + std::to_string(n) + "]";
}


// What every step of the export shares: the episodes loaded in export
// order with their actions, the tasks, and what the features hold.
struct ExportPlan {
  std::vector<LoadedEpisode> episodes;
  std::vector<std::string> tasks;
  double fps = 0;
  bool use_ctrl = false;     // actions are the controls (all episodes have the same), else next qpos
  bool with_object = false;  // every episode has object poses
  std::int64_t total = 0;    // frames over all episodes
  size_t nq = 0, na = 0;     // state and action sizes
  const retarget::HandTrajectory& first() const { return episodes.front().trajectory; }
  const std::vector<std::string>& action_names() const {
    return use_ctrl ? first().ctrl_names : first().qpos_names;
  }
};

// Loads the version's episodes in export order, numbers their tasks and
// derives each frame's action and global index.
ExportPlan LoadPlan(const Manifest& m, const fs::path& version_dir, const LeRobotOptions& options) {
  ExportPlan plan;
  std::vector<LoadedEpisode>& episodes = plan.episodes;
  std::map<std::string, std::int64_t> task_index;
  for (const Episode* e : ExportOrder(m)) {
    if (options.hand_object_only && e->hand_only) continue;
    LoadedEpisode l;
    l.episode = e;
    Load(l, version_dir, episodes.empty() ? nullptr : &episodes.front(), options.fps);
    if (!task_index.count(e->task)) {
      task_index[e->task] = static_cast<std::int64_t>(plan.tasks.size());
      plan.tasks.push_back(e->task);
    }
    l.task_index = task_index[e->task];
    episodes.push_back(std::move(l));
  }
  if (episodes.empty()) {  // every episode hand-only, and those left out
    throw Error("empty_version", "the version has no hand-object episode", {.file = version_dir.string()});
  }
  const retarget::HandTrajectory& first = plan.first();
  plan.fps = first.fps;
  plan.use_ctrl = std::all_of(episodes.begin(), episodes.end(), [&](const LoadedEpisode& l) {
    return !l.trajectory.ctrl.empty() && l.trajectory.ctrl_names == first.ctrl_names;
  });
  plan.with_object = std::all_of(episodes.begin(), episodes.end(),
                                 [](const LoadedEpisode& l) { return !l.object_pose.empty(); });
  for (LoadedEpisode& l : episodes) {
    const auto& t = l.trajectory;
    const size_t n = t.qpos.size();
    for (size_t f = 0; f < n; ++f) {
      const Eigen::VectorXd& a = plan.use_ctrl ? t.ctrl[f] : t.qpos[std::min(f + 1, n - 1)];
      l.action.emplace_back(a.data(), a.data() + a.size());
    }
    l.from = plan.total;
    plan.total += static_cast<std::int64_t>(n);
  }
  plan.nq = first.qpos_names.size();
  plan.na = episodes.front().action[0].size();
  return plan;
}

// data/chunk-000/file-000.parquet: one row a frame, one row group an episode.
void WriteFrames(const ExportPlan& plan, const fs::path& out_dir, const fs::path& scratch) {
  std::vector<ParquetColumn> data_columns = {
      {"timestamp", "FLOAT"},          {"frame_index", "BIGINT"}, {"episode_index", "BIGINT"},
      {"index", "BIGINT"},             {"task_index", "BIGINT"},  {kStateFeature, ListType("FLOAT", plan.nq)},
      {kActionFeature, ListType("FLOAT", plan.na)}};
  if (plan.with_object) data_columns.push_back({kObjectPoseFeature, "FLOAT[7]"});
  ParquetWriter data(out_dir / "data" / kChunk / (std::string(kFile) + ".parquet"), data_columns, scratch);
  for (size_t i = 0; i < plan.episodes.size(); ++i) {
    const LoadedEpisode& l = plan.episodes[i];
    std::vector<Json> rows;
    for (size_t f = 0; f < l.state.size(); ++f) {
      Json row = {{"timestamp", static_cast<double>(f) / plan.fps},
                  {"frame_index", f},
                  {"episode_index", i},
                  {"index", l.from + static_cast<std::int64_t>(f)},
                  {"task_index", l.task_index},
                  {kStateFeature, l.state[f]},
                  {kActionFeature, l.action[f]}};
      if (plan.with_object) row[kObjectPoseFeature] = l.object_pose[f];
      rows.push_back(std::move(row));
    }
    data.AddRowGroup(rows);
  }
  data.Finish();
}

// The numeric features, each with the rows it holds for episode i.
using NumericFeatures = std::vector<std::pair<std::string, std::function<Rows(const LoadedEpisode&, size_t)>>>;
NumericFeatures NumericFeaturesOf(const ExportPlan& plan) {
  const double fps = plan.fps;
  NumericFeatures numeric = {
      {"timestamp", [fps](const LoadedEpisode& l, size_t) {
         Rows r;
         for (size_t f = 0; f < l.state.size(); ++f) r.push_back({static_cast<double>(static_cast<float>(f / fps))});
         return r;
       }},
      {"frame_index", [](const LoadedEpisode& l, size_t) {
         Rows r;
         for (size_t f = 0; f < l.state.size(); ++f) r.push_back({static_cast<double>(f)});
         return r;
       }},
      {"episode_index", [](const LoadedEpisode& l, size_t i) { return Rows(l.state.size(), {static_cast<double>(i)}); }},
      {"index", [](const LoadedEpisode& l, size_t) {
         Rows r;
         for (size_t f = 0; f < l.state.size(); ++f) r.push_back({static_cast<double>(l.from + static_cast<std::int64_t>(f))});
         return r;
       }},
      {"task_index", [](const LoadedEpisode& l, size_t) { return Rows(l.state.size(), {static_cast<double>(l.task_index)}); }},
      {kStateFeature, [](const LoadedEpisode& l, size_t) { return AsFloat32(l.state); }},
      {kActionFeature, [](const LoadedEpisode& l, size_t) { return AsFloat32(l.action); }},
  };
  if (plan.with_object) {
    numeric.push_back({kObjectPoseFeature, [](const LoadedEpisode& l, size_t) { return AsFloat32(l.object_pose); }});
  }
  return numeric;
}

// Statistics of every numeric feature over the dataset (returned) and per
// episode (*episode_stats).
Json ComputeStatistics(const ExportPlan& plan, const NumericFeatures& numeric, std::vector<Json>* episode_stats) {
  Json stats = Json::object();
  episode_stats->assign(plan.episodes.size(), Json::object());
  for (const auto& [feature, rows_of] : numeric) {
    Rows all;
    for (size_t i = 0; i < plan.episodes.size(); ++i) {
      Rows rows = rows_of(plan.episodes[i], i);
      (*episode_stats)[i][feature] = ToJson(ComputeStats(rows));
      all.insert(all.end(), rows.begin(), rows.end());
    }
    stats[feature] = ToJson(ComputeStats(all));
  }
  return stats;
}

// meta/episodes/chunk-000/file-000.parquet: one row an episode, with where
// its frames (and video span) are and its statistics.
void WriteEpisodeTable(const ExportPlan& plan, const NumericFeatures& numeric,
                       const std::vector<Json>& episode_stats, bool videos, const fs::path& out_dir,
                       const fs::path& scratch) {
  std::vector<ParquetColumn> episode_columns = {
      {"episode_index", "BIGINT"},          {"tasks", "VARCHAR[]"},
      {"length", "BIGINT"},                 {"data/chunk_index", "BIGINT"},
      {"data/file_index", "BIGINT"},        {"dataset_from_index", "BIGINT"},
      {"dataset_to_index", "BIGINT"},       {"meta/episodes/chunk_index", "BIGINT"},
      {"meta/episodes/file_index", "BIGINT"}, {"doasido/episode_id", "VARCHAR"},
      {"doasido/clip_id", "BIGINT"},        {"doasido/split", "VARCHAR"},
      {kHandOnlyColumn, "BOOLEAN"}};
  const std::string video_prefix = std::string("videos/") + kSourceVideoFeature + "/";
  if (videos) {
    for (const char* c : {"chunk_index", "file_index"}) episode_columns.push_back({video_prefix + c, "BIGINT"});
    for (const char* c : {"from_timestamp", "to_timestamp"}) episode_columns.push_back({video_prefix + c, "DOUBLE"});
  }
  for (const auto& [feature, rows_of] : numeric) {
    const size_t dims = episode_stats[0][feature]["min"].size();
    for (const char* stat : kStatNames) {
      episode_columns.push_back({"stats/" + feature + "/" + stat,
                                 std::string(stat) == "count" ? "BIGINT[1]" : ListType("DOUBLE", dims)});
    }
  }
  ParquetWriter writer(out_dir / "meta/episodes" / kChunk / (std::string(kFile) + ".parquet"),
                       episode_columns, scratch);
  std::vector<Json> rows;
  for (size_t i = 0; i < plan.episodes.size(); ++i) {
    const LoadedEpisode& l = plan.episodes[i];
    const auto length = static_cast<std::int64_t>(l.state.size());
    Json row = {{"episode_index", i},
                {"tasks", {l.episode->task}},
                {"length", length},
                {"data/chunk_index", 0},
                {"data/file_index", 0},
                {"dataset_from_index", l.from},
                {"dataset_to_index", l.from + length},
                {"meta/episodes/chunk_index", 0},
                {"meta/episodes/file_index", 0},
                {"doasido/episode_id", l.episode->id},
                {"doasido/clip_id", l.episode->clip_id},
                {"doasido/split", l.episode->split},
                {kHandOnlyColumn, l.episode->hand_only}};
    if (videos) {
      row[video_prefix + "chunk_index"] = 0;
      row[video_prefix + "file_index"] = 0;
      row[video_prefix + "from_timestamp"] = static_cast<double>(l.from) / plan.fps;
      row[video_prefix + "to_timestamp"] = static_cast<double>(l.from + length) / plan.fps;
    }
    for (const auto& [feature, s] : episode_stats[i].items()) {
      for (const auto& [stat, v] : s.items()) row["stats/" + feature + "/" + stat] = v;
    }
    rows.push_back(std::move(row));
  }
  writer.AddRowGroup(rows);
  writer.Finish();
}

// meta/tasks.parquet: the task texts by index.
void WriteTaskTable(const ExportPlan& plan, const fs::path& out_dir, const fs::path& scratch) {
  ParquetWriter writer(out_dir / "meta/tasks.parquet", {{"task_index", "BIGINT"}, {"task", "VARCHAR"}},
                       scratch);
  writer.SetMetadata("pandas", PandasTaskIndex().dump());
  std::vector<Json> rows;
  for (size_t i = 0; i < plan.tasks.size(); ++i) rows.push_back({{"task", plan.tasks[i]}, {"task_index", i}});
  writer.AddRowGroup(rows);
  writer.Finish();
}

// meta/info.json: the features, the splits as episode ranges, the paths.
Json InfoJson(const ExportPlan& plan, bool videos, const Json& video_feature) {
  const std::vector<LoadedEpisode>& episodes = plan.episodes;
  Json features = {{"timestamp", Feature("float32", {1}, nullptr)},
                   {"frame_index", Feature("int64", {1}, nullptr)},
                   {"episode_index", Feature("int64", {1}, nullptr)},
                   {"index", Feature("int64", {1}, nullptr)},
                   {"task_index", Feature("int64", {1}, nullptr)},
                   {kStateFeature, Feature("float32", {static_cast<int>(plan.nq)}, plan.first().qpos_names)},
                   {kActionFeature, Feature("float32", {static_cast<int>(plan.na)}, plan.action_names())}};
  if (plan.with_object) {
    features[kObjectPoseFeature] = Feature("float32", {7}, {"tx", "ty", "tz", "qw", "qx", "qy", "qz"});
  }
  if (videos) features[kSourceVideoFeature] = video_feature;
  Json splits = Json::object();
  for (size_t i = 0; i < episodes.size();) {
    size_t j = i;
    while (j < episodes.size() && episodes[j].episode->split == episodes[i].episode->split) ++j;
    splits[episodes[i].episode->split] = std::to_string(i) + ":" + std::to_string(j);
    i = j;
  }
  return {
      {"codebase_version", kLeRobotVersion},
      {"robot_type", plan.first().embodiment},
      {"total_episodes", episodes.size()},
      {"total_frames", plan.total},
      {"total_tasks", plan.tasks.size()},
      {"chunks_size", 1000},
      {"data_files_size_in_mb", 100},
      {"video_files_size_in_mb", 200},
      {"fps", plan.fps},
      {"splits", splits},
      {"data_path", "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"},
      {"video_path", videos ? Json("videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4")
                            : Json(nullptr)},
      {"features", features}};
}

std::int64_t FolderBytes(const fs::path& dir) {
  std::int64_t bytes = 0;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::end(it); ++it) {
    if (it->is_regular_file()) bytes += static_cast<std::int64_t>(it->file_size());
  }
  return bytes;
}

}  // namespace

ExportSummary ExportLeRobot(const fs::path& version_dir, const fs::path& out_dir,
                            const LeRobotOptions& options) {
  const Manifest m = ReadManifest(version_dir);
  std::error_code ec;
  if (fs::exists(out_dir, ec) && !fs::is_empty(out_dir, ec)) {
    throw Error("output_exists", "the export folder is not empty", {.file = out_dir.string()});
  }
  if (m.episodes.empty()) throw Error("empty_version", "the version has no episodes", {.file = version_dir.string()});

  const ExportPlan plan = LoadPlan(m, version_dir, options);
  const fs::path scratch = out_dir / ".staging";
  WriteFrames(plan, out_dir, scratch);
  const NumericFeatures numeric = NumericFeaturesOf(plan);
  std::vector<Json> episode_stats;
  const Json stats = ComputeStatistics(plan, numeric, &episode_stats);
  Json video_feature;
  if (options.videos) {
    video_feature = WriteVideo(plan.episodes, plan.fps,
                               out_dir / "videos" / kSourceVideoFeature / kChunk / (std::string(kFile) + ".mp4"));
  }
  WriteEpisodeTable(plan, numeric, episode_stats, options.videos, out_dir, scratch);
  WriteTaskTable(plan, out_dir, scratch);
  fs::remove_all(scratch, ec);

  WriteJson(out_dir / "meta/info.json", InfoJson(plan, options.videos, video_feature));
  WriteJson(out_dir / "meta/stats.json", stats);
  WriteJson(out_dir / "meta/doasido_manifest.json", ToJson(m));

  ExportSummary summary;
  summary.episodes = static_cast<std::int64_t>(plan.episodes.size());
  summary.frames = plan.total;
  summary.bytes = FolderBytes(out_dir);
  return summary;
}

}  // namespace doasido::dataset
