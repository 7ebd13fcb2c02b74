// doasido objects: the objects on files, no database. Each video or still
// image gets <out>/<stem>.json (objects/objects_file.h: the box keypoints and
// the lifted pose and size)
// and, with --overlay, <stem>.overlay.mp4 or <stem>.overlay.png with the
// boxes drawn. A bad input is reported by name and the others still run.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "cli/commands.h"
#include "core/config_check.h"
#include "core/error.h"
#include "core/whole_output.h"
#include "core/progress.h"
#include "filters/hand_landmarker.h"
#include "hands/hand_detection.h"
#include "hands/hand_intrinsics.h"
#include "hands/hands_config.h"
#include "objects/box_overlay.h"
#include "objects/objects_file.h"
#include "objects/object_prompts.h"
#include "objects/objects_in_video.h"
#include "video/mp4_writer.h"

namespace doasido::cli {
namespace {

namespace fs = std::filesystem;
using namespace doasido::objects;

struct ObjectsOptions {
  std::vector<std::string> inputs;
  std::string out;
  bool overlay = false;
  std::vector<std::string> seeds;  // FRAME:X,Y,W,H[:CATEGORY]
  bool near_hands = false;
  double fov_deg = hands::HandsConfig{}.default_fov_deg;
  ObjectsConfig lifting;  // its `models` is the tracker's configuration
  BoxKeypointsConfig& config = lifting.models;
};

// The hand landmarker's hands of every frame of a video (or of an image),
// for the boxes tried beside the fingers.
HandsByFrame FindHands(const fs::path& input, const cv::Mat* still) {
  filters::HandLandmarker landmarker({.max_hands = 2, .clip = input.stem().string()});
  const hands::DetectedFrames found =
      still ? hands::DetectImage(*still, landmarker)
            : hands::DetectVideo(input, DecoderOptions{.clip = input.stem().string()}, 640, landmarker);
  HandsByFrame out;
  for (std::size_t i = 0; i < found.frames.size(); ++i) {
    auto& list = out[found.first_frame + static_cast<std::int64_t>(i)];
    for (const hands::HandObservation& h : found.frames[i]) {
      HandPoints2d p;
      for (int k = 0; k < kHandPoints; ++k) p[k] = h.uv[k];
      list.push_back(p);
    }
  }
  return out;
}

// Overlays of videos are drawn at most this large on their longer side.
constexpr int kOverlaySide = 1280;

void WriteVideoOverlay(const fs::path& video, const Json& objects, const fs::path& path) {
  DecoderOptions options{.analysis_size = kOverlaySide, .skip_loop_filter = false};
  VideoDecoder decoder(video, options);
  const int width = objects.at("width"), height = objects.at("height");
  const double fps = objects.at("fps").get<double>() > 0 ? objects.at("fps").get<double>() : 30.0;
  Mp4Writer writer(path, decoder.geometry().width, decoder.geometry().height, fps);
  const Json& frames = objects.at("frames");
  AnalysisFrame frame;
  for (size_t i = 0; i < frames.size() && decoder.Next(&frame); ++i) {
    cv::Mat canvas = frame.bgr.clone();
    DrawObjects(canvas, frames[i], width, height);
    writer.Write(canvas);
  }
  writer.Finish();
}

void RunOne(const fs::path& input, const ObjectsOptions& o, const std::vector<SeedBox>& seeds,
            BoxTracker& tracker) {
  if (!fs::is_regular_file(input)) throw Error("input_missing", "no such file", {.file = input.string()});
  const std::string stem = input.stem().string();
  const bool image = cv::haveImageReader(input.string());
  cv::Mat still;
  DetectedObjects detected;
  if (image) {
    still = cv::imread(input.string(), cv::IMREAD_COLOR);
    if (still.empty()) throw Error("image_unreadable", "cannot decode the image", {.file = input.string()});
  }
  const HandsByFrame hands = o.near_hands ? FindHands(input, image ? &still : nullptr) : HandsByFrame{};
  if (image) {
    detected = ObjectsInImage(still, tracker, seeds, o.near_hands ? &hands : nullptr);
  } else {
    Progress progress(stem, 0);
    detected = ObjectsInVideo(input, DecoderOptions{.clip = stem}, o.config.max_side, tracker,
                              [&](std::int64_t done) { progress.Set(static_cast<std::uint64_t>(done)); },
                              seeds, o.near_hands ? &hands : nullptr);
  }
  Json objects =
      ObjectsFileJson(detected, hands::KFromFov(detected.width, detected.height, o.fov_deg), o.lifting);
  objects["input"] = fs::absolute(input).string();
  const fs::path json_path = fs::path(o.out) / (stem + ".json");
  WriteFileWhole(json_path, objects.dump() + "\n");
  std::string overlay;
  if (o.overlay) {
    const fs::path path = fs::path(o.out) / (stem + (image ? ".overlay.png" : ".overlay.mp4"));
    if (image) {
      DrawObjects(still, objects.at("frames").at(0), detected.width, detected.height);
      if (!cv::imwrite(path.string(), still)) throw Error("io", "cannot write the overlay", {.file = path.string()});
    } else {
      WriteVideoOverlay(input, objects, path);
    }
    overlay = path.string();
  }
  std::map<int, std::string> tracks;
  int with_object = 0;
  for (const auto& frame : detected.frames) {
    with_object += !frame.empty();
    for (const ObjectObservation& ob : frame) tracks[ob.track] = ob.category;
  }
  std::printf("%s: %zu frame(s), %d with an object, %zu track(s); %s%s%s\n", input.string().c_str(),
              detected.frames.size(), with_object, tracks.size(), json_path.string().c_str(),
              overlay.empty() ? "" : ", ", overlay.c_str());
  std::fflush(stdout);
}

void RunObjects(ObjectsOptions& o) {
  o.config.hand_proposals = o.near_hands;
  CheckConfig(o.lifting, "objects");
  std::map<std::string, std::string> seen;  // two inputs with one stem would write one file
  for (const std::string& input : o.inputs) {
    auto [it, fresh] = seen.emplace(fs::path(input).stem().string(), input);
    if (!fresh) {
      throw Error("bad_arguments", "both " + it->second + " and " + input + " would write " + it->first + ".json",
                  {.file = input});
    }
  }
  std::vector<SeedBox> seeds;  // a bad one is refused before any work
  for (const std::string& text : o.seeds) {
    for (SeedBox& seed : SeedsFromPrompt(text, "", "--seed")) seeds.push_back(std::move(seed));
  }
  fs::create_directories(o.out);
  BoxTracker tracker(o.config, "");
  int failed = 0;
  for (const std::string& input : o.inputs) {
    try {
      RunOne(input, o, seeds, tracker);
    } catch (const Error& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      ++failed;
    } catch (const std::exception& e) {  // a library's own error: still this input's alone
      std::fprintf(stderr, "error: %s: %s\n", input.c_str(), e.what());
      ++failed;
    }
  }
  if (failed > 0) {
    throw Error("objects_failed", std::to_string(failed) + " of " + std::to_string(o.inputs.size()) +
                                      " input(s) failed (see above)");
  }
}

}  // namespace

void AddObjectsCommand(CLI::App& app) {
  auto o = std::make_shared<ObjectsOptions>();
  auto* cmd = app.add_subcommand(
      "objects",
      "Find objects in videos or still images without a database: MediaPipe Objectron's 2D\n"
      "detector (SSD MobileNetV2, Open Images) and its box-landmark models for cups and mugs,\n"
      "shoes, chairs and cameras, run natively; one track per object with a fixed category,\n"
      "the 9 keypoints of its 3D bounding box in the image, lifted to a pose and size in the\n"
      "camera frame. Writes <out>/<stem>.json per input.");
  cmd->add_option("inputs", o->inputs, "Videos (any format ffmpeg reads) or images (PNG, JPEG, ...)")
      ->required();
  cmd->add_option("--out", o->out, "Output folder (created)")->required();
  cmd->add_option("--categories", o->config.categories,
                  "Box-landmark models to run, comma-separated: cup,sneakers,chair,camera")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->capture_default_str();
  cmd->add_option("--detect-every", o->config.detect_every,
                  "While objects are tracked, the detector looks for others every this many frames")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--min-presence", o->config.min_presence,
                  "Box-landmark presence below this ends a track ([objects.models] min_presence)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--seed", o->seeds,
                  "FRAME:X,Y,W,H[:CATEGORY] (category cup when not given; several joined by ';'): an\n"
                  "object the detector may miss, boxed by hand on one frame (pixels of the input); followed\n"
                  "from there in 2D (median flow), the box-landmark model reading its keypoints (a clip\n"
                  "list's object_box column takes the same text); the track ends where the keypoints leave\n"
                  "the followed box or the follower loses it. One value per --seed (repeat it)")
      ->allow_extra_args(false);
  cmd->add_option("--follow-side", o->config.prompt_follow_side,
                  "A seeded box is followed on a grey frame shrunk so that its long side is this many\n"
                  "pixels ([objects.models] prompt_follow_side)")
      ->check(CLI::Range(16, 1024))
      ->capture_default_str();
  cmd->add_option("--follow-max-error", o->config.prompt_follow_max_error,
                  "Forward-backward error (pixels of the follower's frame) a followed point may have\n"
                  "([objects.models] prompt_follow_max_error)")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--max-jump", o->config.prompt_max_jump,
                  "A seeded track ends where the model's keypoint centre lies further than this times the\n"
                  "box's long side from the followed box or from where it was last seen\n"
                  "([objects.models] prompt_max_jump)")
      ->check(CLI::Range(0.01, 10.0))
      ->capture_default_str();
  cmd->add_flag("--near-hands", o->near_hands,
                "Also find the hands (MediaPipe Hands) and try boxes beside their fingers with the\n"
                "box-landmark models: some held objects the 2D detector misses, as rough boxes; a bare\n"
                "hand can pass as a cup (docs/object_models.md)");
  cmd->add_option("--fov", o->fov_deg, "Horizontal field of view of the camera, degrees (for the 3D lifting)")
      ->check(CLI::Range(1.0, 179.0))
      ->capture_default_str();
  cmd->add_flag("--overlay", o->overlay,
                "Also draw the boxes: <stem>.overlay.mp4 for a video, <stem>.overlay.png for an image");
  cmd->footer(
      "The JSON: {\"width\", \"height\", \"fps\", \"first_frame\", \"K\", \"tracks\", \"frames\": [{\"frame\": i,\n"
      "\"objects\": [{\"category\", \"score\", \"track\", \"keypoints_2d\": [[x, y] x 9], \"center_camera\":\n"
      "[x, y, z], \"rotation_camera\": [[3 x 3]], \"size_m\": [x, y, z], \"scale_assumed\", ...}]}]},\n"
      "keypoint 0 the box centre and 1-8 its corners in the order of MediaPipe's objectron.py\n"
      "(1 back-bottom-left, 2 front-bottom-left, 3 back-top-left, 4 front-top-left, 5-8 the same\n"
      "on the right), pixels of the input as displayed; score is the box-landmark model's presence\n"
      "(a box is kept at >= 0.99). The 3D fields: EPnP on the corners, one smoothing per track, in\n"
      "the camera frame (x right, y down, z forward; metres) of a camera of --fov; with no hands\n"
      "in 3D here the size is the category's prior (scale_assumed true; the objects stage sizes\n"
      "it by the touching hand). Frames the fit filled have keypoints_2d null (docs/objects.md).\n"
      "The models are the npm package @mediapipe/objectron (scripts/setup.sh installs it).\n"
      "The 2D detector does not find every object of its categories (it finds scikit-image's\n"
      "coffee cup photo, not 02_cups' red plastic cups: no cup score above 0.2): --seed starts a\n"
      "track where a person boxed the object;\n"
      "--near-hands tries boxes beside the fingers (rough boxes, and hands alone can pass).\n\n"
      "Example:\n"
      "  doasido objects clips/cups.mp4 photos/mug.jpg --out work/objects --overlay\n"
      "  # work/objects/cups.json, cups.overlay.mp4, mug.json, mug.overlay.png\n"
      "  doasido objects clips/cups.mp4 --seed 0:570,290,170,255 --out work/objects\n"
      "  doasido objects clips/held_cup.mp4 --near-hands --fov 60 --out work/objects");
  cmd->callback([o] { RunObjects(*o); });
}

}  // namespace doasido::cli
