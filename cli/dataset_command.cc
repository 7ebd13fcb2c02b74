// `doasido dataset`: versions of verified trajectories and their exports.
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>

#include "cli/commands.h"
#include "cli/output_options.h"
#include "core/progress.h"
#include "dataset/lerobot_export.h"
#include "dataset/robomimic_export.h"
#include "dataset/version_diff.h"
#include "dataset/version_files.h"
#include "dataset/version_store.h"
#include "db/database.h"

namespace doasido::cli {
namespace {

namespace fs = std::filesystem;
using namespace doasido::dataset;

struct Options {
  DbOptions db;
  std::string root = "datasets";
  std::string name = kDefaultDatasetName;
  std::string select = "verified";
  std::string split = "train=0.8,val=0.1,test=0.1";
  std::int64_t seed = 0;
  bool no_thumbnails = false;
  bool allow_empty = false;
  bool allow_stale = false;
  std::string version, other;
  std::string format;
  std::string out;
  bool json = false;
  bool no_videos = false;
  bool no_verify = false;
  bool hand_object_only = false;
  double fps = 0;
};

void AddRootOptions(CLI::App& cmd, Options& o) {
  cmd.add_option("--root", o.root, "Folder holding the datasets (<root>/<name>/vK)")
      ->capture_default_str();
  cmd.add_option("--name", o.name, "Dataset name")->capture_default_str();
}

std::string Date(double t) {
  const std::time_t s = static_cast<std::time_t>(t);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M", std::localtime(&s));
  return buf;
}

std::string SplitCounts(const Manifest& m) {
  std::map<std::string, int> n;
  for (const Episode& e : m.episodes) n[e.split]++;
  std::string text;
  for (const auto& [split, fraction] : m.split_fractions) {
    text += (text.empty() ? "" : ", ") + split + " " + std::to_string(n[split]);
  }
  return text;
}

void Create(const Options& o) {
  Database db(o.db.db, Database::OpenMode::kExisting);
  // A dataset root holds many versions: a new one never replaces anything,
  // so an existing root is this command's own (and no --force is needed);
  // the guard keeps it out of versions, the database and the artifacts.
  CheckOutputPath({.path = o.root,
                   .kind = OutputRequest::Kind::kFolder,
                   .option = "--root",
                   .what = "the dataset root",
                   .is_own_output = [](const fs::path&) { return true; },
                   .force = true,
                   .databases = {o.db.db}});
  CreateOptions c;
  c.name = o.name;
  c.selection = ParseSelection(o.select);
  c.splits = ParseSplits(o.split);
  c.seed = o.seed;
  c.thumbnails = !o.no_thumbnails;
  c.allow_empty = o.allow_empty;
  c.allow_stale = o.allow_stale;
  Progress progress("dataset", 0);
  const Manifest m = CreateVersion(db, o.root, c, [&progress](int done, int total) {
    progress.SetTotal(static_cast<std::uint64_t>(total));
    progress.Set(static_cast<std::uint64_t>(done));
  });
  progress.Finish();
  std::int64_t bytes = 0;
  for (const FileEntry& f : m.files) bytes += f.size;
  std::printf("created %s/%s: %zu episodes (%s) of %zu clips considered, %zu files, %.1f MB%s\n",
              m.name.c_str(), m.version.c_str(), m.episodes.size(), SplitCounts(m).c_str(),
              m.episodes.size() + m.excluded.size(), m.files.size(), static_cast<double>(bytes) / 1e6,
              m.parent.empty() ? "" : (", parent " + m.parent).c_str());
  if (!m.stale.empty()) {
    std::printf("--allow-stale: %zu clips had unsettled runs (recorded in the manifest)\n",
                m.stale.size());
  }
  std::printf("%s\n", (fs::path(o.root) / m.name / m.version).c_str());
}

void List(const Options& o) {
  const auto versions = ListVersions(o.root);
  for (const VersionRef& v : ListStrayVersions(o.root)) {
    std::printf("%s/%s is not a version: %s has no %s\n", v.name.c_str(), v.version.c_str(),
                v.dir.c_str(), kManifestFile);
  }
  if (versions.empty()) {
    std::printf("no versions under %s (make one with `doasido dataset create`)\n", o.root.c_str());
    return;
  }
  std::printf("%-16s %-6s %-16s %8s %9s %-8s %s\n", "name", "vers", "created", "episodes",
              "selection", "parent", "revision");
  for (const VersionRef& v : versions) {
    // One broken version is named; the healthy ones are still listed.
    Manifest m;
    try {
      if (const std::string why = ManifestHashProblem(v.dir); !why.empty()) {
        throw Error("corrupt_version", why, {.file = (v.dir / kManifestFile).string()});
      }
      m = ReadManifest(v.dir);
    } catch (const Error& e) {
      std::printf("%-16s %-6s BROKEN: %s\n", v.name.c_str(), v.version.c_str(), e.what());
      continue;
    }
    std::printf("%-16s %-6s %-16s %8zu %9s %-8s %s\n", v.name.c_str(), v.version.c_str(),
                Date(m.created_at).c_str(), m.episodes.size(), ToString(m.selection),
                m.parent.empty() ? "-" : m.parent.c_str(), m.tool_revision.c_str());
  }
}

void Show(const Options& o) {
  const fs::path dir = FindVersion(o.root, o.name, o.version);
  if (const std::string why = ManifestHashProblem(dir); !why.empty()) {
    throw Error("corrupt_version", why + " (doasido dataset verify names every difference)",
                {.file = (dir / kManifestFile).string()});
  }
  const Manifest m = ReadManifest(dir);
  if (o.json) {
    std::printf("%s\n", ToJson(m).dump(2).c_str());
    return;
  }
  std::printf("%s/%s  %s  created %s by doasido %s (%s)\n", m.name.c_str(), m.version.c_str(),
              dir.c_str(), Date(m.created_at).c_str(), m.tool_version.c_str(),
              m.tool_revision.c_str());
  std::printf("selection %s of stage %s; splits %s (seed %lld); parent %s\n", ToString(m.selection),
              m.trajectory_stage.c_str(), SplitCounts(m).c_str(), static_cast<long long>(m.seed),
              m.parent.empty() ? "-" : m.parent.c_str());
  std::printf("%zu episodes, %zu clips left out; database %s\n\n", m.episodes.size(),
              m.excluded.size(), m.database.c_str());
  // kind: hand-object (a trajectory with object poses: dynamics when the
  // trajectory stage is `retarget`) or hand-only.
  std::printf("%-12s %-24s %-6s %6s %-11s %-24s %s\n", "episode", "clip", "split", "frames", "kind",
              "task", "verified by");
  for (const Episode& e : m.episodes) {
    std::printf("%-12s %-24.24s %-6s %6lld %-11s %-24.24s %s\n", e.id.c_str(),
                e.external_id.c_str(), e.split.c_str(), static_cast<long long>(e.frames),
                e.hand_only ? "hand-only" : "hand-object", e.task.c_str(),
                e.verification ? e.verification->reviewer.c_str() : "-");
  }
  std::map<std::string, int> why;
  for (const Exclusion& x : m.excluded) why[x.decided_by.stage + " " + x.decided_by.verdict]++;
  if (!why.empty()) std::printf("\nleft out:\n");
  for (const auto& [stage, n] : why) std::printf("  %5d  %s\n", n, stage.c_str());
}

void Diff(const Options& o) {
  const Manifest a = ReadManifest(FindVersion(o.root, o.name, o.version));
  const Manifest b = ReadManifest(FindVersion(o.root, o.name, o.other));
  const auto changes = DiffVersions(a, b);
  if (o.json) {
    Json out = Json::array();
    for (const auto& c : changes) {
      out.push_back({{"change", ToString(c.kind)}, {"clip_id", c.clip_id},
                     {"external_id", c.external_id}, {"reasons", c.reasons}});
    }
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  std::map<EpisodeChange::Kind, int> n;
  for (const auto& c : changes) {
    n[c.kind]++;
    std::printf("%-8s clip %-6lld %-24s", ToString(c.kind), static_cast<long long>(c.clip_id),
                c.external_id.c_str());
    for (size_t i = 0; i < c.reasons.size(); ++i) {
      std::printf("%s%s\n", i ? "                                          " : "",
                  c.reasons[i].c_str());
    }
  }
  std::printf("%s -> %s: %d added, %d removed, %d changed\n", a.version.c_str(), b.version.c_str(),
              n[EpisodeChange::Kind::kAdded], n[EpisodeChange::Kind::kRemoved],
              n[EpisodeChange::Kind::kChanged]);
}

void RequireIntact(const fs::path& dir);

void Verify(const Options& o) {
  const fs::path dir = FindVersion(o.root, o.name, o.version);
  const auto problems = VerifyVersion(dir);
  if (problems.empty()) {
    const Manifest m = ReadManifest(dir);
    std::printf("%s/%s: all %zu files match the manifest\n", m.name.c_str(), m.version.c_str(),
                m.files.size());
    return;
  }
  RequireIntact(dir);
}

// The problems `dataset verify` finds, printed; throws Error("corrupt_version").
void RequireIntact(const fs::path& dir) {
  const auto problems = VerifyVersion(dir);
  if (problems.empty()) return;
  for (const FileProblem& p : problems) {
    std::fprintf(stderr, "%s: %s\n", (dir / p.path).c_str(), p.what.c_str());
  }
  throw Error("corrupt_version",
              std::to_string(problems.size()) + " files of the version do not match its manifest",
              {.file = (dir / problems.front().path).string()});
}

void Export(const Options& o) {
  const fs::path dir = FindVersion(o.root, o.name, o.version);
  const bool robomimic = o.format == "robomimic";
  // An export replaces its own earlier export (atomically, see the
  // exporters); anything else at --out is refused.
  CheckOutputPath(
      {.path = o.out,
       .kind = robomimic ? OutputRequest::Kind::kFile : OutputRequest::Kind::kFolder,
       .what = robomimic ? "the robomimic HDF5 file" : "the LeRobot folder",
       .is_own_output = robomimic ? std::function<bool(const fs::path&)>([](const fs::path& p) {
                                      return FileStartsWith(p, std::string("\x89HDF\r\n\x1a\n", 8));
                                    })
                                  : FolderHolds({"meta/info.json"}),
       .force = true});
  // What is exported is what the manifest proves, or it is not exported.
  if (o.no_verify) {
    std::fprintf(stderr, "not verifying %s against its manifest (--no-verify)\n", dir.c_str());
  } else {
    RequireIntact(dir);
  }
  ExportSummary s;
  std::vector<fs::path> removed;
  const bool lerobot = o.format == "lerobot";
  if (!lerobot && o.format != "robomimic") {
    throw Error("bad_option", "unknown format '" + o.format + "'", {.field = "--format"});
  }
  WriteWhole(o.out, lerobot ? OutputKind::kFolder : OutputKind::kFile, [&](const fs::path& temp) {
    s = lerobot ? ExportLeRobot(dir, temp, {.videos = !o.no_videos, .fps = o.fps,
                                                        .hand_object_only = o.hand_object_only}) : ExportRobomimic(dir, temp);
  }, &removed);
  for (const fs::path& p : removed) {
    std::fprintf(stderr, "removed %s (left by a killed export)\n", p.c_str());
  }
  std::printf("wrote %s: %lld episodes, %lld frames, %.2f MB\n", o.out.c_str(),
              static_cast<long long>(s.episodes), static_cast<long long>(s.frames),
              static_cast<double>(s.bytes) / 1e6);
}

// `dataset create`: the next version, from the database.
void AddCreateCommand(CLI::App& cmd, const std::shared_ptr<Options>& o) {
  auto* create = cmd.add_subcommand("create", "Make the next version from the database");
  AddDbOptions(*create, o->db);
  AddRootOptions(*create, *o);
  create->add_option("--select", o->select,
                     "verified: accepted by a person in `review serve` /verify; success: passed "
                     "by the trajectory stage; all: passed or flagged")
      ->capture_default_str()
      ->check(CLI::IsMember({"verified", "success", "all"}));
  create->add_option("--split", o->split,
                     "Fractions of episodes per split; a video goes whole to one split")
      ->capture_default_str();
  create->add_option("--seed", o->seed, "Seed of the split assignment")->capture_default_str();
  create->add_flag("--no-thumbnails", o->no_thumbnails,
                   "Playbook report without example thumbnails (no decoding)");
  create->add_flag("--allow-empty", o->allow_empty, "Make a version even with no episodes");
  create->add_flag("--allow-stale", o->allow_stale,
                   "Make a version although some clips' runs are pending, running or stale "
                   "(computed from an earlier upstream run or other parameters); recorded in the "
                   "manifest. Without it such a version is refused, naming the clips");
  create->callback([o] { Create(*o); });
}

// `dataset export`: a version in a training format.
void AddExportCommand(CLI::App& cmd, const std::shared_ptr<Options>& o) {
  auto* exp = cmd.add_subcommand("export", "Write a version in a training format");
  AddRootOptions(*exp, *o);
  exp->add_option("version", o->version, "vK, name/vK or a version folder")->required();
  exp->add_option("--format", o->format,
                  "lerobot: a LeRobot v3.0 folder (Parquet and MP4); robomimic: one HDF5 file")
      ->required()
      ->check(CLI::IsMember({"lerobot", "robomimic"}));
  exp->add_option("--out", o->out,
                  "Output folder (lerobot) or file (robomimic); written beside it and renamed "
                  "into place, replacing an earlier export only when complete")
      ->required();
  exp->add_flag("--hand-object-only", o->hand_object_only,
                "lerobot: leave out the hand-only episodes, so that observation.object_pose is exported");
  exp->add_flag("--no-verify", o->no_verify,
                "Export without first checking every file against the manifest (says so)");
  exp->add_flag("--no-videos", o->no_videos,
                "lerobot: leave out the source video feature (no decoding or encoding)");
  exp->add_option("--fps", o->fps,
                  "lerobot: resample every episode (and its video) to this rate; needed when "
                  "the clips' cameras ran at different rates (e.g. 25 and 30 fps)")
      ->check(CLI::Range(1.0, 1000.0));
  exp->callback([o] { Export(*o); });
}

}  // namespace

void AddDatasetCommand(CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "dataset", "Versioned datasets of retargeted trajectories: create, list, show, diff, "
                 "verify, export");
  cmd->require_subcommand(1);
  cmd->footer(
      "A version is immutable: <root>/<name>/vK/ holds the episodes (robot trajectory with the\n"
      "object's poses, the reconstruction it came from), manifest.json (every file's SHA-256,\n"
      "each episode's provenance) and the playbook report of every clip considered.\n"
      "Examples:\n"
      "  doasido dataset create --db work/doasido.db --root work/datasets --select verified\n"
      "  doasido dataset list   --root work/datasets\n"
      "  doasido dataset diff   --root work/datasets v1 v2\n"
      "  doasido dataset verify --root work/datasets v2\n"
      "  doasido dataset export --root work/datasets v2 --format lerobot --out work/lerobot\n"
      "  doasido dataset export --root work/datasets v2 --format robomimic --out demo.hdf5");

