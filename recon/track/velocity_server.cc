#include "recon/track/velocity_server.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "core/child_groups.h"
#include "core/error.h"
#include "core/json_input.h"
#include "core/stage_progress.h"
#include "recon/bundle/model_command.h"

namespace doasido::recon {
namespace {

constexpr std::uint32_t kMaxHeader = 1 << 20;
constexpr std::uint32_t kMaxPayload = 1u << 30;

// Writes all of `bytes`; false when the reader is gone. SIGPIPE is blocked
// for this thread meanwhile and a pending one is taken back, so a dead
// server is an error, not the end of doasido.
bool WriteAll(int fd, const void* bytes, size_t size) {
  sigset_t pipe_signal, old;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_signal, &old);
  const auto* p = static_cast<const char*>(bytes);
  bool ok = true;
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ok = false;
      break;
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
  if (!ok) {
    const timespec zero{0, 0};
    sigtimedwait(&pipe_signal, nullptr, &zero);
  }
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return ok;
}

// Reads exactly `size` bytes; false at end of file or on an error.
bool ReadAll(int fd, void* bytes, size_t size) {
  auto* p = static_cast<char*>(bytes);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

std::uint32_t LittleEndian(const unsigned char b[4]) {
  return b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
}

}  // namespace

VelocityServer::VelocityServer(const std::string& command, const std::filesystem::path& log)
    : command_(command), log_(log) {
  int in[2], out[2];
  const int err = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (err < 0) throw Error("io", "cannot create the model server's log", {.file = log.string()});
  if (::pipe2(in, O_CLOEXEC) != 0 || ::pipe2(out, O_CLOEXEC) != 0) {
    ::close(err);
    throw Error("io", "cannot make pipes for the model server");
  }
  pid_ = ::fork();
  if (pid_ == 0) {
    ::setpgid(0, 0);
    ::dup2(in[0], STDIN_FILENO);
    ::dup2(out[1], STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(in[0]);
  ::close(out[1]);
  ::close(err);
  to_server_ = in[1];
  from_server_ = out[0];
  if (pid_ < 0) Fail("io", "fork failed");
  ::setpgid(pid_, pid_);
  AddChildGroup(pid_);

  std::vector<double> none;
  Send({{"type", "hello"}, {"protocol", kVelocityProtocol}}, nullptr);
  const Json hello = Receive(&none);
  if (hello.value("type", "") != "hello") Fail(kServerProtocol, "the first answer is not a hello");
  if (hello.value("protocol", -1) != kVelocityProtocol) {
    Fail(kServerVersion, "the server speaks protocol " + hello.value("protocol", Json()).dump() +
                             ", doasido " + std::to_string(kVelocityProtocol));
  }
  try {
    layout_.shape_dim = hello.at("shape_dim").get<int>();
    layout_.pose_dim = hello.at("pose_dim").get<int>();
    frames_ = hello.at("frames").get<int>();
    divergence_ = hello.value("divergence", false);
  } catch (const Json::exception& e) {
    Fail(kServerProtocol, std::string("the hello lacks shape_dim, pose_dim or frames: ") + e.what());
  }
  if (layout_.pose_dim != kPoseDim || layout_.shape_dim < 0 || frames_ < 1) {
    Fail(kServerProtocol, "the hello's layout is not shape_dim >= 0, pose_dim 7, frames >= 1");
  }
}

VelocityServer::~VelocityServer() {
  if (to_server_ >= 0) {
    const Json bye = {{"type", "bye"}};
    const std::string header = bye.dump();
    unsigned char lengths[8] = {0};
    const auto n = static_cast<std::uint32_t>(header.size());
    for (int i = 0; i < 4; ++i) lengths[i] = static_cast<unsigned char>(n >> (8 * i));
    WriteAll(to_server_, lengths, 4) && WriteAll(to_server_, header.data(), header.size()) &&
        WriteAll(to_server_, lengths + 4, 4);
    ::close(to_server_);
  }
  if (from_server_ >= 0) ::close(from_server_);
  if (pid_ > 0) {
    // A polite server has exited on bye; give it a moment, then end the group.
    for (int i = 0; i < 50 && ::waitpid(pid_, nullptr, WNOHANG) == 0; ++i) ::usleep(10000);
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, nullptr, WNOHANG);
    RemoveChildGroup(pid_);
  }
}

void VelocityServer::Fail(const std::string& code, const std::string& message) {
  std::string text = message + " (model server `" + command_ + "`";
  int status = 0;
  if (code == kServerDied && pid_ > 0) {
    for (int i = 0; i < 50 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i) ::usleep(10000);
    if (WIFEXITED(status)) text += ", exit code " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status)) text += ", killed by signal " + std::to_string(WTERMSIG(status));
  }
  text += "; its log " + log_.string() + ")";
  const std::string tail = LogTail(log_, 5);
  if (!tail.empty()) text += ":\n" + tail;
  throw Error(code, text, {.file = log_.string()});
}

