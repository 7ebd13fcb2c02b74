#include "dataset/version_store.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <regex>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include "core/error.h"
#include "core/test_pause.h"
#include "core/tree_copy.h"
#include "core/whole_output.h"
#include "core/tool_version.h"
#include "dataset/episode_selection.h"
#include "dataset/settled_runs.h"
#include "dataset/version_files.h"
#include "recon/reconstruction.h"
#include "reports/report.h"
#include "robot/trajectory/format.h"

namespace doasido::dataset {
namespace {

namespace fs = std::filesystem;

const std::regex kVersionName("v([1-9][0-9]*)");

void CheckName(const std::string& name) {
  static const std::regex ok("[A-Za-z0-9_-][A-Za-z0-9_.-]*");
  if (!std::regex_match(name, ok)) {
    throw Error("bad_option", "'" + name + "' is not a dataset name (letters, digits, _ . -)",
                {.field = "--name"});
  }
}

// Copies a stage's artifact folder into the episode, when the stage made one.
void CopyTree(const fs::path& from, const fs::path& to, const std::string& clip) {
  std::error_code ec;
  if (!fs::is_directory(from, ec)) return;
  CopyTreeAsOurs(from, to, ec);
  if (ec) {
    throw Error("io", "cannot copy " + from.string() + " into the version: " + ec.message(),
                {.clip = clip, .file = to.string()});
  }
}

// Copies one episode's files into `episode_dir` and fills in what the
// trajectory says (frames, fps, embodiment).
// Why an episode cannot be written (its recorded trajectory run's file is
// missing), naming the run and the file; empty when it can.
std::string MissingTrajectory(Database& db, const Episode& e) {
  std::string why;
  const auto run = db.RecordedOutput(e.clip_id, e.trajectory_stage, true, &why);
  if (!run) return why;
  std::error_code ec;
  if (!fs::exists(run->dir / kTrajectoryFile, ec)) {
    return "missing_trajectory: " + e.trajectory_stage + " run " + std::to_string(run->run_id) +
           " has no " + (run->dir / kTrajectoryFile).string();
  }
  return "";
}

// Copies one episode's files into `episode_dir` and fills in what the
// trajectory says (frames, fps, embodiment). The files are those of the
// runs the database records (Database::RecordedOutput); MissingTrajectory
// was checked first.
void WriteEpisode(Database& db, Episode& e, const fs::path& episode_dir) {
  const std::string clip = e.external_id.empty() ? std::to_string(e.clip_id) : e.external_id;
  const fs::path trajectory_dir = db.ArtifactDir(e.clip_id, e.trajectory_stage);
  CopyTree(trajectory_dir, episode_dir / e.trajectory_stage, clip);
  if (const auto recon = db.RecordedOutput(e.clip_id, recon::kReconStageName, true)) {
    CopyTree(recon->dir, episode_dir / recon::kReconStageName, clip);
  }
  const fs::path trajectory = episode_dir / e.trajectory_stage / kTrajectoryFile;
  std::error_code ec;
  if (!fs::exists(trajectory, ec)) {
    throw Error("missing_trajectory", "the trajectory stage's artifact is missing",
                {.clip = clip, .file = (trajectory_dir / kTrajectoryFile).string()});
  }
  // The same bytes twice: a hard link where the file system allows one.
  fs::create_hard_link(trajectory, episode_dir / kTrajectoryFile, ec);
  if (ec) {
    ec.clear();
    fs::copy_file(trajectory, episode_dir / kTrajectoryFile, ec);
  }
  if (ec) throw Error("io", "cannot copy: " + ec.message(), {.clip = clip, .file = trajectory.string()});
  try {
    const retarget::HandTrajectory t = retarget::ReadTrajectoryJson(trajectory);
    e.frames = static_cast<std::int64_t>(t.qpos.size());
    e.fps = t.fps;
    e.embodiment = t.embodiment;
    e.hand_only = t.object_poses.empty();
  } catch (const Error& err) {
    throw Error(err.code(), err.message(),
                {.clip = clip, .file = (trajectory_dir / kTrajectoryFile).string(),
                 .field = err.site().field});
  }
}

}  // namespace

namespace {

// Folders named vK under `root`, with (`with_manifest`) or without one.
std::vector<VersionRef> VersionFolders(const fs::path& root, bool with_manifest) {
  std::vector<VersionRef> out;
  std::error_code ec;
  for (const auto& name_dir : fs::directory_iterator(root, ec)) {
    const std::string name = name_dir.path().filename().string();
    if (name.empty() || name[0] == '.' || !name_dir.is_directory()) continue;
    for (const auto& v : fs::directory_iterator(name_dir.path(), ec)) {
      std::smatch m;
      const std::string leaf = v.path().filename().string();
      if (!std::regex_match(leaf, m, kVersionName) ||
          fs::exists(v.path() / kManifestFile) != with_manifest) {
        continue;
      }
      out.push_back({name, leaf, std::stoi(m[1]), v.path()});
    }
  }
  std::sort(out.begin(), out.end(), [](const VersionRef& a, const VersionRef& b) {
    return a.name != b.name ? a.name < b.name : a.number < b.number;
  });
  return out;
}

}  // namespace

std::vector<VersionRef> ListVersions(const fs::path& root) { return VersionFolders(root, true); }

std::vector<VersionRef> ListStrayVersions(const fs::path& root) {
  return VersionFolders(root, false);
}

fs::path FindVersion(const fs::path& root, const std::string& name, const std::string& version) {
  std::error_code ec;
  if (fs::exists(fs::path(version) / kManifestFile, ec)) return version;
  const size_t slash = version.find('/');
  const std::string want_name = slash == std::string::npos ? name : version.substr(0, slash);
  const std::string want = slash == std::string::npos ? version : version.substr(slash + 1);
  std::string known;
  for (const VersionRef& v : ListVersions(root)) {
    if (v.name == want_name && v.version == want) return v.dir;
    known += (known.empty() ? "" : ", ") + v.name + "/" + v.version;
  }
  throw Error("no_version",
              "no version '" + want_name + "/" + want + "' under " + root.string() +
                  (known.empty() ? " (there are none yet: doasido dataset create)"
                                 : " (there are: " + known + ")"),
              {.field = "version"});
}

namespace {

// The steps of CreateVersion.

// The clips whose runs are not settled; refused unless --allow-stale.
std::vector<UnsettledClip> CheckSettled(Database& db, const CreateOptions& options) {
  std::map<ClipId, std::string> external_ids;
  for (const ClipRecord& clip : db.ListClips()) external_ids[clip.id] = clip.external_id;
  std::vector<UnsettledClip> unsettled = FindUnsettled(db.ReportRuns(), external_ids);
  if (!unsettled.empty() && !options.allow_stale) {
    throw Error("unsettled_runs",
                std::to_string(unsettled.size()) +
                    " clips have runs that are not settled, so a version would mix old and new "
                    "results: " + NameClips(unsettled) +
                    ". Let the workers finish (`doasido run`), or pass --allow-stale to cut the "
                    "version anyway (recorded in its manifest)",
                {.clip = std::to_string(unsettled.front().clip_id), .field = "--allow-stale"});
  }
  return unsettled;
}

// The next version's number under `root` (past every version of the name
// and every stray vK folder) and its parent.
int NextVersionNumber(const fs::path& root, const std::string& name, std::string& parent) {
  int number = 1;
  for (const VersionRef& v : ListVersions(root)) {
    if (v.name != name) continue;
    number = v.number + 1;
    parent = v.version;
  }
  // A vK folder without a manifest is not a version; the next one numbers
  // past it instead of colliding with it on every run.
  for (const VersionRef& v : ListStrayVersions(root)) {
    if (v.name != name) continue;
    std::fprintf(stderr, "%s is not a version (no %s); left alone\n", v.dir.c_str(), kManifestFile);
    number = std::max(number, v.number + 1);
  }
  return number;
}

// Writes the episodes, the playbook report and the manifest into `temp`.
// An episode whose file is missing is left out, named; the others are
// written.
void WriteVersionFiles(Database& db, const CreateOptions& options, const fs::path& temp,
                       Manifest& m, const std::function<void(int, int)>& progress) {
  std::vector<Episode> written;
  for (size_t i = 0; i < m.episodes.size(); ++i) {
    Episode& e = m.episodes[i];
    if (const std::string missing = MissingTrajectory(db, e); !missing.empty()) {
      std::fprintf(stderr, "left out clip %lld: %s\n", static_cast<long long>(e.clip_id),
                   missing.c_str());
      m.excluded.push_back({e.clip_id, e.external_id,
                            e.stages.empty() ? StageProvenance{} : e.stages.back(), missing});
      continue;
    }
    e.index = static_cast<std::int64_t>(written.size());
    WriteEpisode(db, e, temp / kEpisodesFolder / e.id);
    TestPause(kPauseVersionEpisode);
    written.push_back(std::move(e));
    if (progress) progress(static_cast<int>(i + 1), static_cast<int>(m.episodes.size()));
  }
  m.episodes = std::move(written);
  if (m.episodes.empty() && !options.allow_empty) {
    throw Error("empty_version", "every selected episode's trajectory file is missing",
                {.field = "--select"});
  }
  reports::ReportOptions report;
  report.thumbnails = options.thumbnails;
  reports::WriteReport(db, temp / kPlaybookFolder, report);
  m.files = HashFiles(temp);
  WriteManifest(m, temp);
}

// Throws Error(kRunsChanged) naming the first selected episode whose
// recorded run of a stage is no longer the one selected (queued again,
// running, or finished again since): the version would mix what it
// selected with what it copied.
void RefuseChangedRuns(Database& db, const std::vector<Episode>& selected) {
  std::map<std::pair<ClipId, std::string>, Database::ReportRun> now;
  for (Database::ReportRun& r : db.ReportRuns()) {
    const std::pair<ClipId, std::string> key{r.clip_id, r.stage};
    now.emplace(key, std::move(r));
  }
  for (const Episode& e : selected) {
    for (const StageProvenance& s : e.stages) {
      const auto it = now.find({e.clip_id, s.stage});
      std::string what;
      if (it == now.end()) {
        what = "is no longer recorded";
      } else if (it->second.state != "done") {
        what = "is " + it->second.state + " now (queued again)";
      } else if (s.finished_at && it->second.finished_at != s.finished_at) {
        what = "finished again";
      } else {
        continue;
      }
      const std::string clip = e.external_id.empty() ? std::to_string(e.clip_id) : e.external_id;
      throw Error(kRunsChanged,
                  "the runs changed while the version was written: clip " + clip + "'s " +
                      s.stage + " run " + what +
                      "; nothing was published, run `doasido dataset create` again once the "
                      "workers are done",
                  {.clip = clip, .file = db.path().string(), .field = s.stage});
    }
  }
}

// Moves the finished `temp` into place as `final_dir`, never over another
// run's version.
void PublishVersion(const fs::path& temp, const fs::path& final_dir, const std::string& version) {
  if (renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, final_dir.c_str(), RENAME_NOREPLACE) == 0) return;
  const int err = errno;
  std::error_code ec;
  fs::remove_all(temp, ec);
  UnmarkTemporary(temp);
  if (err == EEXIST || err == ENOTEMPTY) {
    throw Error("version_exists", "another run created " + version + " first; run again",
                {.file = final_dir.string()});
  }
  throw Error("io", std::string("cannot rename the version into place: ") + std::strerror(err),
              {.file = final_dir.string()});
}

}  // namespace

