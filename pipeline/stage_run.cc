#include "pipeline/stage_run.h"

#include <chrono>
#include <filesystem>

#include "core/error_codes.h"
#include "core/log.h"
#include "core/permanent_error.h"

namespace doasido::pipeline {
namespace {

std::string ClipLabel(const ClipContext& context) {
  return context.clip.external_id.empty() ? std::to_string(context.clip.id)
                                          : context.clip.external_id;
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
