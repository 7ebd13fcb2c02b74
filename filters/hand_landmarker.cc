#include "filters/hand_landmarker.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "core/config.h"
#include "core/data_dirs.h"
#include "core/error.h"

extern char** environ;

namespace doasido::filters {

extern const char kMediapipeHandsScript[];

namespace {

constexpr const char* kPackages[] = {"@mediapipe/hands", "@tensorflow/tfjs-tflite",
                                     "@tensorflow/tfjs-core", "@tensorflow/tfjs-backend-cpu"};

std::string MissingPackage() {
  for (const char* package : kPackages) {
    if (!std::filesystem::exists(NpmDir() / "node_modules" / package / "package.json")) {
      return package;
    }
  }
  return "";
}

cv::Point3d Point(const Json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}

}  // namespace

bool HandLandmarkerAvailable(std::string* why) {
  const std::string missing = MissingPackage();
  if (!missing.empty()) {
    if (why) *why = "npm package " + missing + " is not in " + NpmDir().string();
    return false;
  }
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    if (why) *why = "node is not installed";
    return false;
  }
  return true;
}

HandLandmarker::HandLandmarker(HandLandmarkerOptions options) : options_(std::move(options)) {
  std::string why;
  if (!HandLandmarkerAvailable(&why)) {
    throw Error("hand_detector_unavailable",
                why + " (scripts/setup.sh installs node and the pinned npm packages)",
                {.clip = options_.clip});
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
  std::vector<std::string> env_strings = {
      "NODE_PATH=" + (NpmDir() / "node_modules").string(),
      "DOASIDO_MAX_HANDS=" + std::to_string(options_.max_hands)};
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::strncmp(*e, "NODE_PATH=", 10) != 0) env_strings.emplace_back(*e);
  }
  std::vector<char*> env;
  for (std::string& s : env_strings) env.push_back(s.data());
  env.push_back(nullptr);
  std::string node = options_.node, flag = "-e", script = kMediapipeHandsScript;
  char* argv[] = {node.data(), flag.data(), script.data(), nullptr};
  const int spawned = posix_spawnp(&pid_, node.c_str(), &actions, nullptr, argv, env.data());
  posix_spawn_file_actions_destroy(&actions);
  close(in[0]);
  close(out[1]);
  to_child_ = in[1];
  from_child_ = out[0];
  if (spawned != 0) {
    pid_ = -1;
    throw Error("hand_detector_unavailable",
                "cannot start " + node + ": " + std::strerror(spawned), {.clip = options_.clip});
  }
  const std::string first = ReadLine();
  const Json hello = Json::parse(first, nullptr, false);
  if (hello.is_discarded() || !hello.value("ready", false)) {
    throw Error("hand_detector_unavailable",
                "the detector did not start: " +
                    (hello.is_object() ? hello.value("error", first) : first),
                {.clip = options_.clip});
  }
}

HandLandmarker::~HandLandmarker() {
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

std::string HandLandmarker::ReadLine() {
  while (true) {
    const size_t nl = buffered_.find('\n');
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
                  {.clip = options_.clip});
    }
    buffered_.append(chunk, static_cast<size_t>(n));
  }
}

void HandLandmarker::WriteAll(const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = write(to_child_, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw Error("hand_detector_failed",
                  std::string("cannot write to the detector: ") + std::strerror(errno),
                  {.clip = options_.clip});
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
}

void HandLandmarker::Reset() {
  const std::string request = "reset\n";
  WriteAll(request.data(), request.size());
}

std::vector<LandmarkedHand> HandLandmarker::Detect(const cv::Mat& bgr) {
  const double shrink =
      std::min(1.0, static_cast<double>(options_.max_side) / std::max(bgr.cols, bgr.rows));
  cv::Mat rgb;
  if (shrink < 1.0) {
    cv::Mat small;
    cv::resize(bgr, small, {}, shrink, shrink, cv::INTER_AREA);
    cv::cvtColor(small, rgb, cv::COLOR_BGR2RGB);
  } else {
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  }
  const std::int64_t id = next_id_++;
  const std::string header = "frame " + std::to_string(id) + " " + std::to_string(rgb.cols) +
                             " " + std::to_string(rgb.rows) + "\n";
  WriteAll(header.data(), header.size());
  WriteAll(rgb.data, rgb.total() * 3);
  const std::string line = ReadLine();
  std::vector<LandmarkedHand> hands;
  try {
    const Json reply = Json::parse(line);
    if (reply.contains("error")) {
      throw Error("hand_detector_failed", reply.at("error").get<std::string>(),
                  {.clip = options_.clip});
    }
    if (reply.at("id").get<std::int64_t>() != id) throw std::runtime_error("reply out of order");
    last_ms_ = reply.at("ms").get<double>();
    const double scale = 1.0 / shrink;
    for (const Json& h : reply.at("hands")) {
      LandmarkedHand hand;
      hand.score = h.at("score").get<double>();
      hand.right = h.at("right").get<double>();
      const Json& b = h.at("box");
      hand.box = cv::Rect2d(cv::Point2d(b.at(0).get<double>(), b.at(1).get<double>()) * scale,
                            cv::Point2d(b.at(2).get<double>(), b.at(3).get<double>()) * scale);
      for (int k = 0; k < kHandKeypoints; ++k) {
        hand.keypoints[k] = Point(h.at("keypoints").at(k)) * scale;
        hand.world[k] = Point(h.at("world").at(k));
      }
      hands.push_back(hand);
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("hand_detector_failed",
                std::string("unreadable answer from the detector: ") + e.what(),
                {.clip = options_.clip});
  }
  return hands;
}

}  // namespace doasido::filters
