#include "objects/objectron_models.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "core/clock.h"
#include "core/data_dirs.h"
#include "core/error.h"
#include "filters/xnnpack_graph.h"
#include "ingest/file_sha256.h"

namespace doasido::objects {

namespace {

namespace fs = std::filesystem;

constexpr const char* kPackedAssets = "objectron_solution_packed_assets.data";
constexpr const char* kPackedLoader = "objectron_solution_packed_assets_loader.js";
constexpr const char* kDetectorFile = "object_detection_ssd_mobilenetv2_oidv4_fp16.tflite";
constexpr const char* kLabelMapFile = "object_detection_oidv4_labelmap.txt";
constexpr const char* kInstall = " (scripts/setup.sh installs the npm package @mediapipe/objectron)";

std::string BoxModelFile(const std::string& category) {
  return "object_detection_3d_" + category + ".tflite";
}

std::vector<std::uint8_t> ReadRange(const fs::path& file, std::size_t begin, std::size_t end) {
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes(end > begin ? end - begin : 0);
  in.seekg(static_cast<std::streamoff>(begin));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!in) {
    throw Error(kObjectDetectorUnavailable, "cannot read bytes " + std::to_string(begin) + "-" +
                                                   std::to_string(end) + kInstall,
                {.file = file.string()});
  }
  return bytes;
}

}  // namespace

// One category's box-landmark graph and where its two outputs are.
struct ObjectronModels::BoxGraph {
  explicit BoxGraph(std::shared_ptr<const filters::TfliteModel> model) : graph(model) {
    for (std::size_t i = 0; i < model->outputs.size(); ++i) {
      const std::size_t n = graph.output(i).size();
      if (n == 18) keypoints = i;
      if (n == 1) presence = i;
    }
    if (graph.input_size() != kBoxInputSize * kBoxInputSize * 3 || keypoints == presence) {
      throw Error("bad_model", "not a box-landmark model: input 224x224x3, outputs [1,18] and [1,1]",
                  {.file = model->path});
    }
  }
  filters::XnnpackGraph graph;
  std::size_t keypoints = 0, presence = 0;
};

const std::vector<ObjectCategory>& ObjectCategories() {
  static const std::vector<ObjectCategory> categories = {
      {"cup", {"Coffee cup", "Mug"}},
      {"sneakers", {"Footwear"}},
      {"chair", {"Chair"}},
      {"camera", {"Camera"}},
  };
  return categories;
}

const ObjectCategory* CategoryOfLabel(const std::string& label) {
  for (const ObjectCategory& c : ObjectCategories()) {
    for (const char* l : c.labels) {
      if (label == l) return &c;
    }
  }
  return nullptr;
}

const ObjectCategory& CategoryNamed(const std::string& name) {
  for (const ObjectCategory& c : ObjectCategories()) {
    if (name == c.name) return c;
  }
  throw Error("bad_config", "object category must be cup, sneakers, chair or camera, not " + name,
              {.field = "categories"});
}

fs::path ObjectronDir() { return NpmDir() / "node_modules" / "@mediapipe/objectron"; }

std::pair<std::size_t, std::size_t> PackedAssetRange(const fs::path& dir, const std::string& name) {
  const fs::path loader = dir / kPackedLoader;
  const auto range = filters::PackedFileRange(loader, name);
  if (!range) {
    throw Error(kObjectDetectorUnavailable,
                name + " is not listed in the @mediapipe/objectron loader" + kInstall,
                {.file = loader.string()});
  }
  return *range;
}

bool ObjectronModelFilesAvailable(std::string* why) {
  const fs::path dir = ObjectronDir();
  std::vector<std::string> files = {kPackedAssets, kPackedLoader};
  for (const ObjectCategory& c : ObjectCategories()) files.push_back(BoxModelFile(c.name));
  for (const std::string& file : files) {
    if (!fs::exists(dir / file)) {
      if (why) *why = (dir / file).string() + " is missing" + kInstall;
      return false;
    }
  }
  return true;
}

