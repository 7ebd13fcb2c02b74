// doasido hands: the hands stage alone on files, no database. Each video or
// still image gets <out>/<stem>.json (hands/hand_keypoints_json.h) and, with
// --overlay, <stem>.overlay.mp4 or <stem>.overlay.png with the keypoints
// drawn. A bad input is reported by name and the others still run.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "cli/commands.h"
#include "core/error.h"
#include "core/progress.h"
#include "hands/hand_keypoints_json.h"
#include "hands/hand_overlay.h"
#include "hands/hand_reconstruction.h"
#include "video/mp4_writer.h"

namespace doasido::cli {
namespace {

namespace fs = std::filesystem;
using namespace doasido::hands;

struct HandsOptions {
  std::vector<std::string> inputs;
  std::string out;
  double fx = 0;   // 0: not given
  double fov = 0;  // 0: not given
  bool overlay = false;
  HandsConfig config;
};

// Overlays of videos are drawn at most this large on their longer side.
constexpr int kOverlaySide = 1280;

Intrinsics CommandIntrinsics(const HandsOptions& o, int width, int height) {
  if (o.fx > 0) {
    Intrinsics in{.assumed = false, .source = kIntrinsicsFromOption};
    in.K << o.fx, 0, 0.5 * (width - 1), 0, o.fx, 0.5 * (height - 1), 0, 0, 1;
    return in;
  }
  if (o.fov > 0) return {.K = KFromFov(width, height, o.fov), .assumed = false, .source = kIntrinsicsFromOption};
  return {.K = KFromFov(width, height, o.config.default_fov_deg), .assumed = true,
          .source = kIntrinsicsFromDefault};
}

void WriteVideoOverlay(const fs::path& video, const Json& keypoints, const fs::path& path) {
  DecoderOptions options{.analysis_size = kOverlaySide, .skip_loop_filter = false};
  VideoDecoder decoder(video, options);
  const int width = keypoints.at("width"), height = keypoints.at("height");
  const double fps = keypoints.at("fps").get<double>() > 0 ? keypoints.at("fps").get<double>() : 30.0;
  Mp4Writer writer(path, decoder.geometry().width, decoder.geometry().height, fps);
  const Json& frames = keypoints.at("frames");
  AnalysisFrame frame;
  for (size_t i = 0; i < frames.size() && decoder.Next(&frame); ++i) {
    cv::Mat canvas = frame.bgr.clone();
    DrawHands(canvas, frames[i], width, height);
    writer.Write(canvas);
  }
  writer.Finish();
}

void RunOne(const fs::path& input, const HandsOptions& o, filters::HandLandmarker& landmarker) {
  if (!fs::is_regular_file(input)) {
    throw Error("input_missing", "no such file", {.file = input.string()});
  }
  const fs::path out_dir = o.out;
  const std::string stem = input.stem().string();
  const bool image = cv::haveImageReader(input.string());
  cv::Mat still;
  DetectedFrames detected;
  if (image) {
    still = cv::imread(input.string(), cv::IMREAD_COLOR);
    if (still.empty()) throw Error("image_unreadable", "cannot decode the image", {.file = input.string()});
    detected = DetectImage(still, landmarker);
  } else {
    Progress progress(stem, 0);
    detected = DetectVideo(input, DecoderOptions{.clip = stem}, o.config.max_side, landmarker,
                           [&](std::int64_t done) { progress.Set(static_cast<std::uint64_t>(done)); });
  }
  const HandsResult result = ReconstructHands(detected, CommandIntrinsics(o, detected.width, detected.height), o.config);
  Json keypoints = KeypointsJson(detected, result);
  keypoints["input"] = fs::absolute(input).string();
  WriteTextFile(out_dir / (stem + ".json"), keypoints.dump() + "\n");
  std::string overlay;
  if (o.overlay) {
    if (image) {
      DrawHands(still, keypoints.at("frames").at(0), detected.width, detected.height);
      const fs::path path = out_dir / (stem + ".overlay.png");
      if (!cv::imwrite(path.string(), still)) throw Error("io", "cannot write the overlay", {.file = path.string()});
      overlay = path.string();
    } else {
      const fs::path path = out_dir / (stem + ".overlay.mp4");
      WriteVideoOverlay(input, keypoints, path);
      overlay = path.string();
    }
  }
  const Json summary = Summarize(detected, result);
  std::printf("%s: %zu frame(s), right %d, left %d frame(s) with a hand, %zu track(s); %s%s%s\n",
              input.string().c_str(), detected.frames.size(),
              summary["sides"]["right"]["frames"].get<int>(), summary["sides"]["left"]["frames"].get<int>(),
              result.tracks.size(), (out_dir / (stem + ".json")).string().c_str(),
              overlay.empty() ? "" : ", ", overlay.c_str());
  std::fflush(stdout);
}

// Two inputs with one stem would write one file: refused before any work.
void RequireDistinctStems(const std::vector<std::string>& inputs) {
  std::map<std::string, std::string> seen;
  for (const std::string& input : inputs) {
    const std::string stem = fs::path(input).stem().string();
    auto [it, fresh] = seen.emplace(stem, input);
    if (!fresh) {
      throw Error("bad_arguments", "both " + it->second + " and " + input + " would write " + stem + ".json",
                  {.file = input});
    }
  }
}

std::unique_ptr<filters::HandLandmarker> StartLandmarker(const HandsConfig& c) {
  return std::make_unique<filters::HandLandmarker>(
      filters::HandLandmarkerOptions{.max_hands = c.max_hands, .max_side = c.max_side, .backend = c.backend,
                                      .models = c.models, .palm_every = c.palm_every,
                                      .lost_search = c.palm_every,
                                      .wide_every = c.wide_search_every,
                                      .lost_wide = c.lost_wide_search});
}

void RunHands(const HandsOptions& o) {
  RequireDistinctStems(o.inputs);
  fs::create_directories(o.out);
  auto landmarker = StartLandmarker(o.config);
  int failed = 0;
  for (const std::string& input : o.inputs) {
    try {
      RunOne(input, o, *landmarker);
    } catch (const Error& e) {
      // The batch goes on; a detector that died is started afresh.
      std::fprintf(stderr, "error: %s\n", e.what());
      ++failed;
      if (e.code() == "hand_detector_failed") landmarker = StartLandmarker(o.config);
    }
  }
  if (failed > 0) {
    throw Error("hands_failed", std::to_string(failed) + " of " + std::to_string(o.inputs.size()) +
                                    " input(s) failed (see above)");
  }
}

}  // namespace

void AddHandsCommand(CLI::App& app) {
  auto o = std::make_shared<HandsOptions>();
  auto* cmd = app.add_subcommand(
      "hands",
      "Find hands in videos or still images without a database: MediaPipe's hand models on\n"
      "every frame, one track per hand with a fixed side, 21 keypoints with confidence, and\n"
      "metric 3D joints in the camera frame (PnP, then a Ceres fit of a skeleton whose bones\n"
      "keep their length). Writes <out>/<stem>.json per input.");
  cmd->add_option("inputs", o->inputs, "Videos (any format ffmpeg reads) or images (PNG, JPEG, ...)")
      ->required();
  cmd->add_option("--out", o->out, "Output folder (created)")->required();
  auto* fx = cmd->add_option("--fx", o->fx, "Focal length in pixels of the input as displayed (fy = fx, centred)")
      ->check(CLI::PositiveNumber);
  auto* fov = cmd->add_option("--fov", o->fov, "Horizontal field of view in degrees, when fx is not known")
      ->check(CLI::Range(1.0, 179.0));
  cmd->add_option("--max-hands", o->config.max_hands, "Hands per frame (1 or 2)")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  cmd->add_flag("--overlay", o->overlay,
                "Also draw the keypoints: <stem>.overlay.mp4 for a video, <stem>.overlay.png for an image");
  fx->excludes(fov);
  cmd->footer(
      "Without --fx or --fov the camera is taken to see 65 degrees across, and the JSON says\n"
      "\"intrinsics_assumed\": true. Joint order is MediaPipe's (0 wrist, 4 thumb tip, 8 index\n"
      "tip, 12 middle, 16 ring, 20 little finger tip); keypoints_2d are pixels of the input as\n"
      "displayed, joints_camera metres (x right, y down, z forward). Frames where a hand was\n"
      "briefly lost are filled by the fit and marked \"filled\". An image (gray ones too) is\n"
      "searched wide: zoomed windows and the whole frame for hands the palm detector misses\n"
      "(docs/hands.md, \"Stills, close-ups and gray\").\n\n"
      "Example:\n"
      "  doasido hands clips/cups.mp4 photos/grasp.jpg --out work/hands --overlay\n"
      "  # work/hands/cups.json, cups.overlay.mp4, grasp.json, grasp.overlay.png");
  cmd->callback([o] { RunHands(*o); });
}

}  // namespace doasido::cli
