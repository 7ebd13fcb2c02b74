// Precision and recall of the four filters on synthetic clips with a known
// defect mix (synth/generator.h). Every clip is rendered, written as an mp4
// (so the filters meet real compression), analysed in one pass with the
// synthetic 100DOH-style boxes as its detections, and judged by the five
// verdict stages with their default thresholds. A filter's positives are the
// clips whose defect it exists to catch:
//   shot_boundary  cut, fade (cross-fade), black (fade from/to black)
//                  -> predicted when it finds a boundary (trim or reject)
//   camera_motion  pan, shake, zoom            -> predicted when rejected
//   out_of_frame   out_of_frame, object_out    -> predicted when rejected
//   activity       static                      -> predicted when rejected
//   interaction    no_contact                  -> predicted when rejected
// Flags (sent to review, neither kept nor dropped) are counted apart.
// Every other clip (including the clean ones) is a negative for that filter,
// except that static clips do not count for interaction: the synthetic
// world's static scene has the hand resting beside the object, never
// touching it, so rejecting it for no interaction is right. The stages run
// in the queue's order: the later filters judge the shot the shot filter
// kept.
//
// Usage: filters_synth_eval_bench [clips=200] [seed=11] [width=320] [cache_dir] [config]
// `config` is a TOML/JSON file with the worker's sections (filters_analyze,
// shot_boundary, camera_motion, ...) to evaluate other parameters.
// Rendering dominates the run time (the analysis itself runs at hundreds of
// frames per second); with a cache_dir the rendered videos and their boxes
// are kept there and reused by later runs with the same seed and size.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/config_check.h"
#include "filters/analyze.h"
#include "filters/kept_shot.h"
#include "stages/verdict_stages.h"
#include "synth/generator.h"

namespace doasido::filters {
namespace {

using namespace doasido::stages;  // the filters' queue stages

std::vector<Detection> SynthDetections(const std::vector<synth::VocFrame>& voc) {
  std::vector<Detection> out;
  for (const synth::VocFrame& f : voc) {
    for (const synth::VocHand& h : f.hands) {
      if (h.box.empty()) continue;
      Detection d;
      d.frame = f.frame;
      d.kind = "hand";
      d.x1 = h.box.x0;
      d.y1 = h.box.y0;
      d.x2 = h.box.x1 + 1;  // inclusive -> exclusive
      d.y2 = h.box.y1 + 1;
      d.contact_state = h.contact_state;
      d.hand_side = h.side;
      d.source = "synth";
      out.push_back(d);
    }
    for (const synth::VocObject& o : f.objects) {
      if (o.box.empty()) continue;
      Detection d;
      d.frame = f.frame;
      d.kind = "object";
      d.x1 = o.box.x0;
      d.y1 = o.box.y0;
      d.x2 = o.box.x1 + 1;
      d.y2 = o.box.y1 + 1;
      d.source = "synth";
      out.push_back(d);
    }
  }
  return out;
}

Json DetectionsToJson(const std::vector<Detection>& detections) {
  Json out = Json::array();
  for (const Detection& d : detections) {
    out.push_back({d.frame, d.kind, d.x1, d.y1, d.x2, d.y2, d.contact_state, d.hand_side});
  }
  return out;
}

std::vector<Detection> DetectionsFromJson(const Json& j) {
  std::vector<Detection> out;
  for (const Json& r : j) {
    Detection d;
    d.frame = r[0];
    d.kind = r[1];
    d.x1 = r[2];
    d.y1 = r[3];
    d.x2 = r[4];
    d.y2 = r[5];
    d.contact_state = r[6];
    d.hand_side = r[7];
    d.source = "synth";
    out.push_back(d);
  }
  return out;
}

struct Filter {
  std::string name;
  std::set<std::string> positives;
};

}  // namespace
}  // namespace doasido::filters

