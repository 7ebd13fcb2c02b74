#include "dataset/episode_selection.h"

#include <algorithm>
#include <cstdio>
#include <map>

#include "core/error.h"
#include "ingest/file_sha256.h"
#include "robot/trajectory/format.h"

namespace doasido::dataset {
namespace {

StageProvenance ProvenanceOf(const Database::ReportRun& r) {
  return {r.stage, r.param_hash, r.verdict, r.reason, r.verdict_source, r.finished_at};
}

std::string Describe(const Database::ReportRun& r) {
  if (r.state != "done") return r.stage + ": " + r.state;
  std::string text = r.stage + ": " + r.verdict;
  if (!r.reason.empty()) text += " (" + r.reason + ")";
  if (r.verdict_source == "rethreshold" || r.verdict_source == kHumanVerdictSource) {
    text += " by " + r.verdict_source;
  }
  return text;
}

// Why `selection` refuses a done trajectory run, or empty when it takes it.
std::string Refusal(const Database::ReportRun& r, Selection selection) {
  if (r.verdict != "pass" && r.verdict != "flag") return Describe(r);
  if (selection == Selection::kAll) return "";
  if (r.verdict != "pass") return Describe(r) + ", not passed";
  if (selection == Selection::kVerified && r.verdict_source != kHumanVerdictSource) {
    return r.stage + ": not verified by a person";
  }
  return "";
}

// The SHA-256 of the trajectory file of the clip's recorded trajectory run,
// or "" when there is none to read.
std::string CurrentTrajectorySha(Database& db, ClipId clip, const std::string& stage) {
  const auto run = db.RecordedOutput(clip, stage, true);
  if (!run) return "";
  const auto file = run->dir / kTrajectoryFile;
  std::error_code ec;
  return std::filesystem::exists(file, ec) ? ingest::FileSha256(file) : "";
}

std::string Text(const Json& metadata, const char* key) {
  const auto it = metadata.find(key);
  if (it == metadata.end() || !it->is_string()) return "";
  return it->get<std::string>();
}

}  // namespace

std::string TrajectoryStage(const std::vector<std::string>& pipeline) {
  if (std::string stage = retarget::TrajectoryStageOf(pipeline); !stage.empty()) return stage;
  throw Error("no_trajectory_stage",
              "the pipeline has no retargeting stage (add retarget or retarget_kinematic with "
              "`doasido init --pipeline ...`)",
              {.field = "pipeline"});
}

std::string TaskOf(const Json& metadata) {
  if (std::string n = Text(metadata, "narration"); !n.empty()) return n;
  const std::string verb = Text(metadata, "verb");
  std::string noun = Text(metadata, "object");
  if (noun.empty()) noun = Text(metadata, "noun");
  if (!verb.empty()) return noun.empty() ? verb : verb + " " + noun;
  if (std::string g = Text(metadata, "genre"); !g.empty()) return g;
  return "manipulate the object";
}

EpisodeSelection SelectEpisodes(Database& db, Selection selection) {
  EpisodeSelection out;
  out.trajectory_stage = TrajectoryStage(db.Pipeline());
  std::map<ClipId, std::vector<Database::ReportRun>> runs;
  for (Database::ReportRun& r : db.ReportRuns()) runs[r.clip_id].push_back(std::move(r));
  std::map<ClipId, Database::ReviewRow> accepted;  // latest acceptance of a trajectory
  for (Database::ReviewRow& r : db.ListReviews()) {
    if (r.stage == out.trajectory_stage && r.decision == "accept") accepted[r.clip_id] = r;
  }
  std::map<ClipId, std::string> videos;
  for (const ClipRecord& clip : db.ListClips(&videos)) {
    Episode e;
    e.clip_id = clip.id;
    e.external_id = clip.external_id;
    std::optional<Exclusion> stop;
    bool reached = false;
    for (const Database::ReportRun& r : runs[clip.id]) {
      e.stages.push_back(ProvenanceOf(r));
      const bool trajectory = r.stage == out.trajectory_stage;
      std::string why = trajectory             ? Refusal(r, selection)
                        : r.verdict != "pass" ? Describe(r)
                                              : "";
      if (trajectory && why.empty() && r.state == "done") {
        // A person's acceptance counts for the trajectory they saw only.
        const auto it = accepted.find(clip.id);
        const std::string sha = it == accepted.end() || it->second.artifact_sha256.empty()
                                    ? ""
                                    : CurrentTrajectorySha(db, clip.id, r.stage);
        if (it != accepted.end() && (sha.empty() || sha != it->second.artifact_sha256)) {
          if (selection == Selection::kVerified) {
            why = r.stage + ": the trajectory changed since " + it->second.reviewer + " verified it";
          }
          accepted.erase(it);  // verified a trajectory this one replaced
        }
      }
      if (!why.empty()) {
        stop = Exclusion{clip.id, clip.external_id, ProvenanceOf(r), why};
        break;
      }
      if (trajectory) {
        reached = true;
        e.upstream = r.inputs;
        break;
      }
    }
    if (!stop && !reached) {
      const auto& last = runs[clip.id];
      stop = Exclusion{clip.id, clip.external_id,
                       last.empty() ? StageProvenance{} : ProvenanceOf(last.back()),
                       "no " + out.trajectory_stage + " run"};
    }
    if (stop) {
      out.excluded.push_back(std::move(*stop));
      continue;
    }
    char id[32];
    std::snprintf(id, sizeof id, "clip-%06lld", static_cast<long long>(clip.id));
    e.id = id;
    e.video = videos[clip.id];
    e.video_key = e.video;
    e.start_frame = clip.start_frame;
    e.end_frame = clip.end_frame;
    e.start_s = clip.start_s;
    e.end_s = clip.end_s;
    e.source_list = clip.source_list;
    e.source_line = clip.source_line;
    e.task = TaskOf(clip.metadata);
    e.trajectory_stage = out.trajectory_stage;
    e.metadata = clip.metadata;
    if (const auto it = accepted.find(clip.id); it != accepted.end()) {
      e.verification = Verification{it->second.reviewer, it->second.created_at, it->second.reason};
    }
    out.episodes.push_back(std::move(e));
  }
  return out;
}

}  // namespace doasido::dataset