Manifest CreateVersion(Database& db, const fs::path& root, const CreateOptions& options,
                       const std::function<void(int, int)>& progress) {
  CheckName(options.name);
  // Rows and folders of before a merge or of after it, never between.
  const Database::ArtifactLock reading = db.LockForReading();
  const std::vector<UnsettledClip> unsettled = CheckSettled(db, options);
  EpisodeSelection selection = SelectEpisodes(db, options.selection);
  if (selection.episodes.empty() && !options.allow_empty) {
    throw Error("empty_version",
                "no clip's trajectory meets --select " + std::string(ToString(options.selection)) +
                    " (" + std::to_string(selection.excluded.size()) + " clips considered)",
                {.field = "--select"});
  }
  const fs::path dataset_dir = root / options.name;
  std::error_code ec;
  fs::create_directories(dataset_dir, ec);
  if (ec) throw Error("io", "cannot create: " + ec.message(), {.file = dataset_dir.string()});
  for (const fs::path& p : RemoveAbandonedTemporaries(dataset_dir)) {
    std::fprintf(stderr, "removed %s (left by a killed `dataset create`)\n", p.c_str());
  }

  Manifest m;
  m.name = options.name;
  m.version = "v" + std::to_string(NextVersionNumber(root, options.name, m.parent));
  m.created_at = static_cast<double>(std::time(nullptr));
  m.tool_version = ToolVersion();
  m.tool_revision = SourceRevision();
  m.database = fs::absolute(db.path()).string();
  m.selection = options.selection;
  m.split_fractions = options.splits;
  m.seed = options.seed;
  m.trajectory_stage = selection.trajectory_stage;
  m.allow_stale = options.allow_stale;
  for (const UnsettledClip& u : unsettled) m.stale.push_back(NameClips({u}));
  m.excluded = std::move(selection.excluded);
  m.episodes = std::move(selection.episodes);
  AssignSplits(m.episodes, options.splits, options.seed);

  const fs::path temp = TempSibling(dataset_dir / m.version);
  MarkTemporary(temp);
  const std::vector<Episode> selected = m.episodes;
  try {
    fs::create_directories(temp / kEpisodesFolder, ec);
    if (ec) throw Error("io", "cannot create: " + ec.message(), {.file = temp.string()});
    try {
      WriteVersionFiles(db, options, temp, m, progress);
    } catch (const Error&) {
      RefuseChangedRuns(db, selected);  // a copy that failed because a run moved on
      throw;
    }
    RefuseChangedRuns(db, selected);
  } catch (...) {
    fs::remove_all(temp, ec);
    UnmarkTemporary(temp);
    throw;
  }
  PublishVersion(temp, dataset_dir / m.version, m.version);
  UnmarkTemporary(temp);
  return m;
}

}  // namespace doasido::dataset
