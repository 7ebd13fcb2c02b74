// The two MediaPipe Hands models as functions from an input tensor to their
// raw outputs, behind one interface with two runtimes:
//   native: our TFLite reader (filters/tflite_model.h) executed by XNNPACK
//           (filters/xnnpack_graph.h) in this process; graph pairs built
//           once per process into a pool (PrepareHandModels), each
//           HandModels borrowing one for its life;
//   wasm:   TFLite's WebAssembly runtime in a Node process
//           (filters/mediapipe_hands.js), the reference the tests compare
//           the native runtime against, and the fallback where the native
//           one cannot load.
// What goes in and what comes out is the same for both, so the pre- and
// post-processing (filters/hand_landmarker.cc) is shared.
//
// The model files come from the npm package @mediapipe/hands in NpmDir()
// (core/data_dirs.h), in two variants (kModelsFull, kModelsLite):
// hand_landmark_<variant>.tflite, and palm_detection_<variant>.tflite packed
// in hands_solution_packed_assets.data at the byte range its loader script
// lists.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace doasido::filters {

inline constexpr int kPalmInputSize = 192;      // palm detector input, square
inline constexpr int kLandmarkInputSize = 224;  // landmark model input, square
inline constexpr int kPalmAnchors = 2016;
inline constexpr int kPalmValues = 18;  // box (cx, cy, w, h) + 7 keypoints (x, y)

inline constexpr const char* kBackendNative = "native";
inline constexpr const char* kBackendWasm = "wasm";

// Which of the models the package ships run, same inputs and outputs:
// "full" (palm detector 344 M multiply-adds, landmark model 331 M), "lite"
// (289 M and 146 M; other weights, so other palms and keypoints), or
// "lite_landmark" (the full palm detector, the lite landmark model).
inline constexpr const char* kModelsFull = "full";
inline constexpr const char* kModelsLite = "lite";
inline constexpr const char* kModelsLiteLandmark = "lite_landmark";

struct PalmOutput {
  std::vector<float> regressors;  // kPalmAnchors x kPalmValues, input pixels about the anchor
  std::vector<float> logits;      // kPalmAnchors
};
struct LandmarkOutput {
  std::vector<float> screen;  // 21 x (x, y, z), input pixels
  float presence = 0;         // 0..1
  float right = 0;            // 0..1, mirrored (see LandmarkedHand::right)
  std::vector<float> world;   // 21 x (x, y, z), metres
};

class HandModels {
 public:
  virtual ~HandModels() = default;
  // `input`: size x size x 3 floats, RGB in [0, 1], rows top to bottom.
  virtual void Palm(const float* input, PalmOutput* out) = 0;
  virtual void Landmark(const float* input, LandmarkOutput* out) = 0;
  // CPU milliseconds the models took since the last call of this (and
  // resets it): the calling thread's (native) or the Node process's (wasm).
  virtual double TakeModelMs() = 0;
  virtual const char* backend() const = 0;
};

// The runtime named `backend` ("native" or "wasm") running the model pair
// `models` (kModelsFull or kModelsLite). Throws
// Error("hand_detector_unavailable") saying what is missing; with
// `fallback`, a native runtime that cannot load gives the wasm one and
// `note` says why.
std::unique_ptr<HandModels> MakeHandModels(const std::string& backend, const std::string& clip,
                                           bool fallback = true, std::string* note = nullptr,
                                           const std::string& models = kModelsFull);
std::unique_ptr<HandModels> MakeNativeHandModels(const std::string& clip,
                                                 const std::string& models = kModelsFull);
std::unique_ptr<HandModels> MakeWasmHandModels(const std::string& clip,
                                               const std::string& models = kModelsFull);

// Builds `count` native graph pairs of `models` (and runs each once) into
// the process's pool, unless that many are already there: each native
// HandModels borrows a pair for its life and gives it back, so a worker
// that calls this before its first clip pays no build on any clip. False
// (with the reason in `why`) when the native runtime cannot load; throws
// Error("bad_config") for a bad `models`.
bool PrepareHandModels(const std::string& models, int count = 1, std::string* why = nullptr);
// Graph pairs built in this process so far (the pool's; for tests and benches).
int HandModelGraphBuilds();

// True when the wasm runtime can start (node and the npm packages), else
// false with the reason in `why`.
bool WasmHandModelsAvailable(std::string* why = nullptr);
// True when the model files are in the npm folder.
bool HandModelFilesAvailable(std::string* why = nullptr, const std::string& models = kModelsFull);
// The files of the pair `models`; throws Error("bad_config", field
// "models") for a name other than the three above.
std::string PalmModelFile(const std::string& models);
std::string LandmarkModelFile(const std::string& models);

// The folder of @mediapipe/hands, and the palm detector's byte range in its
// packed assets (throws Error("hand_detector_unavailable") when not listed).
std::filesystem::path MediapipeHandsDir();
std::pair<std::size_t, std::size_t> PalmModelRange(const std::filesystem::path& hands_dir,
                                                   const std::string& models = kModelsFull);

}  // namespace doasido::filters
