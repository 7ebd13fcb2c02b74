// doasido: turn videos of hands at work into robot manipulation data.
// The command table; each command is defined in cli/<name>_command.cc.
#include <cstdio>
#include <cstdlib>

#include "cli/commands.h"
#include "core/error.h"
#include "core/log.h"

int main(int argc, char** argv) {
  CLI::App app{
      "doasido: curate videos of people using their hands and turn them into robot-hand\n"
      "manipulation data. Clips flow through a queue of stages kept in one SQLite file."};
  app.set_version_flag("--version", "doasido 0.1.0");
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->capture_default_str();
  app.footer(
      "Start here:\n"
      "  doasido init --db work/doasido.db\n"
      "  doasido ingest --db work/doasido.db clips.csv\n"
      "  doasido run --db work/doasido.db --jobs 2\n"
      "  doasido status --db work/doasido.db\n"
      "Run `doasido <command> --help` for each command.");

  using namespace doasido::cli;
  const auto commands = {AddInitCommand, AddIngestCommand, AddStatusCommand,
                         AddQueueCommand, AddWorkerCommand, AddRunCommand,
                         AddRethresholdCommand, AddSynthCommand, AddRetargetCommand,
                         AddReportCommand, AddReviewCommand, AddHandCommand, AddHandsCommand,
                         AddObjectsCommand,
                         AddDeployCommand, AddDatasetCommand,
                         AddShardCommands};
  for (auto add : commands) add(app);

  app.parse_complete_callback([&] { doasido::InitLogging(log_level); });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const doasido::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    // Exit 2: the command was pointed at the wrong thing (a bad config, a
    // missing or foreign database); nothing ran.
    const bool wrong_target = e.code() == "bad_config" || e.code() == "no_database" ||
                              e.code() == "foreign_database";
    return wrong_target ? 2 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
