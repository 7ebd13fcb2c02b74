// Per-filter agreement with labels on real footage made by others
// (../shared/data/videos; labels from its README). Every filter judges every
// clip from one analysis pass (stages decide from stored signals), so a clip
// a first filter rejects is still judged by the rest.
//   positive: a hand handles an object, static camera, one shot: every
//             filter should pass it.
//   negative: the filter named in the label should reject it; the others
//             are not scored on it.
// Usage: filters_real_footage_bench [videos folder] [learned|builtin] [config.toml]
// (config: a [filters_analyze] table, to measure other settings)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "core/log.h"
#include "filters/activity.h"
#include "filters/analyze.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"

using namespace doasido;
using namespace doasido::filters;
using namespace doasido::stages;

namespace {

struct Label {
  const char* file;
  const char* rejected_by;  // empty: a positive
  const char* why;
};

// ../shared/data/README.md
const Label kLabels[] = {
    {"02_cups.mp4", "", "two hands move cups"},
    {"03_blocks.mp4", "", "hands stack blocks"},
    {"bass_guitar.mp4", "", "hand frets a bass neck"},
    {"eyeliner.avi", "", "hand draws with a pencil"},
    {"laptop_trackpad.mp4", "", "hand works a trackpad"},
    {"apple.mp4", kInteractionStageName, "no hands"},
    {"bedroom.mp4", kInteractionStageName, "hands, no object handled"},
    {"yoga.mp4", kInteractionStageName, "hands, no object handled"},
    {"asl_hand.mp4", kInteractionStageName, "hands, no object handled"},
    {"arm_wrestling.mp4", kCameraMotionStageName, "handheld, strong motion"},
    {"making_cake.mp4", kCameraMotionStageName, "whip pans"},
    {"pool_cleaning.mp4", kCameraMotionStageName, "pans and tilts"},
};

// One line on the learned detector's samples: how many had a hand, and the
// object evidence at the fingertips (median over hands).
std::string Found(const char* file, const Json& analysis) {
  char line[256];
  if (!analysis.contains(kHandsMeasurement)) {
    std::snprintf(line, sizeof line, "%-20s %s", file,
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
                file, samples, samples ? static_cast<double>(with_hand) / samples : 0.0, total,
                in_contact, edges.empty() ? 0.0 : edges[edges.size() / 2],
                hands.at("ms_per_sample").get<double>());
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  InitLogging("warn");
  const std::filesystem::path dir =
      argc > 1 ? std::filesystem::path(argv[1]) : std::filesystem::path(DOASIDO_SHARED_DATA) / "videos";
  AnalyzeConfig config;
  // Every filter judges every clip, so the models run on every clip (the
  // pipeline's default runs them only on clips the cheap verdicts keep; a
  // config with after_cheap_verdicts = true measures that).
  config.learned_detector.after_cheap_verdicts = false;
  if (argc > 3) ReadSection(LoadConfigFile(argv[3]), "filters_analyze", config);
  if (argc > 2) config.hand_detector = argv[2];
  std::vector<std::string> found;
  std::vector<std::unique_ptr<stages::Stage>> stages;
  stages.push_back(std::make_unique<ShotBoundaryStage>());
  stages.push_back(std::make_unique<InteractionStage>());
  stages.push_back(std::make_unique<OutOfFrameStage>());
  stages.push_back(std::make_unique<ActivityStage>());
  stages.push_back(std::make_unique<CameraMotionStage>());
  std::map<std::string, int> agree, scored;
  int positives = 0, positives_kept = 0;
  std::printf("%-20s %-16s", "video", "label");
  for (const auto& s : stages) std::printf(" %-19.19s", s->Name().c_str());
  std::printf("\n");
  double analysis_s = 0;
  for (const Label& label : kLabels) {
    const auto t = std::chrono::steady_clock::now();
    ClipContext context;
    context.clip.external_id = label.file;
    context.video.path = (dir / label.file).string();
    context.measurements[kAnalyzeStageName] =
        AnalyzeClip(dir / label.file, DecoderOptions{}, {}, config).measurements;
    analysis_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    found.push_back(Found(label.file, context.measurements[kAnalyzeStageName]));
    const bool positive = label.rejected_by[0] == '\0';
    std::printf("%-20s %-16s", label.file, positive ? "positive" : label.rejected_by);
    bool kept = true;
    for (const auto& stage : stages) {
      const StageResult r = stage->Run(context);
      const bool rejected = r.verdict == Verdict::kReject;
      kept = kept && !rejected;
      std::string cell = r.verdict == Verdict::kPass ? "pass" : ToString(r.verdict);
      if (!r.reason.empty() && r.verdict != Verdict::kPass) cell = r.reason;
      if (positive || stage->Name() == label.rejected_by) {
        const bool ok = positive ? !rejected : rejected;
        scored[stage->Name()]++;
        agree[stage->Name()] += ok;
        cell += ok ? " ok" : " WRONG";
      }
      std::printf(" %-19.19s", cell.c_str());
      if (std::getenv("DOASIDO_BENCH_VERBOSE") && r.measurements.contains("summary")) {
        std::fprintf(stderr, "%s %s %s\n", label.file, stage->Name().c_str(),
                     r.measurements.at("summary").dump().c_str());
      }
    }
    std::printf("\n");
    positives += positive;
    positives_kept += positive && kept;
  }
  std::printf("\nagreement with the labels (positives must pass, a negative must be rejected by "
              "its filter):\n");
  int total = 0, total_ok = 0;
  for (const auto& s : stages) {
    std::printf("  %-15s %d/%d\n", s->Name().c_str(), agree[s->Name()], scored[s->Name()]);
    total += scored[s->Name()];
    total_ok += agree[s->Name()];
  }
  std::printf("\nwhat the hand detector found (%s):\n", config.hand_detector.c_str());
  for (const std::string& line : found) std::printf("  %s\n", line.c_str());
  std::printf("all filters: %d/%d decisions agree; %d of %d positives pass every filter; "
              "analysis %.1f s for %zu videos\n",
              total_ok, total, positives_kept, positives, analysis_s, std::size(kLabels));
  return 0;
}