  AddCreateCommand(*cmd, o);

  auto* list = cmd->add_subcommand("list", "List the versions under --root");
  list->add_option("--root", o->root, "Folder holding the datasets")->capture_default_str();
  list->callback([o] { List(*o); });

  auto* show = cmd->add_subcommand("show", "Episodes, splits and provenance of one version");
  AddRootOptions(*show, *o);
  show->add_option("version", o->version, "vK, name/vK or a version folder")->required();
  show->add_flag("--json", o->json, "Print the manifest");
  show->callback([o] { Show(*o); });

  auto* diff = cmd->add_subcommand(
      "diff", "Episodes added, removed and changed between two versions, and why");
  AddRootOptions(*diff, *o);
  diff->add_option("old", o->version, "The older version")->required();
  diff->add_option("new", o->other, "The newer version")->required();
  diff->add_flag("--json", o->json, "Print JSON");
  diff->callback([o] { Diff(*o); });

  auto* verify = cmd->add_subcommand(
      "verify", "Check every file of a version against its manifest (SHA-256); exit 1 naming "
                "the files that differ");
  AddRootOptions(*verify, *o);
  verify->add_option("version", o->version, "vK, name/vK or a version folder")->required();
  verify->callback([o] { Verify(*o); });

  AddExportCommand(*cmd, o);
}

}  // namespace doasido::cli
