// How long the report's numbers take for a pool of clips, against the peers
// a user already runs on the same database in the same process:
//   status   Database::Counts() (what `doasido status` reads)
//   naive    GetMeasurements() of every clip and stage, parsing the whole
//            JSON (per-frame signals included) as a reader without
//            json_extract would
//   report   CollectReport + RenderHtml + ReportToJson, no thumbnails
// Each clip has seven stage runs with 300-frame signal arrays and scores.
// Usage: reports_collect_bench [clips]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/log.h"
#include "db/database.h"
#include "reports/html_report.h"
#include "reports/report_data.h"
#include "reports/report_files.h"
#include "filters/activity.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/verdict.h"
#include "stages/probe_stage.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace doasido;

namespace {

const std::vector<std::string> kPipeline = {
    doasido::stages::kProbeStageName,          doasido::filters::kAnalyzeStageName,
    doasido::filters::kInteractionStageName,  doasido::filters::kOutOfFrameStageName,
    doasido::filters::kShotBoundaryStageName, doasido::filters::kActivityStageName,
    doasido::filters::kCameraMotionStageName};

void Build(Database& db, int clips) {
  db.SetPipeline(kPipeline);
  Database::Transaction tx(db);
  for (int i = 0; i < clips; ++i) {
    ClipRecord c;
    c.video_id = db.UpsertVideo("/videos/v" + std::to_string(i) + ".mp4");
    c.external_id = "c" + std::to_string(i);
    c.metadata = {{"source", i % 3 ? "internet" : "egocentric"}};
    db.InsertClip(c);
  }
  while (auto claim = db.ClaimNext("w", {}, 600, 3)) {
    StageResult r;
    const int h = static_cast<int>((claim->clip_id * 2654435761u + claim->stage.size()) % 100);
    r.verdict = h < 8 ? Verdict::kReject : h < 10 ? Verdict::kFlag : Verdict::kPass;
    r.reason = r.verdict == Verdict::kPass ? "" : claim->stage;
    Json signal = Json::array();
    for (int t = 0; t < 300; ++t) signal.push_back(0.001 * ((t * 37 + h) % 1000));
    r.measurements = {{"signals", {{"a", signal}, {"b", signal}}},
                      {"summary",
                       {{"scores",
                         {{{"name", "s"}, {"value", h / 100.0}, {"rejects", "above"},
                           {"reject", 0.92}, {"flag", 0.9}}}}}}};
    db.Complete(*claim, "w", "p", r, 0.01);
  }
  tx.Commit();
}

template <typename F>
double Best(int repeats, F f) {
  double best = 1e30;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  InitLogging("warn");
  const int clips = argc > 1 ? std::atoi(argv[1]) : 2000;
  const fs::path dir = fs::temp_directory_path() / ("reports_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  {
    Database db(dir / "b.db");
    const auto t0 = Clock::now();
    Build(db, clips);
    std::printf("built %d clips in %.1f s\n", clips,
                std::chrono::duration<double>(Clock::now() - t0).count());
    std::size_t sink = 0;
    const double status = Best(3, [&] { sink += db.Counts().size(); });
    const double naive = Best(3, [&] {
      for (const auto& c : db.ListClips()) {
        for (const auto& s : kPipeline) {
          if (auto m = db.GetMeasurements(c.id, s)) sink += m->size();
        }
      }
    });
    reports::ReportOptions options;
    options.thumbnails = false;
    const double report = Best(3, [&] {
      const auto data = reports::CollectReport(db, options);
      sink += reports::RenderHtml(data).size() + reports::ReportToJson(data).dump().size();
    });
    std::printf("%-8s %10s %10s\n", "what", "seconds", "x status");
    std::printf("%-8s %10.4f %10.1f\n", "status", status, 1.0);
    std::printf("%-8s %10.4f %10.1f\n", "naive", naive, naive / status);
    std::printf("%-8s %10.4f %10.1f\n", "report", report, report / status);
    std::printf("report / naive measurement read: %.2f  (sink %zu)\n", report / naive, sink);
  }
  fs::remove_all(dir);
  return 0;
}
