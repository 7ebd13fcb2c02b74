#include "pipeline/stage_run.h"

#include <chrono>
#include <filesystem>

#include "core/bounded_text.h"
#include "core/error_codes.h"
#include "core/output_path.h"
#include "core/log.h"
#include "core/permanent_error.h"

namespace doasido::pipeline {
namespace {

std::string ClipLabel(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
}

// Writes `text` whole into the run's artifact folder when it is too long for
// the database; returns the path named in the stored tail, or "" when the
// text fits or the file cannot be written.
std::string KeepWhole(Database& db, const Claim& claim, const std::string& file,
                      const std::string& text) {
  if (text.size() <= kMaxStoredTextBytes) return "";
  const std::filesystem::path path = db.ArtifactDir(claim.clip_id, claim.stage) / file;
  try {
    std::filesystem::create_directories(path.parent_path());
    WriteFileAtomically(path, text);
  } catch (const std::exception& e) {
    spdlog::warn("cannot keep the whole text in {}: {}", path.string(), e.what());
    return "";
  }
  return path.string();
}

}  // namespace

StageRunReport RunClaimedStage(Database& db, Stage& stage, const Claim& claim,
                               const std::string& worker, const std::string& param_hash,
                               int max_attempts, const std::function<void()>& in_same_commit) {
  StageRunReport report;
  bool permanent = false;  // a retry cannot fix it: fail now
  report.clip = std::to_string(claim.clip_id);
  const auto start = std::chrono::steady_clock::now();
  try {
    ClipContext context = db.LoadContext(claim.clip_id, claim.stage);
    report.clip = ClipLabel(context);
    std::filesystem::create_directories(context.artifact_dir);
    report.result = stage.Run(context);
  } catch (const PermanentError& e) {
    report.error = e.what();
    permanent = true;
  } catch (const Error& e) {
    report.error = e.what();
    permanent = IsPermanentError(e.code());
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
      permanent = true;
    }
  }
  if (report.error.size() > kMaxStoredTextBytes) {
    report.error = BoundedTail(report.error, kMaxStoredTextBytes,
                               KeepWhole(db, claim, kErrorLogFile, report.error));
  }
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Database::Transaction tx(db);
  if (!report.error.empty()) {
    spdlog::warn("{} on clip {} (attempt {}): {}", claim.stage, report.clip, claim.attempts,
                 report.error);
    db.Fail(claim, worker, report.error, permanent ? claim.attempts : max_attempts);
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
