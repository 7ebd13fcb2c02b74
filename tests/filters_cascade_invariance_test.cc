// The cascade changes cost, never outcome (filters/deferred_hand_models.h).
//
// For every clip, the default configuration (the hand models deferred to
// clips the cheap verdicts keep, thinned and gated) and the full
// measurement (the models on every sample of every clip: no deferral, no
// still samples, the palm detector on every sample) stop the clip at the
// same stage for the same reason, the verdicts taken in the order the
// evidence is taken: the cheap verdicts (shot boundary, camera motion)
// first, then the hand verdicts. And the default configuration, run in the
// queue's stage order (a hand stage before camera motion), stops it there
// too: a hand stage whose evidence was not taken records not_measured and
// moves the clip on, never pass, reject or flag.
//
// The clips: every video under ../shared/data (whole files), the files
// named in bench/cascade_invariance_clips.txt (one path a line, relative to
// the source folder, '#' comments; optional), and synthetic clips of seeds
// 41 and 23 (synth/generator.h, the filters' defect mix), analysed without
// their boxes so that the detectors run.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "filters/analyze.h"
#include "testing/real_footage.h"
#include "filters/hand_landmarker.h"
#include "filters/verdict.h"
#include "stages/verdict_stages.h"
#include "synth/generator.h"
#include "test_util.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

// The queue's order of the verdict stages (stages/stage_registry.cc).
const std::vector<std::string> kQueueOrder = {kShotBoundaryStageName, kInteractionStageName,
                                              kOutOfFrameStageName, kActivityStageName,
                                              kCameraMotionStageName};
// The order the evidence is taken in: the cheap verdicts
// (CheapVerdictConfigs) before the hand models.
const std::vector<std::string> kEvidenceOrder = {kShotBoundaryStageName, kCameraMotionStageName,
                                                 kInteractionStageName, kOutOfFrameStageName,
                                                 kActivityStageName};

struct Stop {
  std::string stage = "(kept)", reason;
  bool operator==(const Stop& o) const { return stage == o.stage && reason == o.reason; }
};
std::ostream& operator<<(std::ostream& os, const Stop& s) {
  return os << s.stage << (s.reason.empty() ? "" : ":" + s.reason);
}

struct Judged {
  Stop stop;
  std::map<std::string, StageResult> verdicts;  // the stages that judged, by name
};

// The verdict stages in `order` on `analysis`, each on the kept shot (the
// shot-boundary stage comes first in both orders); the first reject stops
// the clip, a flag or not_measured moves it on, as the queue does.
Judged Judge(const Json& analysis, const std::vector<std::string>& order) {
  static const std::map<std::string, std::shared_ptr<Stage>> stages = {
      {kShotBoundaryStageName, std::make_shared<ShotBoundaryStage>()},
      {kInteractionStageName, std::make_shared<InteractionStage>()},
      {kOutOfFrameStageName, std::make_shared<OutOfFrameStage>()},
      {kActivityStageName, std::make_shared<ActivityStage>()},
      {kCameraMotionStageName, std::make_shared<CameraMotionStage>()}};
  ClipContext context;
  context.clip.external_id = "invariance";
  context.measurements[kAnalyzeStageName] = analysis;
  Judged out;
  for (const std::string& name : order) {
    StageResult r = stages.at(name)->Run(context);
    if (name == kShotBoundaryStageName) context.measurements[name] = r.measurements;
    const bool rejected = r.verdict == Verdict::kReject;
    if (rejected) out.stop = {name, r.reason};
    out.verdicts[name] = std::move(r);
    if (rejected) break;
  }
  return out;
}

AnalyzeConfig FullMeasurement() {
  AnalyzeConfig c;
  LearnedDetectorConfig& d = c.learned_detector;
  d.after_cheap_verdicts = false;
  d.still_sample_fps = d.sample_fps;
  d.palm_every = 1;
  d.no_hand_palm_every = 1;
  d.no_hand_changed_fraction = 0;
  return c;
}

struct Clip {
  std::string name;
  std::filesystem::path video;
};

std::vector<Clip> RealClips() {
  std::vector<Clip> out;
  const std::set<std::string> kVideo = {".mp4", ".avi", ".mov", ".mkv", ".webm"};
  for (const auto& e : std::filesystem::recursive_directory_iterator(testing::SharedData())) {
    if (e.is_regular_file() && kVideo.count(e.path().extension().string())) {
      out.push_back({e.path().lexically_relative(testing::SharedData()).string(), e.path()});
    }
  }
  const std::filesystem::path source = testing::SourceDir();
  std::ifstream list(source / "bench" / "cascade_invariance_clips.txt");
  for (std::string line; std::getline(list, line);) {
    line = line.substr(0, line.find('#'));
    line.erase(line.find_last_not_of(" \t\r") + 1);
    if (line.empty()) continue;
    const std::filesystem::path named = std::filesystem::path(line).is_absolute() ? std::filesystem::path(line) : source / line;
    if (!std::filesystem::exists(named)) {
      ADD_FAILURE() << "bench/cascade_invariance_clips.txt names a missing file: " << line;
      continue;
    }
    // A package's gzipped video is decoded from its decompressed copy.
    out.push_back({line, testing::ResolveRealFootage(named.string(), testing::SharedData(),
                                                     std::filesystem::temp_directory_path() / "doasido-cascade-videos")});
  }
  std::sort(out.begin(), out.end(), [](const Clip& a, const Clip& b) { return a.name < b.name; });
  return out;
}

