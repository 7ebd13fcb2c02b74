#include "filters/hand_models.h"

#include <time.h>

#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <utility>

#include "core/clock.h"
#include "core/data_dirs.h"
#include "core/error.h"
#include "filters/xnnpack_graph.h"

namespace doasido::filters {

namespace {

constexpr const char* kPackedAssets = "hands_solution_packed_assets.data";
constexpr const char* kPackedLoader = "hands_solution_packed_assets_loader.js";

// Output index of the tensor called `name` (the models name them Identity,
// Identity_1, ...).
std::size_t OutputNamed(const TfliteModel& m, const std::string& name) {
  for (std::size_t i = 0; i < m.outputs.size(); ++i) {
    if (m.tensors[m.outputs[i]].name == name) return i;
  }
  throw Error("bad_model", "no output named " + name, {.file = m.path});
}

// The parsed models of one pair, read once per process and shared by every
// graph pair (XNNPACK reads the weights from them).
struct ParsedModels {
  std::shared_ptr<const TfliteModel> palm, landmark;
};
ParsedModels LoadParsedModels(const std::string& pair) {
  static std::mutex mutex;
  static std::map<std::string, ParsedModels> loaded;
  std::lock_guard<std::mutex> lock(mutex);
  ParsedModels& models = loaded[pair];
  if (!models.palm) {
    const std::filesystem::path dir = MediapipeHandsDir();
    const auto [begin, end] = PalmModelRange(dir, pair);
    models.palm = std::make_shared<TfliteModel>(ReadTfliteModel(dir / kPackedAssets, begin, end));
    models.landmark = std::make_shared<TfliteModel>(ReadTfliteModel(dir / LandmarkModelFile(pair)));
  }
  return models;
}

// One pair of graphs (used by one HandModels at a time).
struct GraphPair {
  explicit GraphPair(const ParsedModels& m)
      : palm(m.palm), landmark(m.landmark),
        palm_boxes(OutputNamed(*m.palm, "Identity")),
        palm_scores(OutputNamed(*m.palm, "Identity_1")),
        screen(OutputNamed(*m.landmark, "Identity")),
        presence(OutputNamed(*m.landmark, "Identity_1")),
        right(OutputNamed(*m.landmark, "Identity_2")),
        world(OutputNamed(*m.landmark, "Identity_3")) {
    if (palm.input_size() != kPalmInputSize * kPalmInputSize * 3 ||
        landmark.input_size() != kLandmarkInputSize * kLandmarkInputSize * 3 ||
        palm.output(palm_boxes).size() != kPalmAnchors * kPalmValues) {
      throw Error("bad_model", "the hand models' tensors are not the sizes MediaPipe Hands has",
                  {.file = m.palm->path});
    }
  }
  XnnpackGraph palm, landmark;
  std::size_t palm_boxes, palm_scores, screen, presence, right, world;
};

// Graph pairs built once per process and lent to one HandModels at a
// time, whatever thread it runs on: a worker builds them before its first
// clip (PrepareHandModels) and each landmarker after borrows them. A
// thread-local pair would be built again by every new thread and would
// cost its first clip the build and the first runs.
class GraphPool {
 public:
  static GraphPool& Get() {
    static GraphPool pool;
    return pool;
  }
  std::unique_ptr<GraphPair> Borrow(const std::string& pair) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      std::vector<std::unique_ptr<GraphPair>>& free = free_[pair];
      if (!free.empty()) {
        std::unique_ptr<GraphPair> graphs = std::move(free.back());
        free.pop_back();
        return graphs;
      }
    }
    auto graphs = std::make_unique<GraphPair>(LoadParsedModels(pair));
    Warm(*graphs);
    ++builds_;
    return graphs;
  }
  void Return(const std::string& pair, std::unique_ptr<GraphPair> graphs) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_[pair].push_back(std::move(graphs));
  }
  int builds() const { return builds_.load(); }

 private:
  // One run of each graph on a blank input: the first run of a new graph
  // touches its scratch memory for the first time, paid here, not in a clip.
  static void Warm(GraphPair& g) {
    std::fill(g.palm.input(), g.palm.input() + g.palm.input_size(), 0.f);
    g.palm.Run();
    std::fill(g.landmark.input(), g.landmark.input() + g.landmark.input_size(), 0.f);
    g.landmark.Run();
  }
  std::mutex mutex_;
  std::map<std::string, std::vector<std::unique_ptr<GraphPair>>> free_;
  std::atomic<int> builds_{0};
};