int main(int argc, char** argv) {
  using namespace doasido;
  using namespace doasido::filters;
  synth::SynthConfig cfg;
  cfg.clips = argc > 1 ? std::atoi(argv[1]) : 200;
  cfg.seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 11;
  cfg.width = argc > 3 ? std::atoi(argv[3]) : 320;
  cfg.height = cfg.width * 3 / 4;
  cfg.mix =
      "clean=0.2,cut=0.08,fade=0.08,black=0.08,pan=0.08,shake=0.08,zoom=0.08,"
      "out_of_frame=0.08,object_out=0.08,no_contact=0.08,static=0.08";
  cfg.write_bundles = false;
  const bool keep = argc > 4;
  const std::filesystem::path dir =
      keep ? std::filesystem::path(argv[4])
           : std::filesystem::temp_directory_path() / "doasido_filters_synth_eval";
  std::filesystem::create_directories(dir);

  const std::vector<Filter> filters = {{kShotBoundaryStageName, {"cut", "fade", "black"}},
                                       {kCameraMotionStageName, {"pan", "shake", "zoom"}},
                                       {kOutOfFrameStageName, {"out_of_frame", "object_out"}},
                                       {kActivityStageName, {"static"}},
                                       {kInteractionStageName, {"no_contact"}}};
  const Json config = argc > 5 ? LoadConfigFile(argv[5]) : Json::object();
  auto section = [&config]<typename T>(const char* name, T value) {
    ReadCheckedSection(config, name, value);
    return value;
  };
  const AnalyzeConfig analyze = section(kAnalyzeStageName, AnalyzeConfig{});
  ShotBoundaryStage shots(section(kShotBoundaryStageName, ShotBoundaryConfig{}));
  CameraMotionStage camera(section(kCameraMotionStageName, CameraMotionConfig{}));
  OutOfFrameStage out(section(kOutOfFrameStageName, OutOfFrameConfig{}));
  ActivityStage activity(section(kActivityStageName, ActivityConfig{}));
  InteractionStage interaction(section(kInteractionStageName, InteractionConfig{}));
  const std::map<std::string, const stages::Stage*> stages = {{kShotBoundaryStageName, &shots},
                                                      {kCameraMotionStageName, &camera},
                                                      {kOutOfFrameStageName, &out},
                                                      {kActivityStageName, &activity},
                                                      {kInteractionStageName, &interaction}};

  const auto kinds = synth::AssignDefects(synth::ParseMix(cfg.mix), cfg.clips, cfg.seed);
  // predicted[filter][kind] = clips of that kind the filter caught; total[kind].
  std::map<std::string, std::map<std::string, int>> predicted;
  std::map<std::string, int> total;
  std::map<std::string, std::map<std::string, int>> flagged;
  std::vector<std::string> misses;
  double render_s = 0, analyse_s = 0;
  std::int64_t frames = 0;
  for (int i = 0; i < cfg.clips; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    char stem[96];
    std::snprintf(stem, sizeof stem, "s%llu_%dx%d_c%04d", static_cast<unsigned long long>(cfg.seed),
                  cfg.width, cfg.height, i);
    const auto video = dir / (std::string(stem) + ".mp4");
    const auto boxes_file = dir / (std::string(stem) + ".json");
    std::vector<Detection> detections;
    std::string clip_id = stem;
    if (keep && std::filesystem::exists(video) && std::filesystem::exists(boxes_file)) {
      std::ifstream in(boxes_file);
      detections = DetectionsFromJson(Json::parse(in));
    } else {
      const synth::RenderedClip clip = synth::RenderClip(cfg, i, kinds[i]);
      synth::WriteVideo(clip.bgr, cfg.fps, video);
      detections = SynthDetections(clip.voc);
      std::ofstream(boxes_file) << DetectionsToJson(detections).dump();
    }
    const auto t1 = std::chrono::steady_clock::now();
    const ClipAnalysis analysis = AnalyzeClip(video, {}, detections, analyze);
    const auto t2 = std::chrono::steady_clock::now();
    render_s += std::chrono::duration<double>(t1 - t0).count();
    analyse_s += std::chrono::duration<double>(t2 - t1).count();
    frames += analysis.measurements.at("clip").at("frames").get<std::int64_t>();
    if (!keep) {
      std::filesystem::remove(video);
      std::filesystem::remove(boxes_file);
    }

    const std::string kind = synth::DefectName(kinds[i]);
    ++total[kind];
    const Json& m = analysis.measurements;
    // The queue's order: the shot filter first; the others judge its kept shot.
    Json shot;
    for (const Filter& f : filters) {
      Json input = {{"clip", m.at("clip")}, {"signals", m.at(f.name)}};
      if (!shot.is_null()) input["shot"] = shot;
      const StageResult r = *stages.at(f.name)->Redecide(input);
      if (f.name == kShotBoundaryStageName) {
        shot = ToJson(KeptShotFromSummary(r.measurements.at("summary")));
      }
      if (f.name == kInteractionStageName && kind == "static") continue;  // no contact by construction
      bool caught = r.verdict == Verdict::kReject;
      if (f.name == kShotBoundaryStageName)
        caught = !r.measurements.at("summary").at("boundaries").empty();
      if (caught) ++predicted[f.name][kind];
      if (r.verdict == Verdict::kFlag) ++flagged[f.name][kind];
      const bool positive = f.positives.count(kind) > 0;
      if (std::getenv("DOASIDO_EVAL_VERBOSE") != nullptr) {
        Json summary = r.measurements.at("summary");
        if (f.name == kShotBoundaryStageName) {
          const auto lc =
              m.at(kShotBoundaryStageName).at("changed_fraction_long").get<std::vector<double>>();
          summary["max_changed_long"] = *std::max_element(lc.begin(), lc.end());
        }
        std::printf("ALL %s %s %s %d %s %s\n", clip_id.c_str(), kind.c_str(), f.name.c_str(),
                    caught ? 1 : 0, r.reason.c_str(), summary.dump().c_str());
      }
      if (caught != positive && !(f.name == kInteractionStageName && kind == "static")) {
        misses.push_back(clip_id + " (" + kind + "): " + f.name + " " +
                         (caught ? "false alarm " : "missed ") + r.reason + " " +
                         r.measurements.at("summary").dump());
      }
    }
    std::fprintf(stderr, "\r%d/%d clips", i + 1, cfg.clips);
  }
  std::fprintf(stderr, "\n");

  std::printf("\n%d synthetic clips (seed %llu, %dx%d, %d frames at %.0f fps), mix %s\n", cfg.clips,
              static_cast<unsigned long long>(cfg.seed), cfg.width, cfg.height, cfg.frames, cfg.fps,
              cfg.mix.c_str());
  std::printf("%-14s %-32s %4s %4s %4s %9s %7s %14s\n", "filter", "positives", "TP", "FP", "FN",
              "precision", "recall", "flagged +/-");
  for (const Filter& f : filters) {
    int tp = 0, fp = 0, fn = 0, flag_pos = 0, flag_neg = 0;
    std::string names;
    for (const auto& [kind, n] : total) {
      if (f.name == kInteractionStageName && kind == "static") continue;
      const int caught = predicted[f.name][kind];
      if (f.positives.count(kind)) {
        tp += caught;
        fn += n - caught;
        flag_pos += flagged[f.name][kind];
      } else {
        fp += caught;
        flag_neg += flagged[f.name][kind];
      }
    }
    for (const std::string& k : f.positives) names += (names.empty() ? "" : ",") + k;
    const double precision = tp + fp > 0 ? static_cast<double>(tp) / (tp + fp) : 1.0;
    const double recall = tp + fn > 0 ? static_cast<double>(tp) / (tp + fn) : 1.0;
    std::printf("%-14s %-32s %4d %4d %4d %9.3f %7.3f %8d/%d\n", f.name.c_str(), names.c_str(), tp,
                fp, fn, precision, recall, flag_pos, flag_neg);
  }
  std::printf("\nFraction of clips of each kind that each filter caught\n%-13s %5s", "kind", "n");
  for (const Filter& f : filters) std::printf(" %14s", f.name.c_str());
  std::printf("\n");
  for (const auto& [kind, n] : total) {
    std::printf("%-13s %5d", kind.c_str(), n);
    for (const Filter& f : filters) {
      std::printf(" %14.2f", static_cast<double>(predicted[f.name][kind]) / n);
    }
    std::printf("\n");
  }
  std::printf("\nrender+encode %.1f s, analysis %.1f s (%.0f frames/s wall)\n", render_s, analyse_s,
              frames / analyse_s);
  if (!misses.empty()) {
    std::printf("\nErrors (%zu):\n", misses.size());
    for (const std::string& m : misses) std::printf("  %s\n", m.c_str());
  }
  benchmark::DoNotOptimize(frames);
  return 0;
}
