// Export of a version in LeRobot's v3.0 layout (REFERENCE §6):
//   meta/info.json        codebase_version "v3.0", robot_type, fps, features,
//                         totals, chunks_size, path templates, splits
//   meta/stats.json       min, max, mean, std, count, q01/q10/q50/q90/q99 per
//                         numeric feature and dimension
//   meta/tasks.parquet    task (string) -> task_index
//   meta/episodes/chunk-000/file-000.parquet   one row per episode: indices,
//                         lengths, data and video locations, per-episode stats
//   data/chunk-000/file-000.parquet            one row per frame, one row group
//                         per episode (dataset/parquet_writer.h for the limit)
//   videos/observation.images.source/chunk-000/file-000.mp4   the episodes'
//                         source spans, one after another (video/mp4_writer.h)
//   meta/doasido_manifest.json   the version's manifest (provenance)
// Frame features: observation.state (the robot's joint positions), action
// (the actuator targets when every trajectory has them, else the next
// frame's joint positions), observation.object_pose (tx, ty, tz, qw, qx, qy,
// qz, when every trajectory has object poses: absent, not zero-filled, as
// soon as one episode is hand-only); float32, as LeRobot stores them. The
// episodes table marks hand-only episodes in its doasido/hand_only column. Episodes are ordered by split so that each split is one index range
// in info.json's "splits". Everything goes into one data file and one video
// file (no rollover at data_files_size_in_mb / video_files_size_in_mb).
#pragma once

#include <filesystem>

#include "dataset/robomimic_export.h"

namespace doasido::dataset {

inline constexpr const char* kLeRobotVersion = "v3.0";
inline constexpr const char* kStateFeature = "observation.state";
inline constexpr const char* kActionFeature = "action";
inline constexpr const char* kObjectPoseFeature = "observation.object_pose";
inline constexpr const char* kSourceVideoFeature = "observation.images.source";
inline constexpr const char* kHandOnlyColumn = "doasido/hand_only";  // episodes table, BOOLEAN

struct LeRobotOptions {
  bool videos = true;  // encode the source spans (needs the source videos)
  // > 0: every episode resampled to this rate (dataset/resample.h), its
  // video frames picked to match; 0: episodes must share the first one's.
  double fps = 0;
  // Leave out the hand-only episodes: a version that mixes them with
  // hand-object ones then exports observation.object_pose (which a single
  // hand-only episode drops for all). Throws Error("empty_version") when no
  // hand-object episode is left.
  bool hand_object_only = false;
};

// Writes the export into `out_dir`, which must not exist or be empty.
// Throws Error("output_exists"), Error("mixed_trajectories") naming the
// episode whose fps (without options.fps) or joints differ from the first
// one's, Error("io"), Error("parquet"), Error("video_encode"), and the
// decoder's errors naming the clip's video.
ExportSummary ExportLeRobot(const std::filesystem::path& version_dir,
                            const std::filesystem::path& out_dir, const LeRobotOptions& options);

}  // namespace doasido::dataset
