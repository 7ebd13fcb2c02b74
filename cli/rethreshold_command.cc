// `doasido rethreshold`: re-decides the verdict stages from their stored
// measurements under the current --config, without decoding anything.
#include <cstdio>
#include <map>

#include "cli/commands.h"
#include "cli/stage_registry.h"
#include "core/log.h"
#include "db/database.h"

namespace doasido::cli {
namespace {

struct StageTally {
  std::int64_t redecided = 0, unchanged = 0, human_kept = 0, rerun = 0;
  std::map<std::string, std::int64_t> transitions;  // "pass -> reject:no_activity"
};

// The measurements without the thresholds recorded beside each score: what
// later stages may read.
Json WithoutThresholds(Json measurements) {
  if (measurements.contains("summary") && measurements["summary"].is_object()) {
    measurements["summary"].erase("scores");
  }
  return measurements;
}

std::string Outcome(const std::string& verdict, const std::string& reason) {
  return reason.empty() ? verdict : verdict + ":" + reason;
}

// Re-decides every finished run of `name` and then runs, in process, the
// runs of `name` that are pending (clips a change upstream sent on).
StageTally RethresholdStage(Database& db, const std::string& name, const Json& config,
                            bool dry_run) {
  StageTally tally;
  const auto stage = MakeStage(name, config);
  const std::string hash = ParamHash(stage->Params());
  const auto runs = db.ListRuns({.stage = name, .state = "done"});
  constexpr size_t kBatch = 500;
  for (size_t begin = 0; begin < runs.size(); begin += kBatch) {
    Database::Transaction tx(db);
    for (size_t i = begin; i < std::min(runs.size(), begin + kBatch); ++i) {
      const StageRunRow& run = runs[i];
      const auto measurements = db.GetMeasurements(run.clip_id, name);
      if (!measurements) continue;
      const std::optional<StageResult> result = stage->Redecide(*measurements);
      if (!result) continue;
      const bool verdict_changed =
          run.verdict != ToString(result->verdict) || run.reason != result->reason;
      const bool changed = verdict_changed || WithoutThresholds(*measurements) !=
                                                  WithoutThresholds(result->measurements);
      if (dry_run) {
        const auto history = db.VerdictHistory(run.clip_id, name);
        if (!history.empty() && history.back().source == "human") {
          ++tally.human_kept;
          continue;
        }
        ++tally.redecided;
      } else if (!db.StoreRedecision(run.clip_id, name, hash, *result, changed)) {
        ++tally.human_kept;
        continue;
      } else {
        ++tally.redecided;
      }
      if (verdict_changed) {
        ++tally.transitions[Outcome(run.verdict, run.reason) + " -> " +
                            Outcome(ToString(result->verdict), result->reason)];
      } else {
        ++tally.unchanged;
      }
    }
    if (!dry_run) tx.Commit();
  }
  if (dry_run) return tally;
  const std::string worker = "rethreshold";
  while (auto claim = db.ClaimNext(worker, {name}, 600, 3)) {
    Database::Transaction tx(db);
    try {
      const StageResult result = stage->Run(db.LoadContext(claim->clip_id, name));
      db.Complete(*claim, worker, hash, result, 0);
      ++tally.transitions["(queued) -> " + Outcome(ToString(result.verdict), result.reason)];
      ++tally.rerun;
    } catch (const Error& e) {
      db.Fail(*claim, worker, e.what(), 3);
    }
    tx.Commit();
  }
  return tally;
}

}  // namespace

void AddRethresholdCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    std::vector<std::string> stages;
    bool dry_run = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "rethreshold",
      "Re-decide the filter verdicts from stored measurements with new thresholds (no decoding)");
  AddDbOptions(*cmd, opt->db);
  cmd->add_option("--stages", opt->stages,
                  "Only these stages (default: every pipeline stage that decides from stored "
                  "measurements)")
      ->delimiter(',');
  cmd->add_flag("--dry-run", opt->dry_run,
                "Count what would change without writing (first-order: a clip that a change "
                "upstream would send on is not judged)");
  cmd->footer(
      "Reads each finished run's stored measurements, derives the verdict again with the\n"
      "thresholds of --config, and stores the new verdict (history source 'rethreshold').\n"
      "A changed verdict re-queues the clip's later stages and judges them at once when they\n"
      "too decide from measurements; verdicts given by a person are kept. Later `doasido run`\n"
      "with the same --config has nothing left to redo.\n\n"
      "Example (reject clips with less than 30% of active frames instead of 10%):\n"
      "  printf '[activity]\\nmin_active_fraction = 0.3\\n' > strict.toml\n"
      "  doasido rethreshold --db work/doasido.db --config strict.toml --dry-run\n"
      "  doasido rethreshold --db work/doasido.db --config strict.toml");
  cmd->callback([opt] {
    Database db(opt->db.db);
    const Json config = LoadConfig(opt->db);
    std::vector<std::string> names;
    for (const auto& stage : db.Pipeline()) {
      bool eligible = false;
      for (const auto& entry : StageTable()) {
        if (entry.name == stage) eligible = entry.decides_from_measurements;
      }
      const bool wanted = opt->stages.empty() ||
                          std::find(opt->stages.begin(), opt->stages.end(), stage) !=
                              opt->stages.end();
      if (eligible && wanted) names.push_back(stage);
    }
    for (const auto& wanted : opt->stages) {
      if (std::find(names.begin(), names.end(), wanted) == names.end()) {
        throw Error("bad_stage",
                    "'" + wanted + "' is not a pipeline stage that decides from measurements",
                    {.file = opt->db.db, .field = "stages"});
      }
    }
    std::printf("%-16s %10s %10s %10s %10s\n", "stage", "re-decided", "unchanged", "person",
                "judged");
    for (const auto& name : names) {
      const StageTally t = RethresholdStage(db, name, config, opt->dry_run);
      std::printf("%-16s %10lld %10lld %10lld %10lld\n", name.c_str(),
                  static_cast<long long>(t.redecided), static_cast<long long>(t.unchanged),
                  static_cast<long long>(t.human_kept), static_cast<long long>(t.rerun));
      for (const auto& [what, n] : t.transitions) {
        std::printf("%-16s   %-48s %lld\n", "", what.c_str(), static_cast<long long>(n));
      }
    }
    if (opt->dry_run) {
      std::printf("\n(dry run: nothing written)\n");
      return;
    }
    std::printf("\n");
    PrintStatusTable(db);
  });
}

}  // namespace doasido::cli
