#include "cli/ingest_options.h"
#include "cli/worker_options.h"
#include "db/database.h"

namespace doasido::cli {

void AddRunCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    IngestOptions ingest;
    WorkerOptions worker;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "run", "Ingest lists (optional), then run workers until the queue is empty");
  AddDbOptions(*cmd, opt->db);
  AddIngestOptions(*cmd, opt->ingest);
  AddWorkerOptions(*cmd, opt->worker);
  cmd->footer("Resumable: run it again after a crash or Ctrl-C and it continues where it "
              "stopped.\n\nExample:\n"
              "  doasido run --db work/doasido.db clips.csv --jobs 2");
  cmd->callback([opt] {
    auto worker = opt->worker;
    worker.until_empty = true;
    worker = FinishWorkerOptions(worker, opt->db);  // refuses a bad --config before any work
    std::filesystem::create_directories(std::filesystem::absolute(opt->db.db).parent_path());
    {
      Database db(opt->db.db);
      if (!opt->ingest.lists.empty() && !IngestLists(db, opt->ingest)) {
        throw Error("ingest", "some lists could not be read");
      }
      if (db.Pipeline().empty()) {
        throw Error("pipeline", "empty database: give a clip list or run `doasido init`",
                    {.file = opt->db.db});
      }
    }
    pipeline::RunWorkers(worker);
    Database db(opt->db.db);
    std::printf("\n");
    PrintStatusTable(db);
  });
}

}  // namespace doasido::cli