void VelocityServer::Send(const Json& header, const StateMatrix* payload) {
  const std::string text = header.dump();
  const auto payload_bytes = payload ? payload->size() * sizeof(double) : 0;
  unsigned char h[4], p[4];
  for (int i = 0; i < 4; ++i) {
    h[i] = static_cast<unsigned char>(text.size() >> (8 * i));
    p[i] = static_cast<unsigned char>(payload_bytes >> (8 * i));
  }
  const bool ok = WriteAll(to_server_, h, 4) && WriteAll(to_server_, text.data(), text.size()) &&
                  WriteAll(to_server_, p, 4) &&
                  (!payload || WriteAll(to_server_, payload->data(), payload_bytes));
  if (!ok) Fail(kServerDied, "the model server stopped reading");
}

Json VelocityServer::Receive(std::vector<double>* payload) {
  unsigned char length[4];
  if (!ReadAll(from_server_, length, 4)) Fail(kServerDied, "the model server closed its output");
  const std::uint32_t header_size = LittleEndian(length);
  if (header_size == 0 || header_size > kMaxHeader) {
    Fail(kServerProtocol, "a header length of " + std::to_string(header_size) + " bytes");
  }
  std::string header(header_size, '\0');
  if (!ReadAll(from_server_, header.data(), header_size) || !ReadAll(from_server_, length, 4)) {
    Fail(kServerDied, "the model server closed its output mid-answer");
  }
  const std::uint32_t payload_size = LittleEndian(length);
  if (payload_size % sizeof(double) != 0 || payload_size > kMaxPayload) {
    Fail(kServerProtocol, "a payload of " + std::to_string(payload_size) + " bytes");
  }
  payload->resize(payload_size / sizeof(double));
  if (!ReadAll(from_server_, payload->data(), payload_size)) {
    Fail(kServerDied, "the model server closed its output mid-answer");
  }
  Json parsed;
  try {
    parsed = ParseJsonInput(header, {}, {.max_depth = 8, .max_bytes = kMaxHeader});
  } catch (const Error& e) {
    Fail(kServerProtocol, std::string("a header that is not JSON: ") + e.what());
  }
  if (!parsed.is_object()) Fail(kServerProtocol, "a header that is not a JSON object");
  if (parsed.value("type", "") == "error") {
    Fail(kServerError, "the model server says: " + parsed.value("message", std::string("?")));
  }
  return parsed;
}

StateMatrix VelocityServer::Ask(const Json& header, const StateMatrix* payload,
                                const std::string& type, Eigen::Index rows, Eigen::Index cols) {
  Send(header, payload);
  std::vector<double> values;
  const Json answer = Receive(&values);
  if (answer.value("type", "") != type || answer.value("rows", -1) != rows ||
      answer.value("cols", -1) != cols || static_cast<Eigen::Index>(values.size()) != rows * cols) {
    Fail(kServerProtocol, "asked for " + type + " of " + std::to_string(rows) + " x " +
                              std::to_string(cols) + ", got " + answer.dump().substr(0, 120) +
                              " with " + std::to_string(values.size()) + " values");
  }
  for (double v : values) {
    if (!std::isfinite(v)) Fail(kServerProtocol, "a " + type + " answer holds NaN or infinity");
  }
  ReportStageProgress();
  return Eigen::Map<const StateMatrix>(values.data(), rows, cols);
}

void VelocityServer::Velocity(int frame, double t, const StateMatrix& x, StateMatrix* v) {
  *v = Ask({{"type", "velocity"}, {"frame", frame}, {"t", t}, {"rows", x.rows()}, {"cols", x.cols()}},
           &x, "velocity", x.rows(), layout_.dim());
}

void VelocityServer::PoseDivergence(int frame, double t, const StateMatrix& x,
                                    Eigen::VectorXd* div) {
  if (!divergence_) VelocityField::PoseDivergence(frame, t, x, div);
  const StateMatrix d = Ask({{"type", "divergence"}, {"frame", frame}, {"t", t},
                             {"rows", x.rows()}, {"cols", x.cols()}},
                            &x, "divergence", x.rows(), 1);
  *div = d.col(0);
}

}  // namespace doasido::recon
