#include "cli/commands.h"
#include "cli/option_checks.h"
#include "db/database.h"

namespace doasido::cli {
namespace {

// The options of every `queue` subcommand (each sets the ones it takes).
struct QueueOptions {
  DbOptions db;
  std::string stage;
  std::string state;
  std::optional<ClipId> clip;
  int limit = 50;
  bool all = false;
  bool json = false;
};

// The runs as a table, or as JSON.
void PrintRuns(const std::vector<StageRunRow>& rows, bool json) {
  if (json) {
    Json out = Json::array();
    for (const auto& r : rows) {
      out.push_back({{"run", r.run_id}, {"clip", r.clip_id}, {"external_id", r.external_id},
                     {"stage", r.stage}, {"state", ToString(r.state)}, {"attempts", r.attempts},
                     {"verdict", r.verdict}, {"reason", r.reason}, {"error", r.error},
                     {"lease_owner", r.lease_owner}, {"seconds", r.duration_s}});
    }
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  std::printf("%8s %-24s %-16s %-8s %3s %-7s %s\n", "clip", "external id", "stage", "state",
              "try", "verdict", "reason / error");
  for (const auto& r : rows) {
    std::printf("%8lld %-24.24s %-16s %-8s %3d %-7s %s\n", static_cast<long long>(r.clip_id),
                r.external_id.c_str(), r.stage.c_str(), ToString(r.state), r.attempts,
                r.verdict.c_str(), (r.error.empty() ? r.reason : r.error).c_str());
  }
}

// `queue list`: the runs, filtered.
void AddQueueList(CLI::App& cmd, const std::shared_ptr<QueueOptions>& opt) {
  auto* list = cmd.add_subcommand("list", "List stage runs with their state, verdict and error");
  AddDbOptions(*list, opt->db);
  list->add_option("--stage", opt->stage, "Only this stage");
  list->add_option("--state", opt->state, "Only this state")
      ->check(CLI::IsMember({"pending", "running", "done", "failed"}));
  list->add_option("--clip", opt->clip, "Only this clip id")->check(FiniteRange(1, 1000000000000000.0));
  list->add_option("--limit", opt->limit, "At most this many rows (0: all)")->check(FiniteRange(0, 1000000000.0))->capture_default_str();
  list->add_flag("--json", opt->json, "Print JSON");
  list->callback([opt] {
    Database db(opt->db.db, Database::OpenMode::kExisting);
    PrintRuns(db.ListRuns({opt->stage, opt->state, opt->clip, opt->limit}), opt->json);
  });
}

// `queue retry`: failed runs queued again.
void AddQueueRetry(CLI::App& cmd, const std::shared_ptr<QueueOptions>& opt) {
  auto* retry = cmd.add_subcommand("retry", "Queue failed runs again (attempts start over)");
  AddDbOptions(*retry, opt->db);
  retry->add_option("--stage", opt->stage, "Only this stage (default: all)");
  retry->add_option("--clip", opt->clip, "Only this clip id")->check(FiniteRange(1, 1000000000000000.0));
  retry->callback([opt] {
    Database db(opt->db.db, Database::OpenMode::kExisting);
    std::printf("%lld failed runs queued again\n",
                static_cast<long long>(db.Retry(opt->stage, opt->clip)));
  });
}

// `queue reset`: a stage queued again from scratch.
void AddQueueReset(CLI::App& cmd, const std::shared_ptr<QueueOptions>& opt) {
  auto* reset = cmd.add_subcommand(
      "reset", "Queue a stage again from scratch for one clip or all; later stages are dropped");
  AddDbOptions(*reset, opt->db);
  reset->add_option("--stage", opt->stage, "The stage to run again")->required();
  auto* clip = reset->add_option("--clip", opt->clip, "This clip id")->check(FiniteRange(1, 1000000000000000.0));
  auto* all = reset->add_flag("--all", opt->all, "Every clip");
  clip->excludes(all);
  reset->callback([opt] {
    if (!opt->clip && !opt->all) throw Error("usage", "give --clip ID or --all");
    Database db(opt->db.db, Database::OpenMode::kExisting);
    std::printf("%lld runs of %s reset\n",
                static_cast<long long>(db.Reset(opt->stage, opt->clip)), opt->stage.c_str());
  });
}

// `queue release`: the leases of workers that are gone handed back.
void AddQueueRelease(CLI::App& cmd, const std::shared_ptr<QueueOptions>& opt) {
  auto* release = cmd.add_subcommand(
      "release", "Hand back the runs of workers that are gone, without waiting for their leases");
  AddDbOptions(*release, opt->db);
  release->footer(
      "Only when no worker is running on this database: a shard whose Slurm task was\n"
      "cancelled or preempted (its array script runs this before `doasido run`).\n\n"
      "Example:\n  doasido queue release --db work/shards/shard-000/doasido.db");
  release->callback([opt] {
    Database db(opt->db.db, Database::OpenMode::kExisting);
    std::printf("%lld running runs released\n", static_cast<long long>(db.ReleaseLeases()));
  });
}

}  // namespace

void AddQueueCommand(CLI::App& app) {
  auto opt = std::make_shared<QueueOptions>();
  auto* cmd = app.add_subcommand("queue", "List, retry or reset stage runs");
  cmd->require_subcommand(1);
  cmd->footer("Examples:\n"
              "  doasido queue list --db work/doasido.db --state failed\n"
              "  doasido queue retry --db work/doasido.db --stage probe\n"
              "  doasido queue reset --db work/doasido.db --stage probe --clip 17\n"
              "  doasido queue reset --db work/doasido.db --stage probe --all");
  AddQueueList(*cmd, opt);
  AddQueueRetry(*cmd, opt);
  AddQueueReset(*cmd, opt);
  AddQueueRelease(*cmd, opt);
}

}  // namespace doasido::cli
