#include <filesystem>

#include "cli/commands.h"
#include "stages/stage_registry.h"
#include "db/database.h"

namespace doasido::cli {

void AddInitCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    std::vector<std::string> pipeline;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("init", "Create a database (or upgrade one) and set its pipeline");
  AddDbOptions(*cmd, opt->db);
  std::string stages;
  for (const auto& entry : stages::StageTable()) {
    const double limit = entry.timeout_s;
    const std::string limit_text =
        limit >= 3600 ? std::to_string(static_cast<int>(limit / 3600)) + " h"
                      : std::to_string(static_cast<int>(limit / 60)) + " min";
    stages += "\n  " + entry.name + std::string(14 - std::min<size_t>(13, entry.name.size()), ' ') +
              entry.summary + " [limit " + limit_text + "]";
  }
  cmd->add_option("--pipeline", opt->pipeline,
                  "Ordered stages every clip goes through, or presets: `default` (the whole "
                  "chain, what init gives without --pipeline), `filters` (the filtering job "
                  "alone, for its report); a preset word in a list stands for its stages, e.g. "
                  "filters,hands,bundle,recon,retarget_kinematic")
      ->delimiter(',')
      ->allow_extra_args(false);
  std::string presets;
  for (const auto& [name, list] : stages::PipelinePresets()) {
    presets += "\n  " + name + std::string(14 - std::min<size_t>(13, name.size()), ' ');
    for (size_t i = 0; i < list.size(); ++i) presets += (i ? "," : "") + list[i];
  }
  cmd->footer("Stages:" + stages + "\n\nPresets:" + presets +
              "\n\nEach stage run has a wall-clock limit; a run past it fails as stage_timeout "
              "(not retried, except for download). A run that reports progress (frames "
              "decoded, solver iterations, a model command's log growing) and then stands still "
              "for no_progress seconds (default 900) fails the same way. Change limits by stage "
              "in --config:\n"
              "  [timeouts]\n  probe = 30      # seconds\n  bundle = 14400\n"
              "  no_progress = 600"
              "\n\nExample:\n  doasido init --db work/doasido.db\n"
              "  doasido init --db work/report-only.db --pipeline filters\n"
              "  doasido init --db work/queue-test.db --pipeline noop\n"
              "  doasido init --db work/kinematic.db --pipeline filters,hands,bundle,recon,retarget_kinematic");
  cmd->callback([opt] {
    LoadConfig(opt->db);  // a bad --config is refused before the database is touched
    // So is a bad --pipeline.
    std::vector<std::string> pipeline = stages::ExpandPipeline(
        opt->pipeline.empty() ? std::vector<std::string>{stages::kPresetDefault} : opt->pipeline);
    std::filesystem::create_directories(
        std::filesystem::absolute(opt->db.db).parent_path());
    Database db(opt->db.db);
    if (opt->pipeline.empty() && !db.Pipeline().empty()) {
      pipeline = db.Pipeline();  // re-running init keeps an existing pipeline
    }
    db.SetPipeline(pipeline, stages::FlagContinuingStages(pipeline));
    std::string joined;
    for (const auto& s : pipeline) joined += (joined.empty() ? "" : " -> ") + s;
    std::printf("%s: schema %d, pipeline %s\n", db.path().c_str(), db.SchemaVersion(),
                joined.c_str());
  });
}

}  // namespace doasido::cli
