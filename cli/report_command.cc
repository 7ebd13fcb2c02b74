#include <filesystem>

#include "cli/commands.h"
#include "cli/output_options.h"
#include "core/config_check.h"
#include "db/database.h"
#include "reports/report.h"

namespace doasido::cli {

void AddReportCommand(CLI::App& app) {
  struct Options {
    DbOptions db;
    std::string out;
    int max_thumbnails = reports::ThumbnailOptions{}.max_per_reason;
    bool no_thumbnails = false;
    bool force = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "report", "Write the playbook report: funnel, score distributions, examples per reason, "
                "sources and run statistics as one self-contained HTML page plus JSON and CSV");
  AddDbOptions(*cmd, opt->db);
  cmd->add_option("--out", opt->out, "Folder for report.html, report.json and the CSV files")
      ->required();
  cmd->add_option("--max-thumbnails", opt->max_thumbnails,
                  "Example clips shown per rejection reason")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-thumbnails", opt->no_thumbnails,
                "Skip decoding videos for example thumbnails (numbers and charts only)");
  AddForceFlag(*cmd, opt->force);
  cmd->footer("Example:\n  doasido report --db work/doasido.db --out work/report\n"
              "  xdg-open work/report/report.html\n"
              "The [report] table of --config sets the rest (histogram_bins, max_failures,\n"
              "thumbnail.panel_height, thumbnail.jpeg_quality, ...).");
  cmd->callback([opt, cmd] {
    Database db(opt->db.db, Database::OpenMode::kExisting);
    CheckOutputPath({.path = opt->out,
                     .kind = OutputRequest::Kind::kFolder,
                     .what = "the report",
                     .is_own_output = FolderHolds({"report.html", "report.json"}),
                     .force = opt->force,
                     .databases = {opt->db.db}});
    reports::ReportOptions options;
    ReadCheckedSection(LoadConfig(opt->db), reports::kReportSection, options);
    // Given on the command line, it wins over the config file.
    if (cmd->count("--max-thumbnails") > 0) {
      options.thumbnail.max_per_reason = opt->max_thumbnails;
    }
    if (opt->no_thumbnails) options.thumbnails = false;
    reports::ReportOutput out;
    WriteWhole(opt->out, OutputKind::kFolder, [&](const std::filesystem::path& temp) {
      out = reports::WriteReport(db, temp, options);
    });
    // Named where they are now, not where they were written.
    auto moved = [&](const std::filesystem::path& p) {
      return (std::filesystem::path(opt->out) / p.filename()).string();
    };
    out.html = moved(out.html);
    out.json = moved(out.json);
    for (auto& p : out.csv) p = moved(p);
    const auto& f = out.data.funnel;
    std::printf("%lld clips, %lld survive (%.1f%%)\n", static_cast<long long>(f.pool),
                static_cast<long long>(f.survivors), reports::Percent(f.survivors, f.pool));
    const auto& dl = out.data.downloads;
    if (dl.fetched + dl.reused + dl.failed > 0) {
      std::string reasons;
      for (const auto& [reason, n] : dl.failures_by_reason) {
        reasons += (reasons.empty() ? " (" : ", ") + reason + " " + std::to_string(n);
      }
      std::printf("downloads: %lld fetched, %.1f MB at %.1f MB/s, %lld reused, %lld failed%s\n",
                  static_cast<long long>(dl.fetched), static_cast<double>(dl.bytes) / 1e6,
                  dl.bytes_per_s / 1e6, static_cast<long long>(dl.reused),
                  static_cast<long long>(dl.failed), (reasons + (reasons.empty() ? "" : ")")).c_str());
    }
    for (const auto& note : out.data.notes) std::printf("note: %s\n", note.c_str());
    std::printf("wrote %s\n      %s\n", out.html.c_str(), out.json.c_str());
    for (const auto& p : out.csv) std::printf("      %s\n", p.c_str());
  });
}

}  // namespace doasido::cli