ObjectronModels::ObjectronModels(const std::vector<std::string>& categories, const std::string& clip)
    : clip_(clip) {
  std::string why;
  if (!ObjectronModelFilesAvailable(&why)) {
    throw Error(kObjectDetectorUnavailable, why, {.clip = clip});
  }
  const fs::path dir = ObjectronDir();
  const fs::path packed = dir / kPackedAssets;
  // The detector: its bytes must be the file google/mediapipe records.
  const auto [begin, end] = PackedAssetRange(dir, kDetectorFile);
  const std::vector<std::uint8_t> bytes = ReadRange(packed, begin, end);
  ingest::Sha256 sha;
  sha.Update(bytes.data(), bytes.size());
  const std::string digest = sha.HexDigest();
  if (digest != kDetectorSha256) {
    throw Error(kObjectDetectorUnavailable,
                std::string(kDetectorFile) + " in the packed assets has SHA-256 " + digest +
                    ", not the " + kDetectorSha256 + " google/mediapipe records" + kInstall,
                {.clip = clip, .file = packed.string()});
  }
  auto detector = std::make_shared<const filters::TfliteModel>(
      filters::ReadTfliteModel(bytes.data(), bytes.size(), packed.string() + ":" + kDetectorFile));
  detector_ = std::make_unique<filters::XnnpackGraph>(detector);
  for (std::size_t i = 0; i < detector->outputs.size(); ++i) {
    const std::size_t n = detector_->output(i).size();
    if (n == static_cast<std::size_t>(kDetectorAnchors) * 4) detector_boxes_ = i;
    if (n == static_cast<std::size_t>(kDetectorAnchors) * kDetectorClasses) detector_logits_ = i;
  }
  if (detector_->input_size() != kDetectorInputSize * kDetectorInputSize * 3 ||
      detector_boxes_ == detector_logits_) {
    throw Error(kObjectDetectorUnavailable,
                "the detector's tensors are not SSD MobileNetV2's (300x300x3 in; 1917x4 and 1917x24 out)",
                {.clip = clip, .file = packed.string()});
  }
  // The label map: one label per line, class index = line number.
  const auto [label_begin, label_end] = PackedAssetRange(dir, kLabelMapFile);
  const std::vector<std::uint8_t> label_bytes = ReadRange(packed, label_begin, label_end);
  std::istringstream lines(std::string(label_bytes.begin(), label_bytes.end()));
  for (std::string line; std::getline(lines, line);) labels_.push_back(line);
  if (labels_.size() != static_cast<std::size_t>(kDetectorClasses)) {
    throw Error(kObjectDetectorUnavailable,
                "the label map has " + std::to_string(labels_.size()) + " labels, not 24",
                {.clip = clip, .file = packed.string()});
  }
  for (const std::string& name : categories) {
    CategoryNamed(name);
    const fs::path file = dir / BoxModelFile(name);
    auto model = std::make_shared<const filters::TfliteModel>(filters::ReadTfliteModel(file));
    boxes_[name] = std::make_unique<BoxGraph>(model);
  }
}

ObjectronModels::~ObjectronModels() = default;

void ObjectronModels::Detect(const float* input, DetectorOutput* out) {
  const double start = ThreadCpuMs();
  std::copy(input, input + detector_->input_size(), detector_->input());
  detector_->Run();
  out->boxes = detector_->output(detector_boxes_);
  out->logits = detector_->output(detector_logits_);
  detector_ms_ += ThreadCpuMs() - start;
  ++detector_runs_;
}

void ObjectronModels::Landmarks(const std::string& category, const float* input,
                                BoxLandmarkOutput* out) {
  const auto it = boxes_.find(category);
  if (it == boxes_.end()) {
    throw Error(kObjectDetectorFailed, "no box-landmark model loaded for " + category,
                {.clip = clip_});
  }
  const double start = ThreadCpuMs();
  BoxGraph& g = *it->second;
  std::copy(input, input + g.graph.input_size(), g.graph.input());
  g.graph.Run();
  const std::vector<float>& k = g.graph.output(g.keypoints);
  std::copy(k.begin(), k.end(), out->keypoints.begin());
  out->presence = g.graph.output(g.presence).at(0);
  landmark_ms_ += ThreadCpuMs() - start;
  ++landmark_runs_;
}

}  // namespace doasido::objects
