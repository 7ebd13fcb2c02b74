// A model that stays loaded: a long-lived command that a worker starts once
// and feeds clips to, instead of starting a command per clip (whose model
// load would be paid by every clip). The line protocol (docs/clip_bundle.md,
// "Server mode"; tools/bundle_server.py is a working reference):
//
//   - doasido starts the command with /bin/sh in its own process group; its
//     stdin and stdout are pipes to doasido, its stderr goes to the server
//     log (appended).
//   - Once its model is loaded the server prints one line
//       {"type": "ready"}
//     within start_timeout_s.
//   - Per clip doasido writes one line, a JSON object with the command
//     mode's placeholders as keys:
//       {"type": "clip", "clip": "c0007", "video": "/abs/v.mp4",
//        "first_frame": 0, "last_frame": -1, "fps": 30.0,
//        "output": "/abs/artifacts/7/bundle"}
//     and the server answers with one line:
//       {"type": "done", "clip": "c0007", "bundle": "<output>"}    or
//       {"type": "error", "clip": "c0007", "message": "...", "permanent": false}
//   - Any other stdout line (a library printing) is appended to the log.
//   - When doasido closes the server's stdin the server exits; a server
//     still running 5 s later is killed with its group.
// A request that outlives its budget, a server that dies or answers out of
// protocol: the whole group is killed and the next request starts a fresh
// server. Progress (core/stage_progress.h) is reported whenever the log
// grows or a line arrives, so the worker's no-progress watch sees a live
// server.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include "core/config.h"

namespace doasido::recon {

struct ServerReply {
  enum class Kind {
    kDone,       // the server answered "done"
    kError,      // the server answered "error"
    kDied,       // the server exited (or closed stdout) before answering
    kTimedOut,   // no answer within the budget: the server was killed
    kProtocol,   // an answer out of protocol: the server was killed
  };
  Kind kind = Kind::kDied;
  Json message = Json::object();  // the reply line (kDone, kError)
  std::string detail;             // what happened, for kDied/kTimedOut/kProtocol
  std::string log_tail;           // the server log's last lines
};

class ModelServer {
 public:
  // `command` runs under /bin/sh; `log` collects its stderr.
  ModelServer(std::string command, std::filesystem::path log, double start_timeout_s,
              int tail_lines);
  ~ModelServer();  // closes stdin, waits up to 5 s, then kills the group
  ModelServer(const ModelServer&) = delete;
  ModelServer& operator=(const ModelServer&) = delete;

  // Sends one request line and waits up to timeout_s for its reply. Starts
  // the server first when none is running (its ready line has its own
  // budget, start_timeout_s). Throws Error("io") only when the process
  // cannot be started at all.
  ServerReply Request(const Json& request, double timeout_s);

  // Servers started by this object so far.
  int starts() const { return starts_; }
  const std::filesystem::path& log() const { return log_; }

 private:
  void Start();
  void Stop(bool kill_now);
  // Reads stdout until a protocol line arrives, the process ends or the
  // deadline passes.
  ServerReply Await(std::chrono::steady_clock::time_point deadline, const std::string& waiting_for);
  ServerReply Fail(ServerReply::Kind kind, std::string detail);

  std::string command_;
  std::filesystem::path log_;
  double start_timeout_s_;
  int tail_lines_;
  pid_t pid_ = -1;
  int to_server_ = -1, from_server_ = -1;
  std::string pending_;  // stdout bytes after the last full line
  std::uintmax_t log_size_ = 0;
  int starts_ = 0;
};

}  // namespace doasido::recon
