// Per-filter agreement with labels on real footage made by others
// (../shared/data/videos; labels from its README). Every filter judges every
// clip from one analysis pass (stages decide from stored signals), so a clip
// a first filter rejects is still judged by the rest.
//   positive: a hand handles an object, static camera, one shot: every
//             filter should pass it.
//   negative: the filter named in the label should reject it; the others
//             are not scored on it.
// Usage: filters_real_footage_bench [videos folder]
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "core/log.h"
#include "filters/activity.h"
#include "filters/analyze_stage.h"
#include "filters/camera_motion.h"
#include "filters/interaction.h"
#include "filters/out_of_frame.h"
#include "filters/shot_boundary.h"
#include "filters/stage_support.h"

using namespace doasido;
using namespace doasido::filters;

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

}  // namespace

int main(int argc, char** argv) {
  InitLogging("warn");
  const std::filesystem::path dir =
      argc > 1 ? std::filesystem::path(argv[1]) : std::filesystem::path(DOASIDO_SHARED_DATA) / "videos";
  std::vector<std::unique_ptr<Stage>> stages;
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
        AnalyzeClip(dir / label.file, DecoderOptions{}, {}, AnalyzeConfig{}).measurements;
    analysis_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
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
  std::printf("all filters: %d/%d decisions agree; %d of %d positives pass every filter; "
              "analysis %.1f s for %zu videos\n",
              total_ok, total, positives_kept, positives, analysis_s, std::size(kLabels));
  return 0;
}
