#include <cstdio>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "db/database.h"
#include "review/server.h"
#include "cli/review_reasons.h"
#include "review/study.h"
#include "stages/stage_registry.h"

namespace doasido::cli {
namespace {

void PrintSummary(const review::StudySummary& s) {
  auto pct = [](double v) { return 100.0 * v; };
  std::printf("study %s: %d items (%d complete), %d raters per item, %d ratings\n",
              s.name.c_str(), s.items, s.complete_items, s.raters_per_item, s.ratings);
  std::printf("  A preferred   %6.1f%%  (%d)\n", pct(s.share_a), s.a);
  std::printf("  B preferred   %6.1f%%  (%d)\n", pct(s.share_b), s.b);
  std::printf("  ties          %6.1f%%  (%d)\n", pct(s.share_tie), s.tie);
  if (s.win_rate_a) std::printf("  A win rate among non-ties  %.1f%%\n", pct(*s.win_rate_a));
  if (s.unanimous_share) {
    std::printf("  unanimous items  %.1f%% (%d of %d)\n", pct(*s.unanimous_share),
                s.unanimous_items, s.complete_items);
  }
  if (s.kappa) {
    if (s.kappa->defined) {
      std::printf("  Fleiss' kappa  %.3f  (P_bar %.3f, P_e %.3f)\n", s.kappa->kappa,
                  s.kappa->P_bar, s.kappa->P_e);
    } else {
      std::printf("  Fleiss' kappa  undefined: %s\n", s.kappa->note.c_str());
    }
  } else {
    std::printf("  Fleiss' kappa  needs at least one item with all its ratings\n");
  }
}

}  // namespace

void AddStageReasons(review::ServeOptions& options) {
  // The page offers every reason code a stage can give (the registry's).
  for (const auto& r : stages::StageReasons()) options.stage_reasons.push_back({r.code, r.label});
  options.default_reasons = stages::ReviewDefaultReasons();
}

namespace {

// `review serve`: the page of flagged clips and the studies.
void AddServeCommand(CLI::App& review) {
  struct ServeArgs {
    DbOptions db;
    review::ServeOptions serve;
  };
  auto serve = std::make_shared<ServeArgs>();
  auto* srv = review.add_subcommand("serve", "Serve the review page (flagged clips) and studies");
  AddDbOptions(*srv, serve->db);
  srv->add_option("--host", serve->serve.host, "Address to listen on (loopback unless "
                                             "--allow-remote)")
      ->capture_default_str();
  srv->add_option("--port", serve->serve.port, "Port (0: any free port)")->check(FiniteRange(0, 65535))->capture_default_str();
  srv->add_flag("--allow-remote", serve->serve.allow_remote,
              "Allow a non-loopback --host (anyone who reaches it sees the clips)");
  srv->add_option("--reviewer", serve->serve.reviewer, "Reviewer name filled in on the page");
  srv->footer(
      "Open the printed address in a browser. Keys: a accept, r reject, j/k next/previous,\n"
      "space play/pause. Studies are at /study/<name>?rater=<name>.\n\n"
      "Example:\n"
      "  doasido review serve --db work/doasido.db --reviewer alice --port 8470");
  srv->callback([serve] {
    AddStageReasons(serve->serve);
    review::ReviewServer server(serve->db.db, serve->serve);
    // Ctrl-C ends the process: every decision is its own committed
    // transaction, so there is nothing to flush.
    server.Serve([&](int port) {
      const std::string& host = serve->serve.host;
      const std::string url_host = host.find(':') != std::string::npos ? "[" + host + "]" : host;
      std::printf("doasido review: http://%s:%d/  (Ctrl-C stops)\n", url_host.c_str(), port);
      std::fflush(stdout);
    });
  });
}

// `review study create`: a study from an items CSV.
void AddStudyCreateCommand(CLI::App& study) {
  struct CreateArgs {
    DbOptions db;
    std::string name, items;
    int raters = 3;
    std::int64_t seed = 1;
  };
  auto create = std::make_shared<CreateArgs>();
  auto* c = study.add_subcommand("create", "Create a study from an items CSV");
  AddDbOptions(*c, create->db);
  c->add_option("--name", create->name, "Study name (letters, digits, _ - .)")->required();
  c->add_option("--items", create->items,
                "CSV with item_id, source_video, a_video, b_video, a_label, b_label (paths "
                "relative to the CSV)")
      ->required();
  c->add_option("--raters", create->raters, "Raters per item")->check(FiniteRange(1, 1000))->capture_default_str();
  c->add_option("--seed", create->seed, "Seed of the left/right layout")->capture_default_str();
  c->footer(
      "Example:\n"
      "  doasido review study create --db work/doasido.db --name tracking --items items.csv\n"
      "  # then: doasido review serve --db work/doasido.db; open /study/tracking?rater=ann");
  c->callback([create] {
    Database db(create->db.db, Database::OpenMode::kExisting);
    review::CreateStudyFromCsv(db, create->name, create->items, create->raters, create->seed);
    const auto s = db.GetStudy(create->name);
    std::printf("study %s: %zu items, %d raters per item\n", create->name.c_str(),
                db.GetStudyItems(s->id).size(), s->raters_per_item);
  });
}

// `review study summary`: shares, win rate, unanimity and kappa of a study.
void AddStudySummaryCommand(CLI::App& study) {
  struct SummaryArgs {
    DbOptions db;
    std::string name;
    bool json = false;
  };
  auto summary = std::make_shared<SummaryArgs>();
  auto* m = study.add_subcommand("summary", "Preference shares, win rate, unanimity, Fleiss' "
                                             "kappa");
  AddDbOptions(*m, summary->db);
  m->add_option("--name", summary->name, "Study name")->required();
  m->add_flag("--json", summary->json, "Print JSON");
  m->footer("Example:\n  doasido review study summary --db work/doasido.db --name tracking --json");
  m->callback([summary] {
    Database db(summary->db.db, Database::OpenMode::kExisting);
    const auto s = review::SummarizeStudy(db, summary->name);
    if (summary->json) {
      std::printf("%s\n", review::ToJson(s).dump(2).c_str());
    } else {
      PrintSummary(s);
    }
  });
}

}  // namespace

void AddReviewCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "review", "Review flagged clips in a local web app, and run preference studies");
  cmd->require_subcommand(1);
  cmd->footer(
      "Example:\n"
      "  doasido review serve --db work/doasido.db --reviewer alice\n"
      "  doasido review study create --db work/doasido.db --name tracking --items items.csv\n"
      "  doasido review study summary --db work/doasido.db --name tracking --json");
  AddServeCommand(*cmd);

  auto* study = cmd->add_subcommand("study", "Preference studies: two renderings side by side");
  study->require_subcommand(1);
  study->footer(
      "Example:\n"
      "  doasido review study create --db work/doasido.db --name tracking --items items.csv");
  AddStudyCreateCommand(*study);
  AddStudySummaryCommand(*study);
}

}  // namespace doasido::cli
