#include "recon/bundle/model_server.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <thread>
#include <utility>

#include "core/child_groups.h"
#include "core/error.h"
#include "core/stage_progress.h"
#include "recon/bundle/model_command.h"

namespace doasido::recon {
namespace {

using Clock = std::chrono::steady_clock;

void AppendToLog(const std::filesystem::path& log, const std::string& text) {
  std::ofstream(log, std::ios::app) << text << "\n";
}

std::string ExitText(int status) {
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
}

}  // namespace

ModelServer::ModelServer(std::string command, std::filesystem::path log, double start_timeout_s,
                         int tail_lines)
    : command_(std::move(command)),
      log_(std::move(log)),
      start_timeout_s_(start_timeout_s),
      tail_lines_(tail_lines) {}

ModelServer::~ModelServer() { Stop(false); }

void ModelServer::Start() {
  std::filesystem::create_directories(log_.parent_path());
  const int log_fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) throw Error("io", "cannot open the model server log", {.file = log_.string()});
  int in[2], out[2];
  if (::pipe2(in, O_CLOEXEC) != 0 || ::pipe2(out, O_CLOEXEC) != 0) {
    ::close(log_fd);
    throw Error("io", "cannot make pipes for the model server", {.file = log_.string()});
  }
  ++starts_;
  AppendToLog(log_, "---- doasido: starting model server (start " + std::to_string(starts_) +
                        " in worker " + std::to_string(::getpid()) + "): " + command_);
  const pid_t pid = ::fork();
  if (pid < 0) throw Error("io", "fork failed", {.file = log_.string()});
  if (pid == 0) {
    ::setpgid(0, 0);  // its own group, so a kill reaches every descendant
    ::dup2(in[0], STDIN_FILENO);
    ::dup2(out[1], STDOUT_FILENO);
    ::dup2(log_fd, STDERR_FILENO);
    ::execl("/bin/sh", "sh", "-c", command_.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  AddChildGroup(pid);
  ::close(log_fd);
  ::close(in[0]);
  ::close(out[1]);
  pid_ = pid;
  to_server_ = in[1];
  from_server_ = out[0];
  pending_.clear();
  // A server that dies must not take this process with it through SIGPIPE.
  ::signal(SIGPIPE, SIG_IGN);
}

void ModelServer::Stop(bool kill_now) {
  if (pid_ < 0) return;
  if (to_server_ >= 0) ::close(to_server_);  // EOF: the server's cue to exit
  to_server_ = -1;
  int status = 0;
  const auto give_up = Clock::now() + std::chrono::seconds(kill_now ? 0 : 5);
  while (::waitpid(pid_, &status, WNOHANG) == 0 && Clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid_, SIGKILL);  // the group: descendants too
  ::waitpid(pid_, &status, 0);
  RemoveChildGroup(pid_);
  if (from_server_ >= 0) ::close(from_server_);
  from_server_ = -1;
  pid_ = -1;
}

ServerReply ModelServer::Fail(ServerReply::Kind kind, std::string detail) {
  Stop(true);
  ServerReply reply{.kind = kind, .detail = std::move(detail)};
  AppendToLog(log_, "---- doasido: " + reply.detail);
  reply.log_tail = LogTail(log_, tail_lines_);
  return reply;
}

ServerReply ModelServer::Await(Clock::time_point deadline, const std::string& waiting_for) {
  std::error_code ignored;
  while (true) {
    // A full line may already be buffered.
    for (auto eol = pending_.find('\n'); eol != std::string::npos; eol = pending_.find('\n')) {
      const std::string line = pending_.substr(0, eol);
      pending_.erase(0, eol + 1);
      ReportStageProgress();
      Json message = Json::parse(line, nullptr, false);
      if (!message.is_object() || !message.contains("type") || !message["type"].is_string()) {
        AppendToLog(log_, line);  // a library printing to stdout
        continue;
      }
      return ServerReply{.kind = ServerReply::Kind::kDone, .message = std::move(message)};
    }
    const std::uintmax_t size = std::filesystem::file_size(log_, ignored);
    if (!ignored && size != log_size_) {
      log_size_ = size;
      ReportStageProgress();
    }
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero()) {
      return Fail(ServerReply::Kind::kTimedOut, "no answer in time while " + waiting_for +
                                                    ": the server was killed");
    }
    pollfd p{from_server_, POLLIN, 0};
    const int ready = ::poll(&p, 1, 50);
    if (ready < 0 && errno != EINTR) return Fail(ServerReply::Kind::kDied, "poll failed");
    if (ready <= 0) continue;
    char buffer[4096];
    const ssize_t n = ::read(from_server_, buffer, sizeof buffer);
    if (n > 0) {
      pending_.append(buffer, static_cast<size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    // EOF: the server ended (or closed its stdout, which is as good as dead).
    int status = 0;
    const auto wait_until = Clock::now() + std::chrono::seconds(1);
    pid_t r = 0;
    while ((r = ::waitpid(pid_, &status, WNOHANG)) == 0 && Clock::now() < wait_until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    const std::string how = r == pid_ ? ExitText(status) : "closed its stdout";
    if (r == pid_) {
      ::kill(-pid_, SIGKILL);  // descendants it left behind
      RemoveChildGroup(pid_);
      ::close(from_server_);
      if (to_server_ >= 0) ::close(to_server_);
      from_server_ = to_server_ = -1;
      pid_ = -1;
    }
    return Fail(ServerReply::Kind::kDied,
                std::string("the model server ended (") + how + ") while " + waiting_for);
  }
}

ServerReply ModelServer::Request(const Json& request, double timeout_s) {
  if (pid_ < 0) {
    Start();
    ServerReply ready = Await(Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                 std::chrono::duration<double>(start_timeout_s_)),
                              "doasido waited for its ready line");
    if (ready.kind != ServerReply::Kind::kDone) return ready;
    if (ready.message["type"] != "ready") {
      return Fail(ServerReply::Kind::kProtocol,
                  "expected {\"type\": \"ready\"} first, got " + ready.message.dump());
    }
  }
  const std::string line = request.dump() + "\n";
  for (size_t sent = 0; sent < line.size();) {
    const ssize_t n = ::write(to_server_, line.data() + sent, line.size() - sent);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Fail(ServerReply::Kind::kDied, "the model server stopped reading its stdin");
    sent += static_cast<size_t>(n);
  }
  const std::string clip = request.at("clip");
  ServerReply reply = Await(Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(timeout_s)),
                            "it held clip " + clip);
  if (reply.kind != ServerReply::Kind::kDone) return reply;
  const std::string type = reply.message["type"];  // a string: Await checked
  if (type == "error") {
    reply.kind = ServerReply::Kind::kError;
    reply.log_tail = LogTail(log_, tail_lines_);
    return reply;
  }
  const Json& replied_clip = reply.message["clip"];
  if (type != "done" || !replied_clip.is_string() || replied_clip != clip) {
    return Fail(ServerReply::Kind::kProtocol,
                "expected {\"type\": \"done\" or \"error\", \"clip\": \"" + clip + "\"}, got " +
                    reply.message.dump());
  }
  return reply;
}

}  // namespace doasido::recon
