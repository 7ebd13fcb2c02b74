// Writing a synthetic dataset to disk (synth/generator.h): each clip's
// video, bundles, VOC boxes and ground truth, the clip list and the
// summary. Rendering the clips is synth/generator.cc's.
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "core/csv.h"
#include "core/error.h"
#include "synth/generator.h"
#include "synth/texture.h"

namespace doasido::synth {
namespace fs = std::filesystem;

recon::ClipBundle ModelLikeBundle(const SynthConfig& cfg, int index,
                                  const recon::ClipBundle& truth) {
  std::mt19937_64 rng(Hash(cfg.seed, index, 0x0de1));
  recon::ClipBundle b = truth;
  for (cv::Mat& d : b.depth) d = d.clone();
  ApplyDepthNoise(b.depth, cfg.depth_noise, rng);
  if (b.hand_left) ApplyHandNoise(*b.hand_left, cfg.hand_noise, rng);
  if (b.hand_right) ApplyHandNoise(*b.hand_right, cfg.hand_noise, rng);
  b.producers = Json{{"all", "doasido synth (exact ground truth)"},
                     {"depth", "doasido synth MoGe-like depth noise"},
                     {"hands", "doasido synth HaWoR-like joint noise"},
                     {"candidates", "doasido synth SAM 3D-like pose sampler"}};
  return b;
}

void WriteVideo(const std::vector<cv::Mat>& frames, double fps, const fs::path& path) {
  if (frames.empty()) throw Error("io", "no frames to write", {.file = path.string()});
  const cv::Size size(frames[0].cols, frames[0].rows);
  for (const char* cc : {"avc1", "mp4v"}) {
    cv::VideoWriter w(path.string(), cv::CAP_FFMPEG,
                      cv::VideoWriter::fourcc(cc[0], cc[1], cc[2], cc[3]), fps, size);
    if (!w.isOpened()) continue;
    for (const cv::Mat& f : frames) w.write(f);
    w.release();
    return;
  }
  throw Error("io", "OpenCV/FFmpeg cannot open an mp4 writer (avc1, mp4v)",
              {.file = path.string()});
}

namespace {

// The clip's row of clips.csv: its video, span, defects (each kind once) and
// scene, read back by `doasido ingest` through core/csv.h.
std::string ClipListRow(const SynthConfig& cfg, const RenderedClip& clip) {
  std::string defects;
  for (const auto& d : clip.defects) {
    if (defects.find(d.kind) != std::string::npos) continue;
    defects += (defects.empty() ? "" : ";") + d.kind;
  }
  const Json& scene = clip.gt["scenes"][0];
  std::ostringstream fps;
  fps << cfg.fps;
  return CsvLine({"videos/" + clip.id + ".mp4", clip.id, "0", std::to_string(cfg.frames - 1),
                  "synth", defects, scene["verb"].get<std::string>(),
                  scene["object"].get<std::string>(), scene["two_hands"].get<bool>() ? "2" : "1",
                  std::to_string(cfg.width), std::to_string(cfg.height), fps.str()});
}

}  // namespace

Json DatasetSummary::ToJson() const {
  return Json{{"clips", clips}, {"defect_counts", defect_counts}};
}

DatasetSummary GenerateDataset(const SynthConfig& cfg, const fs::path& out,
                               const std::function<void(int)>& progress) {
  if (cfg.clips < 0) throw Error("bad_config", "clips must be >= 0", {.field = "clips"});
  const auto mix = ParseMix(cfg.mix);
  const std::vector<DefectKind> kinds = AssignDefects(mix, cfg.clips, cfg.seed);
  std::error_code ec;
  for (const char* sub : {"videos", "bundles", "Annotations", "gt"}) {
    fs::create_directories(out / sub, ec);
    if (ec)
      throw Error("io", "cannot create folder: " + ec.message(), {.file = (out / sub).string()});
  }
  DatasetSummary summary;
  summary.clips = cfg.clips;
  for (const auto& [k, w] : mix) summary.defect_counts[DefectName(k)] = 0;
  std::string csv = CsvLine({"video", "id", "start_frame", "end_frame", "source", "defects", "verb",
                             "object", "hands", "width", "height", "fps"});
  for (int i = 0; i < cfg.clips; ++i) {
    RenderedClip clip = RenderClip(cfg, i, kinds[i]);
    WriteVideo(clip.bgr, cfg.fps, out / "videos" / (clip.id + ".mp4"));
    if (cfg.png_every > 0) {
      fs::create_directories(out / "png", ec);
      for (int t = 0; t < cfg.frames; t += cfg.png_every) {
        char name[64];
        std::snprintf(name, sizeof name, "_%06d.png", t);
        const fs::path p = out / "png" / (clip.id + name);
        if (!cv::imwrite(p.string(), clip.bgr[t])) {
          throw Error("io", "cannot write preview", {.file = p.string()});
        }
      }
    }
    if (cfg.write_bundles) recon::WriteBundle(clip.bundle, out / "bundles" / clip.id);
    if (cfg.model_bundles) {
      recon::WriteBundle(ModelLikeBundle(cfg, i, clip.bundle), out / "model_bundles" / clip.id);
    }
    if (cfg.write_annotations) {
      for (const VocFrame& v : clip.voc) WriteVoc(v, out / "Annotations");
    }
    {
      const fs::path p = out / "gt" / (clip.id + ".json");
      std::ofstream f(p, std::ios::binary);
      f << clip.gt.dump(1) << "\n";
      if (!f) throw Error("io", "cannot write ground truth", {.file = p.string()});
    }
    summary.defect_counts[DefectName(kinds[i])]++;
    csv += ClipListRow(cfg, clip);
    if (progress) progress(i + 1);
  }
  auto write_text = [](const fs::path& p, const std::string& text) {
    std::ofstream f(p, std::ios::binary);
    f << text;
    if (!f) throw Error("io", "cannot write file", {.file = p.string()});
  };
  write_text(out / "clips.csv", csv);
  Json mix_json = Json::object();
  for (const auto& [k, w] : mix) mix_json[DefectName(k)] = w;
  Json s = summary.ToJson();
  s["seed"] = cfg.seed;
  s["mix"] = mix_json;
  s["frames_per_clip"] = cfg.frames;
  s["width"] = cfg.width;
  s["height"] = cfg.height;
  s["fps"] = cfg.fps;
  write_text(out / "summary.json", s.dump(1) + "\n");
  return summary;
}

}  // namespace doasido::synth
