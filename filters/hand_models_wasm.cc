// The wasm runtime of filters/hand_models.h: a long-lived Node process
// running filters/mediapipe_hands.js (TFLite's WebAssembly runtime, one
// thread), fed input tensors and answering raw outputs over pipes.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "core/config.h"
#include "core/data_dirs.h"
#include "core/error.h"
#include "filters/hand_models.h"

extern char** environ;

namespace doasido::filters {

extern const char kMediapipeHandsScript[];

namespace {

constexpr const char* kPackages[] = {"@mediapipe/hands", "@tensorflow/tfjs-tflite",
                                     "@tensorflow/tfjs-core", "@tensorflow/tfjs-backend-cpu"};

class WasmHandModels : public HandModels {
 public:
  WasmHandModels(const std::string& clip, const std::string& models);
  ~WasmHandModels() override;

  void Palm(const float* input, PalmOutput* out) override {
    const std::vector<float> v = Request("palm", input, kPalmInputSize);
    if (v.size() != kPalmAnchors * (kPalmValues + 1)) Garbage("palm output size");
    out->regressors.assign(v.begin(), v.begin() + kPalmAnchors * kPalmValues);
    out->logits.assign(v.begin() + kPalmAnchors * kPalmValues, v.end());
  }
  void Landmark(const float* input, LandmarkOutput* out) override {
    const std::vector<float> v = Request("landmark", input, kLandmarkInputSize);
    if (v.size() != 128) Garbage("landmark output size");  // 63 + 1 + 1 + 63
    out->screen.assign(v.begin(), v.begin() + 63);
    out->presence = v[63];
    out->right = v[64];
    out->world.assign(v.begin() + 65, v.end());
  }
  double TakeModelMs() override { return std::exchange(ms_, 0.0); }
  const char* backend() const override { return kBackendWasm; }

 private:
  std::vector<float> Request(const char* model, const float* input, int size);
  [[noreturn]] void Garbage(const std::string& what) const {
    throw Error("hand_detector_failed", "unreadable answer from the detector: " + what,
                {.clip = clip_});
  }
  std::string ReadLine();
  void ReadExact(void* data, std::size_t size);
  void WriteAll(const void* data, std::size_t size);

  std::string clip_;
  pid_t pid_ = -1;
  int to_child_ = -1, from_child_ = -1;
  std::string buffered_;
  double ms_ = 0;
};

WasmHandModels::WasmHandModels(const std::string& clip, const std::string& models)
    : clip_(clip) {
  std::string why;
  if (!WasmHandModelsAvailable(&why)) {
    throw Error("hand_detector_unavailable",
                why + " (scripts/setup.sh installs node and the pinned npm packages)",
                {.clip = clip_});
  }
  // A detector that died must be an error on write, not the end of this process.
  signal(SIGPIPE, SIG_IGN);
  int in[2], out[2];
  if (pipe2(in, O_CLOEXEC) != 0 || pipe2(out, O_CLOEXEC) != 0) {
    throw Error("hand_detector_unavailable", std::string("pipe: ") + std::strerror(errno));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  std::vector<std::string> env_strings = {"NODE_PATH=" + (NpmDir() / "node_modules").string()};
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::strncmp(*e, "NODE_PATH=", 10) != 0) env_strings.emplace_back(*e);
  }
  std::vector<char*> env;
  for (std::string& s : env_strings) env.push_back(s.data());
  env.push_back(nullptr);
  // The script finds the files of the pair by these names.
  std::string node = "node", flag = "-e", script = kMediapipeHandsScript,
              palm = PalmModelFile(models), landmark = LandmarkModelFile(models);
  char* argv[] = {node.data(), flag.data(), script.data(), palm.data(), landmark.data(), nullptr};
  const int spawned = posix_spawnp(&pid_, node.c_str(), &actions, nullptr, argv, env.data());
  posix_spawn_file_actions_destroy(&actions);
  close(in[0]);
  close(out[1]);
  to_child_ = in[1];
  from_child_ = out[0];
  if (spawned != 0) {
    pid_ = -1;
    throw Error("hand_detector_unavailable", "cannot start node: " + std::string(std::strerror(spawned)),
                {.clip = clip_});
  }
  const std::string first = ReadLine();
  const Json hello = Json::parse(first, nullptr, false);
  if (hello.is_discarded() || !hello.value("ready", false)) {
    throw Error("hand_detector_unavailable",
                "the detector did not start: " +
                    (hello.is_object() ? hello.value("error", first) : first),
                {.clip = clip_});
  }
}

WasmHandModels::~WasmHandModels() {
  if (to_child_ >= 0) close(to_child_);
  if (from_child_ >= 0) close(from_child_);
  if (pid_ > 0) {
    int status = 0;
    // End of input ends the program; a stuck one is killed.
    for (int i = 0; i < 100 && waitpid(pid_, &status, WNOHANG) == 0; ++i) usleep(10000);
    if (waitpid(pid_, &status, WNOHANG) == 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
  }
}

std::vector<float> WasmHandModels::Request(const char* model, const float* input, int size) {
  const std::string header = std::string(model) + "\n";
  WriteAll(header.data(), header.size());
  WriteAll(input, sizeof(float) * size * size * 3);
  const std::string line = ReadLine();
  double ms = 0;
  long count = 0;
  if (std::sscanf(line.c_str(), "%lf %ld", &ms, &count) != 2 || count < 0 || count > 1 << 20) {
    Json j = Json::parse(line, nullptr, false);
    throw Error("hand_detector_failed",
                j.is_object() ? j.value("error", line) : "unreadable answer: " + line,
                {.clip = clip_});
  }
  std::vector<float> out(static_cast<std::size_t>(count));
  ReadExact(out.data(), out.size() * sizeof(float));
  ms_ += ms;
  return out;
}

std::string WasmHandModels::ReadLine() {
  while (true) {
    const std::size_t nl = buffered_.find('\n');
    if (nl != std::string::npos) {
      std::string line = buffered_.substr(0, nl);
      buffered_.erase(0, nl + 1);
      return line;
    }
    char chunk[65536];
    const ssize_t n = read(from_child_, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw Error("hand_detector_failed", "the detector process ended unexpectedly",
                  {.clip = clip_});
    }
    buffered_.append(chunk, static_cast<std::size_t>(n));
  }
}

void WasmHandModels::ReadExact(void* data, std::size_t size) {
  char* p = static_cast<char*>(data);
  const std::size_t from_buffer = std::min(size, buffered_.size());
  std::memcpy(p, buffered_.data(), from_buffer);
  buffered_.erase(0, from_buffer);
  p += from_buffer;
  size -= from_buffer;
  while (size > 0) {
    const ssize_t n = read(from_child_, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw Error("hand_detector_failed", "the detector process ended unexpectedly",
                  {.clip = clip_});
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
}

void WasmHandModels::WriteAll(const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = write(to_child_, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw Error("hand_detector_failed",
                  std::string("cannot write to the detector: ") + std::strerror(errno),
                  {.clip = clip_});
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
}

}  // namespace

bool WasmHandModelsAvailable(std::string* why) {
  for (const char* package : kPackages) {
    if (!std::filesystem::exists(NpmDir() / "node_modules" / package / "package.json")) {
      if (why) *why = std::string("npm package ") + package + " is not in " + NpmDir().string();
      return false;
    }
  }
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    if (why) *why = "node is not installed";
    return false;
  }
  return true;
}

std::unique_ptr<HandModels> MakeWasmHandModels(const std::string& clip,
                                               const std::string& models) {
  return std::make_unique<WasmHandModels>(clip, models);
}

}  // namespace doasido::filters
