// A dataset version as it lies on disk, read back for `dataset show`,
// `verify`, `diff` and the exporters.
//
// Layout of one version (written by dataset/version_writer.h, never changed
// afterwards):
//   <root>/<name>/vK/manifest.json          this struct, as JSON
//   <root>/<name>/vK/episodes/<episode>/     trajectory.json (HandTrajectory
//                                            JSON, retarget/kinematic_retarget.h)
//                                            and the files of the stages it
//                                            came from (recon/..., retarget/...)
//   <root>/<name>/vK/playbook/               report.html, report.json, *.csv
//                                            of exactly the clips considered
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "robot/trajectory/format.h"

namespace doasido::dataset {

// manifest.json's "format" and "format_version".
inline constexpr const char* kManifestFormat = "doasido-dataset";
inline constexpr int kManifestFormatVersion = 1;
inline constexpr const char* kManifestFile = "manifest.json";
// Beside the manifest: its own SHA-256 ("<hex>  manifest.json", as sha256sum
// writes it), so an edited manifest is caught by `dataset verify`.
inline constexpr const char* kManifestHashFile = "manifest.sha256";
inline constexpr const char* kEpisodesFolder = "episodes";
inline constexpr const char* kPlaybookFolder = "playbook";
// Every episode folder holds its robot trajectory under the name the
// trajectory stage wrote it.
using retarget::kTrajectoryFile;

// Which trajectories a version takes.
enum class Selection {
  kVerified,  // a person accepted the trajectory in /verify
  kSuccess,   // the trajectory stage passed it (not flagged, not rejected)
  kAll,       // passed or flagged by the trajectory stage
};
const char* ToString(Selection s);
// Throws Error("bad_option") naming `--select` for other text.
Selection ParseSelection(const std::string& text);

struct FileEntry {
  std::string path;  // relative to the version folder, '/'-separated
  std::string sha256;
  std::int64_t size = 0;
};

// One stage's say on the episode's clip.
struct StageProvenance {
  std::string stage;
  std::string param_hash;
  std::string verdict;  // pass | reject | flag
  std::string reason;
  std::string source;  // stage | rethreshold | human (latest verdict row)
  // When the run finished: with the stage, it names the run (row ids change
  // when shards merge). Absent in manifests from before it was recorded.
  std::optional<double> finished_at;
};

struct Verification {
  std::string reviewer;
  double at = 0;  // seconds since the epoch
  std::string reason;
};

struct Episode {
  std::string id;  // folder name under episodes/: "clip-<clip id>"
  std::int64_t index = 0;  // 0.. in manifest order
  std::int64_t clip_id = 0;
  std::string external_id;
  std::string video;  // absolute path or URL of the source video
  std::string video_key;  // what splits group by (the video path)
  std::optional<std::int64_t> start_frame, end_frame;  // inclusive span, as listed
  std::optional<double> start_s, end_s;
  std::string source_list;
  long source_line = 0;
  std::string task;  // from the list row: narration, else "verb object", else genre
  std::string split;  // train | val | test | ...
  std::string trajectory_stage;  // retarget or retarget_kinematic
  std::int64_t frames = 0;       // trajectory length
  double fps = 0;
  std::string embodiment;
  // The trajectory has no object (a hand-only clip: the hands alone were
  // reconstructed and retargeted); exports leave object features out.
  bool hand_only = false;
  std::vector<StageProvenance> stages;  // pipeline order
  // The upstream runs the trajectory run consumed, as it recorded them
  // (Database::UpstreamInputs); null when it recorded none.
  Json upstream;
  std::optional<Verification> verification;
  Json metadata = Json::object();  // the list row's other columns
};

// A clip the version considered and left out, with the stage that decided
// it: what `dataset diff` gives as the reason an episode went away.
struct Exclusion {
  std::int64_t clip_id = 0;
  std::string external_id;
  StageProvenance decided_by;  // the first stage that did not pass, or the
                               // trajectory stage when the selection refused it
  std::string why;             // e.g. "interaction: reject (no_interaction)"
};

struct Manifest {
  std::string name;
  std::string version;  // "v3"
  std::string parent;   // previous version of the name, or empty
  double created_at = 0;
  std::string tool_version;
  std::string tool_revision;
  std::string database;  // absolute path of the database it was made from
  Selection selection = Selection::kVerified;
  std::vector<std::pair<std::string, double>> split_fractions;  // in the order given
  std::int64_t seed = 0;
  std::string trajectory_stage;  // retarget, else retarget_kinematic
  std::vector<Episode> episodes;
  std::vector<Exclusion> excluded;  // clips considered and not taken, by id
  std::vector<FileEntry> files;  // every file of the version but manifest.json
  // `dataset create --allow-stale`: made although these clips' runs were
  // not settled ("clip 3 (why)"), which a version otherwise refuses.
  bool allow_stale = false;
  std::vector<std::string> stale;
};

Json ToJson(const Manifest& m);
// Throws Error("bad_manifest") naming the field.
Manifest ManifestFromJson(const Json& j);

// Reads <version_dir>/manifest.json. Throws Error("bad_manifest") naming the
// file and field, Error("io") when it cannot be read.
Manifest ReadManifest(const std::filesystem::path& version_dir);

}  // namespace doasido::dataset