// Both configurations on `video` (its frames `span`), judged; failures
// name `name`.
void ExpectSameStop(const std::string& name, const std::filesystem::path& video,
                    std::map<std::string, int>* tally, const DecoderOptions& span = {}) {
  const Json cascade = AnalyzeClip(video, span, {}, AnalyzeConfig{}).measurements;
  const Json full = AnalyzeClip(video, span, {}, FullMeasurement()).measurements;
  const Judged in_queue = Judge(cascade, kQueueOrder);
  const Judged in_evidence_order = Judge(cascade, kEvidenceOrder);
  const Judged measured = Judge(full, kEvidenceOrder);
  EXPECT_EQ(in_queue.stop, measured.stop)
      << name << ": the cascade stops it elsewhere than the full measurement ("
      << cascade.at("clip").value("detector_note", "models ran") << ")";
  EXPECT_EQ(in_queue.stop, in_evidence_order.stop) << name;
  // No verdict without its evidence: a section the cascade did not measure
  // gives not_measured naming the verdict that stopped the clip.
  const bool unmeasured = cascade.contains(kNotMeasuredKey);
  for (const auto& [stage, r] : in_queue.verdicts) {
    if (!cascade.contains(stage)) {
      EXPECT_TRUE(unmeasured) << name << " " << stage;
      EXPECT_EQ(r.verdict, Verdict::kNotMeasured) << name << " " << stage;
      EXPECT_EQ(r.reason, in_queue.stop.stage) << name << " " << stage;
    } else {
      EXPECT_NE(r.verdict, Verdict::kNotMeasured) << name << " " << stage;
    }
  }
  if (unmeasured) {
    EXPECT_EQ(cascade.at(kNotMeasuredKey).at("stage"), in_queue.stop.stage) << name;
  }
  ++(*tally)[in_queue.stop.stage + (unmeasured ? " (hands not measured)" : "")];
  std::printf("  %-40s %-28s seed order: %s\n", name.c_str(),
              ::testing::PrintToString(in_queue.stop).c_str(),
              ::testing::PrintToString(Judge(full, kQueueOrder).stop).c_str());
}

class CascadeInvariance : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!HandLandmarkerAvailable(&why)) GTEST_SKIP() << why;
  }
  std::map<std::string, int> tally_;
  void TearDown() override {
    for (const auto& [stop, n] : tally_) std::printf("  stopped at %-40s %d\n", stop.c_str(), n);
  }
};

TEST_F(CascadeInvariance, EveryRealVideo) {
  const std::vector<Clip> clips = RealClips();
  ASSERT_GE(clips.size(), 16u) << "../shared/data holds 16 videos";
  for (const Clip& c : clips) ExpectSameStop(c.name, c.video, &tally_);
  // The set holds clips each verdict stops (else the test proves little).
  EXPECT_GT(tally_.size(), 2u);
}

// The labelled real footage's spans (bench/real_footage_labels.tsv, both
// halves): a part of a video is a clip of its own, whose shots and hands
// differ from the whole file's.
TEST_F(CascadeInvariance, EveryLabelledSpan) {
  const auto clips = testing::ReadRealFootage(testing::SourceDir() / "bench" / "real_footage_labels.tsv");
  int spans = 0;
  for (const testing::RealFootageClip& c : clips) {
    if (c.first_frame == 0 && c.last_frame < 0) continue;  // whole files: EveryRealVideo
    DecoderOptions span;
    span.first_frame = c.first_frame;
    span.last_frame = c.last_frame;
    ExpectSameStop(c.id, testing::ResolveRealFootage(c.source, testing::SharedData(),
                                                     std::filesystem::temp_directory_path() / "doasido-cascade-videos"),
                   &tally_, span);
    ++spans;
  }
  EXPECT_GE(spans, 20);
}

// Synthetic clips of `seed` in the filters' defect mix
// (bench/filters_synth_eval_bench.cc), without their boxes.
void SynthClips(std::uint64_t seed, int clips, std::map<std::string, int>* tally) {
  testing::TempDir dir;
  synth::SynthConfig cfg;
  cfg.clips = clips;
  cfg.seed = seed;
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 60;
  cfg.write_bundles = false;
  cfg.mix =
      "clean=0.2,cut=0.08,fade=0.08,black=0.08,pan=0.08,shake=0.08,zoom=0.08,"
      "out_of_frame=0.08,object_out=0.08,no_contact=0.08,static=0.08";
  const auto kinds = synth::AssignDefects(synth::ParseMix(cfg.mix), cfg.clips, cfg.seed);
  for (int i = 0; i < cfg.clips; ++i) {
    const synth::RenderedClip clip = synth::RenderClip(cfg, i, kinds[i]);
    const auto video = dir / ("c" + std::to_string(i) + ".mp4");
    synth::WriteVideo(clip.bgr, cfg.fps, video);
    ExpectSameStop("seed " + std::to_string(seed) + " clip " + std::to_string(i) + " (" +
                       synth::DefectName(kinds[i]) + ")",
                   video, tally);
  }
}

TEST_F(CascadeInvariance, SyntheticSeed41) { SynthClips(41, 11, &tally_); }
TEST_F(CascadeInvariance, SyntheticSeed23) { SynthClips(23, 11, &tally_); }

}  // namespace
}  // namespace doasido::filters
