// `doasido rethreshold`: re-decides the verdict stages from their stored
// measurements under the current --config, without decoding anything.
#include <cstdio>

#include "cli/commands.h"
#include "db/database.h"
#include "pipeline/rethreshold.h"

namespace doasido::cli {

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
                  "Only these stages, comma-separated (default: every pipeline stage that decides "
                  "from stored measurements)")
      ->delimiter(',')
      ->allow_extra_args(false);
  cmd->add_flag("--dry-run", opt->dry_run,
                "Count what would change without writing (first-order: a clip that a change "
                "upstream would send on is not judged)");
  cmd->footer(
      "Reads each finished run's stored measurements, derives the verdict again with the\n"
      "thresholds of --config, and stores the new verdict (history source 'rethreshold').\n"
      "A changed verdict re-queues the clip's later stages and judges them at once when they\n"
      "too decide from measurements; verdicts given by a person are kept. Later `doasido run`\n"
      "with the same --config has nothing left to redo. A clip that a verdict no longer\n"
      "rejects, whose other stages were not measured because of it (not_measured), goes back\n"
      "to the stage that measures (filters_analyze) for `doasido run`.\n\n"
      "Example (reject clips with less than 30% of active frames instead of 10%):\n"
      "  printf '[activity]\\nmin_active_fraction = 0.3\\n' > strict.toml\n"
      "  doasido rethreshold --db work/doasido.db --config strict.toml --dry-run\n"
      "  doasido rethreshold --db work/doasido.db --config strict.toml");
  cmd->callback([opt] {
    const Json config = LoadConfig(opt->db);  // refuses a bad file before any change
    Database db(opt->db.db, Database::OpenMode::kExisting);
    const std::vector<std::string> names = pipeline::RethresholdStages(db, opt->stages);
    std::printf("%-16s %10s %10s %10s %10s\n", "stage", "re-decided", "unchanged", "person",
                "judged");
    for (const auto& name : names) {
      const pipeline::RethresholdTally t =
          pipeline::RethresholdStage(db, name, config, opt->dry_run);
      std::printf("%-16s %10lld %10lld %10lld %10lld\n", name.c_str(),
                  static_cast<long long>(t.redecided), static_cast<long long>(t.unchanged),
                  static_cast<long long>(t.human_kept), static_cast<long long>(t.rerun));
      for (const auto& [what, n] : t.transitions) {
        std::printf("%-16s   %-48s %lld\n", "", what.c_str(), static_cast<long long>(n));
      }
      if (t.remeasure > 0) {
        std::printf("%-16s   %lld clips sent back for the measurement they lack (not_measured "
                    "runs named this stage)\n", "", static_cast<long long>(t.remeasure));
      }
      if (t.downstream > 0) {
        std::printf("%-16s   %lld later runs queued again on the new verdicts\n", "",
                    static_cast<long long>(t.downstream));
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
