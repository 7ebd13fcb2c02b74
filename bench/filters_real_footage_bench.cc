// Per-filter agreement with hand-made labels on real footage made by others:
// bench/real_footage_labels.tsv (spans of the videos in ../shared/data and
// of videos Debian packages ship; testing/real_footage.h reads it and splits
// it into a tuning half and a held-back half, docs/benchmarks.md "Real
// footage"). Every filter judges every clip from one analysis pass (stages
// decide from stored signals), so a clip a first filter rejects is still
// judged by the rest. A cell is scored when its label is not "-": pass
// means not rejected (a flag agrees), reject means rejected, and for
// shot_boundary pass means no boundary found and trimmed a pass trimmed to
// the longest shot. The two halves are reported apart; tune on the first
// only.
// Usage: filters_real_footage_bench [labels.tsv] [learned|builtin] [config.toml]
// (config: a [filters_analyze] table, to measure other settings)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/log.h"
#include "filters/activity.h"
#include "filters/analyze.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "testing/real_footage.h"

using namespace doasido;
using namespace doasido::filters;
using namespace doasido::stages;
namespace footage = doasido::testing;

namespace {

// Does the stage's result agree with the label?
bool Agrees(const std::string& stage, const std::string& label, const StageResult& r) {
  const bool rejected = r.verdict == Verdict::kReject;
  if (label == footage::kLabelReject) return rejected;
  if (stage != kShotBoundaryStageName) return !rejected;
  const bool trimmed = !rejected && r.reason == kReasonTrimmed;
  return label == footage::kLabelTrimmed ? trimmed : !rejected && !trimmed;
}

struct Tally {
  std::map<std::string, int> agree, scored;
  int clips = 0, clips_all_agree = 0;
};

// One line on the learned detector's samples: how many had a hand, and the
// object evidence at the fingertips (median over hands).
std::string Found(const std::string& id, const Json& analysis) {
  char line[256];
  if (!analysis.contains(kHandsMeasurement)) {
    std::snprintf(line, sizeof line, "%-20s %s", id.c_str(),
                  analysis.at("clip").value("detection_source", "?").c_str());
    return line;
  }
  const Json& hands = analysis.at(kHandsMeasurement);
  int samples = 0, with_hand = 0, in_contact = 0, total = 0;
  std::vector<double> edges;
  for (const Json& sample : hands.at("samples")) {
    ++samples;
    with_hand += !sample.at("hands").empty();
    for (const Json& h : sample.at("hands")) {
      ++total;
      edges.push_back(h.at("object_edges").get<double>());
      in_contact += h.at("object_edges").get<double>() >= AnalyzeConfig{}.learned_detector.min_object_edges;
    }
  }
  std::sort(edges.begin(), edges.end());
  std::snprintf(line, sizeof line,
                "%-20s %2d samples, %4.2f with a hand, %2d hands, %2d touching (median edges %.3f), %.0f ms/sample",
                id.c_str(), samples, samples ? static_cast<double>(with_hand) / samples : 0.0, total,
                in_contact, edges.empty() ? 0.0 : edges[edges.size() / 2],
                hands.at("ms_per_sample").get<double>());
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  InitLogging("warn");
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // a row per clip as it is judged
  const std::filesystem::path table =
      argc > 1 ? std::filesystem::path(argv[1])
               : std::filesystem::path(DOASIDO_SOURCE_DIR) / "bench" / "real_footage_labels.tsv";
  const std::filesystem::path cache =
      std::filesystem::temp_directory_path() / "doasido-real-footage";
  AnalyzeConfig config;
  // Every filter judges every clip, so the models run on every clip (the
  // pipeline's default runs them only on clips the cheap verdicts keep; a
  // config with after_cheap_verdicts = true measures that).
  config.learned_detector.after_cheap_verdicts = false;
  if (argc > 3) ReadSection(LoadConfigFile(argv[3]), "filters_analyze", config);
  if (argc > 2) config.hand_detector = argv[2];
  const std::vector<footage::RealFootageClip> clips = footage::ReadRealFootage(table);
  std::vector<std::string> found, missing;
  std::vector<std::unique_ptr<stages::Stage>> stages;
  stages.push_back(std::make_unique<ShotBoundaryStage>());
  stages.push_back(std::make_unique<InteractionStage>());
  stages.push_back(std::make_unique<OutOfFrameStage>());
  stages.push_back(std::make_unique<ActivityStage>());
  stages.push_back(std::make_unique<CameraMotionStage>());
  std::map<footage::Half, Tally> tally;
  std::printf("%-20s %-5s", "clip", "half");
  for (const auto& s : stages) std::printf(" %-22.22s", s->Name().c_str());
  std::printf("\n");
  double analysis_s = 0;
  for (const footage::RealFootageClip& clip : clips) {
    std::filesystem::path video;
    try {
      video = footage::ResolveRealFootage(clip.source, DOASIDO_SHARED_DATA, cache);
    } catch (const Error& e) {
      missing.push_back(clip.id + ": " + e.what());
      continue;
    }
    const auto t = std::chrono::steady_clock::now();
    DecoderOptions span;
    span.first_frame = clip.first_frame;
    span.last_frame = clip.last_frame;
    span.clip = clip.id;
    ClipContext context;
    context.clip.external_id = clip.id;
    context.video.path = video.string();
    try {
      context.measurements[kAnalyzeStageName] = AnalyzeClip(video, span, {}, config).measurements;
    } catch (const Error& e) {
      missing.push_back(clip.id + ": " + e.what());
      continue;
    }
    analysis_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    found.push_back(Found(clip.id, context.measurements[kAnalyzeStageName]));
    Tally& half = tally[clip.half];
    half.clips++;
    bool all_agree = true;
    std::printf("%-20.20s %-5s", clip.id.c_str(), clip.half == footage::Half::kTuning ? "tune" : "held");
    for (const auto& stage : stages) {
      const StageResult r = stage->Run(context);
      // As in the queue, the later verdicts judge the shot it keeps.
      if (stage->Name() == kShotBoundaryStageName) context.measurements[stage->Name()] = r.measurements;
      std::string cell = r.verdict == Verdict::kPass ? "pass" : ToString(r.verdict);
      if (!r.reason.empty()) cell = r.reason;
      const auto label = clip.labels.find(stage->Name());
      if (label != clip.labels.end()) {
        const bool ok = Agrees(stage->Name(), label->second, r);
        half.scored[stage->Name()]++;
        half.agree[stage->Name()] += ok;
        all_agree = all_agree && ok;
        cell += ok ? " ok" : " WRONG";
      }
      std::printf(" %-22.22s", cell.c_str());
      if (std::getenv("DOASIDO_BENCH_VERBOSE") && r.measurements.contains("summary")) {
        std::fprintf(stderr, "%s %s %s\n", clip.id.c_str(), stage->Name().c_str(),
                     r.measurements.at("summary").dump().c_str());
      }
    }
    std::printf("\n");
    half.clips_all_agree += all_agree;
  }
  std::printf("\nagreement with the labels (cells labelled pass must not be rejected, reject "
              "must be; shot_boundary: pass = no boundary, trimmed = trimmed):\n");
  std::printf("  %-15s %-12s %-12s\n", "filter", "tuning", "held back");
  std::map<footage::Half, std::pair<int, int>> totals;
  for (const auto& s : stages) {
    std::printf("  %-15s", s->Name().c_str());
    for (const footage::Half h : {footage::Half::kTuning, footage::Half::kHeldBack}) {
      const int ok = tally[h].agree[s->Name()], n = tally[h].scored[s->Name()];
      std::printf(" %-12s", (std::to_string(ok) + "/" + std::to_string(n)).c_str());
      totals[h].first += ok;
      totals[h].second += n;
    }
    std::printf("\n");
  }
  std::printf("  %-15s", "all filters");
  for (const footage::Half h : {footage::Half::kTuning, footage::Half::kHeldBack}) {
    std::printf(" %-12s", (std::to_string(totals[h].first) + "/" + std::to_string(totals[h].second)).c_str());
  }
  std::printf("\n  %-15s", "clips all ok");
  for (const footage::Half h : {footage::Half::kTuning, footage::Half::kHeldBack}) {
    std::printf(" %-12s", (std::to_string(tally[h].clips_all_agree) + "/" + std::to_string(tally[h].clips)).c_str());
  }
  std::printf("\n\nwhat the hand detector found (%s):\n", config.hand_detector.c_str());
  for (const std::string& line : found) std::printf("  %s\n", line.c_str());
  for (const std::string& line : missing) std::printf("  NOT JUDGED %s\n", line.c_str());
  std::printf("analysis %.1f s for %zu clips (%zu not judged)\n", analysis_s,
              clips.size() - missing.size(), missing.size());
  return missing.empty() ? 0 : 1;
}
