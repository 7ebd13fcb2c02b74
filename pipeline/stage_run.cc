#include "pipeline/stage_run.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/bounded_text.h"
#include "core/error_codes.h"
#include "core/whole_output.h"
#include "core/log.h"

namespace doasido::pipeline {
namespace {

// Stored measurements name folders relative to the artifact root, and the
// published folder rather than the run's work folder, so they survive a
// move of the database folder and a merge from a shard.
void StoreRelativePaths(Json& value, const std::filesystem::path& work,
                        const std::filesystem::path& published, const std::filesystem::path& root) {
  if (value.is_object() || value.is_array()) {
    for (Json& member : value) StoreRelativePaths(member, work, published, root);
    return;
  }
  if (!value.is_string()) return;
  std::filesystem::path p = value.get<std::string>();
  if (!p.is_absolute()) return;
  auto under = [](const std::filesystem::path& path, const std::filesystem::path& dir) {
    const auto rel = path.lexically_relative(dir);
    return !rel.empty() && *rel.begin() != "..";
  };
  if (under(p, work)) p = published / p.lexically_relative(work);
  if (under(p, root)) value = p.lexically_relative(root).generic_string();
}

// MJCF files a run wrote name their meshes by absolute path (MuJoCo
// compiles them from a temporary copy elsewhere), so a declared .xml file
// that names the run's work folder is rewritten to name the folder it is
// published as.
void PointXmlAtPublished(const StageResult& result, const std::filesystem::path& work,
                         const std::filesystem::path& published) {
  const std::string from = work.string() + "/", to = published.string() + "/";
  for (const auto& [kind, rel] : result.artifacts) {
    if (std::filesystem::path(rel).extension() != ".xml") continue;
    const auto file = work / rel;
    std::ifstream in(file, std::ios::binary);
    if (!in) continue;
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    if (text.find(from) == std::string::npos) continue;
    for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
      text.replace(at, from.size(), to);
    }
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();  // the last bytes reach the disk here: a full disk shows now
    if (!out) throw Error("io", "cannot rewrite", {.file = file.string()});
  }
}

std::string ClipLabel(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

// Writes `text` whole into the run's artifact folder when it is too long for
// the database; returns the path named in the stored tail, or "" when the
// text fits or the file cannot be written.
// Where a failed run's logs and whole texts are kept: its artifact folder
// is discarded (a failed run has no output a later command may take), but
// a person needs the log that says why. <db folder>/logs/<clip>/<stage>-run<run>-<attempt>/.
std::filesystem::path FailedRunLogs(Database& db, const Claim& claim) {
  return db.ArtifactRoot().parent_path() / "logs" / std::to_string(claim.clip_id) /
         (claim.stage + "-run" + std::to_string(claim.run_id) + "-" + std::to_string(claim.attempts));
}

std::string KeepWhole(Database& db, const Claim& claim, const std::string& file,
                      const std::string& text) {
  if (text.size() <= kMaxStoredTextBytes) return "";
  const std::filesystem::path path = FailedRunLogs(db, claim) / file;
  try {
    std::filesystem::create_directories(path.parent_path());
    WriteFileWhole(path, text);
  } catch (const std::exception& e) {
    spdlog::warn("cannot keep the whole text in {}: {}", path.string(), e.what());
    return "";
  }
  return path.string();
}

// Moves the *.log files of a failed run's folder to FailedRunLogs and
// points `error`, which may name them, there.
void KeepFailedRunLogs(Database& db, const Claim& claim, const std::filesystem::path& work,
                       std::string& error) {
  std::error_code ec;
  const std::filesystem::path logs = FailedRunLogs(db, claim);
  bool moved = false;
  for (const auto& entry : std::filesystem::directory_iterator(work, ec)) {
    if (!entry.is_regular_file(ec) || entry.path().extension() != ".log") continue;
    std::filesystem::create_directories(logs, ec);
    std::filesystem::rename(entry.path(), logs / entry.path().filename(), ec);
    moved = moved || !ec;
  }
  if (!moved) return;
  for (const std::string& from : {work.string(), std::filesystem::absolute(work).string()}) {
    for (std::size_t at = error.find(from); at != std::string::npos; at = error.find(from, at)) {
      error.replace(at, from.size(), logs.string());
      at += logs.string().size();
    }
  }
}

}  // namespace

int AttemptsAllowed(const Claim& claim, std::string_view code, int max_attempts) {
  return IsPermanentError(code) ? claim.attempts : max_attempts;
}

StageRunReport RunClaimedStage(Database& db, stages::Stage& stage, const Claim& claim,
                               const std::string& worker, const std::string& param_hash,
                               int max_attempts, const std::function<void()>& in_same_commit) {
  StageRunReport report;
  std::string code;  // the failure's error code, "" for an exception that is not an Error
  report.clip = std::to_string(claim.clip_id);
  const auto start = std::chrono::steady_clock::now();
  // The run writes into a fresh folder, published only when it succeeded
  // (Database::PublishArtifacts); what a killed run left is removed first.
  const std::filesystem::path work = db.ArtifactWorkDir(claim);
  try {
    ClipContext context = db.LoadContext(claim.clip_id, claim.stage);
    report.clip = ClipLabel(context);
    db.ClaimArtifactRoot();
    db.RemoveArtifactLeftovers(claim.clip_id, claim.stage);
    context.artifact_dir = work;
    std::filesystem::create_directories(work);
    report.result = stage.Run(context);
    PointXmlAtPublished(report.result, work, db.ArtifactDir(claim.clip_id, claim.stage));
    db.PublishArtifacts(claim);
    StoreRelativePaths(report.result.measurements, work,
                       db.ArtifactDir(claim.clip_id, claim.stage), db.ArtifactRoot());
  } catch (const Error& e) {
    report.error = e.what();
    code = e.code();
  } catch (const std::exception& e) {
    report.error = std::string("unexpected: ") + e.what();
  }
  if (report.error.empty()) {
    // Measurements are bounded in the database; a stage that measures more
    // is a bug a retry does not fix. The whole JSON stays in the folder.
    const std::string json = report.result.measurements.dump();
    if (json.size() > kMaxMeasurementBytes) {
      const std::string path = KeepWhole(db, claim, kMeasurementsTooLargeFile, json);
      report.error = Error(kMeasurementsTooLarge,
                           std::to_string(json.size()) + " bytes of measurements, more than the " +
                               std::to_string(kMaxMeasurementBytes) + " the database keeps",
                           {.clip = report.clip, .file = path})
                         .what();
      code = kMeasurementsTooLarge;
    }
  }
  if (!report.error.empty()) KeepFailedRunLogs(db, claim, work, report.error);
  if (report.error.size() > kMaxStoredTextBytes) {
    report.error = BoundedTail(report.error, kMaxStoredTextBytes,
                               KeepWhole(db, claim, kErrorLogFile, report.error));
  }
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Database::Transaction tx(db);
  if (!report.error.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(work, ec);
    std::filesystem::remove(work.parent_path(), ec);  // only when empty
    spdlog::warn("{} on clip {} (attempt {}): {}", claim.stage, report.clip, claim.attempts,
                 report.error);
    db.Fail(claim, worker, report.error, AttemptsAllowed(claim, code, max_attempts));
    report.outcome = RunOutcome::kFailed;
  } else if (db.Complete(claim, worker, param_hash, report.result, report.seconds)) {
    spdlog::debug("{} {} -> {} {}", claim.stage, report.clip, ToString(report.result.verdict),
                  report.result.reason);
    report.outcome = RunOutcome::kDone;
  } else {
    spdlog::warn("{} on clip {}: lease lost before completion; result dropped", claim.stage,
                 report.clip);
    report.outcome = RunOutcome::kLeaseLost;
  }
  if (in_same_commit) in_same_commit();
  tx.Commit();
  return report;
}

}  // namespace doasido::pipeline
