// The MediaPipe Objectron models as functions from an input tensor to their
// raw outputs, run natively: our TFLite reader (filters/tflite_model.h)
// executed by XNNPACK (filters/xnnpack_graph.h) on the calling thread.
//
// The files come from the npm package @mediapipe/objectron (pinned in
// scripts/setup.sh) in NpmDir() (core/data_dirs.h); nothing is downloaded:
//   - the 2D detector, SSD MobileNetV2 trained on Open Images v4 (fp16),
//     packed in objectron_solution_packed_assets.data at the byte range its
//     loader script lists, checked against the SHA-256 google/mediapipe
//     records for it (third_party/external_files.bzl); the label map is
//     packed before it;
//   - one box-landmark model per category,
//     object_detection_3d_<category>.tflite.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace doasido::filters {
class XnnpackGraph;
}

namespace doasido::objects {

// Error codes: the models cannot load (a file missing or failing its hash),
// or a run failed.
inline constexpr const char* kObjectDetectorUnavailable = "object_detector_unavailable";
inline constexpr const char* kObjectDetectorFailed = "object_detector_failed";

inline constexpr int kDetectorInputSize = 300;  // square, the whole frame stretched
inline constexpr int kDetectorAnchors = 1917;
inline constexpr int kDetectorClasses = 24;     // class 0 is "???" (background), ignored
inline constexpr int kBoxInputSize = 224;       // box-landmark model input, square
// google/mediapipe's recorded SHA-256 of object_detection_ssd_mobilenetv2_oidv4_fp16.tflite.
inline constexpr const char* kDetectorSha256 =
    "d0a5255bf8c4f5a0bc4240741a76c41d5e939f7655078f945f50ab53a9375da6";

// A category the package has a box-landmark model for, and the detector's
// Open Images labels that select it (python/solutions/objectron.py).
struct ObjectCategory {
  const char* name;                  // "cup", also the model file's suffix
  std::vector<const char*> labels;   // detector labels
};
const std::vector<ObjectCategory>& ObjectCategories();
// The category whose detector labels include `label`, or nullptr.
const ObjectCategory* CategoryOfLabel(const std::string& label);
// Throws Error("bad_config", field "categories") for a name not in the list.
const ObjectCategory& CategoryNamed(const std::string& name);

struct DetectorOutput {
  std::vector<float> boxes;   // kDetectorAnchors x (ty, tx, th, tw), relative to the anchor
  std::vector<float> logits;  // kDetectorAnchors x kDetectorClasses, before the sigmoid
};
struct BoxLandmarkOutput {
  std::array<float, 18> keypoints{};  // 9 x (x, y), pixels of the 224 x 224 input
  float presence = 0;                 // 0..1 (the model applies the sigmoid)
};

class ObjectronModels {
 public:
  // Loads the detector and the models of `categories` (names of
  // ObjectCategories()). Throws Error("object_detector_unavailable") saying
  // which file is missing or fails its hash, `clip` naming the input.
  ObjectronModels(const std::vector<std::string>& categories, const std::string& clip);
  ~ObjectronModels();
  ObjectronModels(const ObjectronModels&) = delete;
  ObjectronModels& operator=(const ObjectronModels&) = delete;

  // `input`: 300 x 300 x 3 floats, RGB in [-1, 1], rows top to bottom.
  void Detect(const float* input, DetectorOutput* out);
  // `input`: 224 x 224 x 3 floats, RGB in [0, 1]; `category` one loaded.
  void Landmarks(const std::string& category, const float* input, BoxLandmarkOutput* out);
  // The detector's label of each class index (the packed label map).
  const std::vector<std::string>& labels() const { return labels_; }
  // CPU milliseconds and runs of each model since the models were made.
  double detector_ms() const { return detector_ms_; }
  double landmark_ms() const { return landmark_ms_; }
  int detector_runs() const { return detector_runs_; }
  int landmark_runs() const { return landmark_runs_; }

 private:
  struct BoxGraph;
  std::unique_ptr<filters::XnnpackGraph> detector_;
  std::size_t detector_boxes_ = 0, detector_logits_ = 0;  // output indices
  std::map<std::string, std::unique_ptr<BoxGraph>> boxes_;
  std::vector<std::string> labels_;
  std::string clip_;
  double detector_ms_ = 0, landmark_ms_ = 0;
  int detector_runs_ = 0, landmark_runs_ = 0;
};

// The folder of @mediapipe/objectron, and the byte range of the packed file
// `name` in its packed assets (throws Error("object_detector_unavailable")
// when the loader does not list it).
std::filesystem::path ObjectronDir();
std::pair<std::size_t, std::size_t> PackedAssetRange(const std::filesystem::path& dir,
                                                     const std::string& name);
// True when every model file is in the npm folder, else false and why.
bool ObjectronModelFilesAvailable(std::string* why = nullptr);

}  // namespace doasido::objects