class NativeHandModels : public HandModels {
 public:
  explicit NativeHandModels(const std::string& pair)
      : pair_(pair), graphs_(GraphPool::Get().Borrow(pair)) {}
  ~NativeHandModels() override { GraphPool::Get().Return(pair_, std::move(graphs_)); }
  void Palm(const float* input, PalmOutput* out) override {
    const double start = ThreadCpuMs();
    XnnpackGraph& g = graphs_->palm;
    std::copy(input, input + g.input_size(), g.input());
    g.Run();
    out->regressors = g.output(graphs_->palm_boxes);
    out->logits = g.output(graphs_->palm_scores);
    ms_ += ThreadCpuMs() - start;
  }
  void Landmark(const float* input, LandmarkOutput* out) override {
    const double start = ThreadCpuMs();
    XnnpackGraph& g = graphs_->landmark;
    std::copy(input, input + g.input_size(), g.input());
    g.Run();
    out->screen = g.output(graphs_->screen);
    out->presence = g.output(graphs_->presence).at(0);
    out->right = g.output(graphs_->right).at(0);
    out->world = g.output(graphs_->world);
    ms_ += ThreadCpuMs() - start;
  }
  double TakeModelMs() override { return std::exchange(ms_, 0.0); }
  const char* backend() const override { return kBackendNative; }

 private:
  std::string pair_;
  std::unique_ptr<GraphPair> graphs_;  // borrowed from the pool
  double ms_ = 0;
};

}  // namespace

bool PrepareHandModels(const std::string& models, int count, std::string* why) {
  PalmModelFile(models);  // a bad name is the config's error
  if (!HandModelFilesAvailable(why, models)) return false;
  std::vector<std::unique_ptr<GraphPair>> built;
  try {
    for (int i = 0; i < count; ++i) built.push_back(GraphPool::Get().Borrow(models));
  } catch (const Error& e) {
    if (why) *why = e.what();
    return false;
  }
  for (auto& graphs : built) GraphPool::Get().Return(models, std::move(graphs));
  return true;
}

int HandModelGraphBuilds() { return GraphPool::Get().builds(); }

std::filesystem::path MediapipeHandsDir() { return NpmDir() / "node_modules" / "@mediapipe/hands"; }

std::string PalmModelFile(const std::string& models) {
  if (models != kModelsFull && models != kModelsLite && models != kModelsLiteLandmark) {
    throw Error("bad_config",
                "hand models must be full, lite or lite_landmark, not " + models,
                {.field = "models"});
  }
  return std::string("palm_detection_") + (models == kModelsLite ? "lite" : "full") + ".tflite";
}

std::string LandmarkModelFile(const std::string& models) {
  PalmModelFile(models);  // checks the name
  return std::string("hand_landmark_") + (models == kModelsFull ? "full" : "lite") + ".tflite";
}

std::pair<std::size_t, std::size_t> PalmModelRange(const std::filesystem::path& hands_dir,
                                                   const std::string& models) {
  const std::string palm = PalmModelFile(models);
  const std::filesystem::path loader = hands_dir / kPackedLoader;
  const auto range = PackedFileRange(loader, palm);
  if (!range) {
    throw Error("hand_detector_unavailable",
                palm + " is not listed in the @mediapipe/hands loader", {.file = loader.string()});
  }
  return *range;
}

bool HandModelFilesAvailable(std::string* why, const std::string& models) {
  const std::filesystem::path dir = MediapipeHandsDir();
  for (const std::string& file : {LandmarkModelFile(models), std::string(kPackedAssets),
                                  std::string(kPackedLoader)}) {
    if (!std::filesystem::exists(dir / file)) {
      if (why) {
        *why = (dir / file).string() +
               " is missing (scripts/setup.sh installs the npm package @mediapipe/hands)";
      }
      return false;
    }
  }
  return true;
}

std::unique_ptr<HandModels> MakeNativeHandModels(const std::string& clip,
                                                 const std::string& models) {
  std::string why;
  if (!HandModelFilesAvailable(&why, models)) {
    throw Error("hand_detector_unavailable", why, {.clip = clip});
  }
  try {
    return std::make_unique<NativeHandModels>(models);
  } catch (const Error& e) {
    throw Error("hand_detector_unavailable", "the native hand models cannot load: " + e.message(),
                {.clip = clip, .file = e.site().file});
  }
}

std::unique_ptr<HandModels> MakeHandModels(const std::string& backend, const std::string& clip,
                                           bool fallback, std::string* note,
                                           const std::string& models) {
  PalmModelFile(models);  // a bad name is the config's error, not a missing runtime
  if (backend == kBackendWasm) return MakeWasmHandModels(clip, models);
  if (backend != kBackendNative) {
    throw Error("bad_config", "hand model backend must be native or wasm, not " + backend,
                {.clip = clip, .field = "backend"});
  }
  try {
    return MakeNativeHandModels(clip, models);
  } catch (const Error& e) {
    if (!fallback || e.code() == "bad_config") throw;
    auto wasm = MakeWasmHandModels(clip, models);
    if (note) *note = std::string(e.what()) + "; using the WebAssembly runtime instead";
    return wasm;
  }
}

}  // namespace doasido::filters
