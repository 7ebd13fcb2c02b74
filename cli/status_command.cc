#include <map>

#include "cli/commands.h"
#include "db/database.h"

namespace doasido::cli {

// Prints the stage x state x verdict table a person reads first.
void PrintStatusTable(Database& db) {
  const auto counts = db.Counts();
  std::printf("%lld clips from %lld videos\n\n", static_cast<long long>(db.CountClips()),
              static_cast<long long>(db.CountVideos()));
  // not_meas: runs whose measurement an earlier verdict made unnecessary
  // (their reason names it; core/records.h).
  std::printf("%-20s %8s %8s %8s %8s %8s %8s %8s\n", "stage", "pending", "running", "pass",
              "reject", "flag", "not_meas", "failed");
  std::vector<std::string> order;
  std::map<std::string, std::map<std::string, long long>> cells;
  std::map<std::string, std::map<std::string, long long>> reasons;
  for (const auto& c : counts) {
    if (!cells.count(c.stage)) order.push_back(c.stage);
    const std::string column = c.state == "done" ? c.verdict : c.state;
    cells[c.stage][column] += c.count;
    if (c.state == "done" && c.verdict != "pass" && !c.reason.empty()) {
      reasons[c.stage][c.verdict + ":" + c.reason] += c.count;
    }
  }
  for (const auto& stage : order) {
    auto& row = cells[stage];
    std::printf("%-20s %8lld %8lld %8lld %8lld %8lld %8lld %8lld\n", stage.c_str(),
                row["pending"], row["running"], row["pass"], row["reject"], row["flag"],
                row[ToString(Verdict::kNotMeasured)], row["failed"]);
    for (const auto& [reason, n] : reasons[stage]) {
      std::printf("%-20s   %-40s %lld\n", "", reason.c_str(), n);
    }
  }
  const auto s = db.Summary();
  if (s.expired > 0) {
    std::printf("\n%lld running stage runs have expired leases (a worker died); a worker will "
                "pick them up\n", static_cast<long long>(s.expired));
  }
  if (s.failed > 0) {
    std::printf("\n%lld stage runs failed: `doasido queue list --state failed` shows why, "
                "`doasido queue retry` tries them again\n", static_cast<long long>(s.failed));
  }
  for (const auto& [stage, n] : db.CountRequeued()) {
    std::printf("\n%lld runs queued again because their %s run changed (they re-run after it)\n",
                static_cast<long long>(n), stage.c_str());
  }
  if (s.sharded > 0) {
    std::printf("\n%lld unfinished stage runs belong to shards (below); `doasido merge` brings "
                "their results back\n", static_cast<long long>(s.sharded));
  }
  PrintShardTable(db);
}

void AddStatusCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    bool json = false;
    bool clips = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("status", "Show how many clips are in each stage, state and "
                                           "verdict");
  AddDbOptions(*cmd, opt->db);
  cmd->add_flag("--json", opt->json, "Counts per stage x state x verdict x reason as JSON");
  cmd->add_flag("--clips", opt->clips, "One line per clip: where it stopped in the pipeline and why");
  cmd->footer("Example:\n  doasido status --db work/doasido.db\n"
              "  doasido status --db work/doasido.db --clips\n"
              "  doasido status --db work/doasido.db --json | jq '.counts'");
  cmd->callback([opt] {
    Database db(opt->db.db, Database::OpenMode::kExisting);
    if (opt->clips) return PrintClipTable(db);
    if (!opt->json) return PrintStatusTable(db);
    Json counts = Json::array();
    for (const auto& c : db.Counts()) {
      counts.push_back({{"stage", c.stage}, {"state", c.state}, {"verdict", c.verdict},
                        {"reason", c.reason}, {"count", c.count}});
    }
    const auto s = db.Summary();
    const Json out = {{"database", db.path().string()},
                      {"pipeline", db.Pipeline()},
                      {"clips", db.CountClips()},
                      {"videos", db.CountVideos()},
                      {"queue", {{"pending", s.pending}, {"running", s.running},
                                 {"done", s.done}, {"failed", s.failed},
                                 {"expired_leases", s.expired}, {"sharded", s.sharded}}},
                      {"requeued_by_upstream", db.CountRequeued()},
                      {"counts", counts}};
    std::printf("%s\n", out.dump(2).c_str());
  });
}

}  // namespace doasido::cli
