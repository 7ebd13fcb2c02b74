#include "cli/worker_options.h"

namespace doasido::cli {

void AddWorkerCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    WorkerOptions worker;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "worker", "Claim stage runs from the queue and run them (safe to run many at once)");
  AddDbOptions(*cmd, opt->db);
  AddWorkerOptions(*cmd, opt->worker);
  cmd->add_flag("--until-empty", opt->worker.until_empty,
                "Exit when no work is left (default: keep waiting for new clips)");
  cmd->footer(
      "Workers lease each run; a worker that dies loses its lease and another picks the run up "
      "after --lease seconds. Changing a stage's parameters (--config) queues its finished "
      "runs again; the same parameters are a no-op.\n\n"
      "Examples:\n"
      "  doasido worker --db work/doasido.db --jobs 4 --until-empty\n"
      "  doasido worker --db work/doasido.db --stages probe --config params.toml");
  cmd->callback([opt] {
    const int code = pipeline::RunWorkers(FinishWorkerOptions(opt->worker, opt->db));
    if (code != 0) throw Error("worker", "workers stopped with errors");
  });
}

}  // namespace doasido::cli
