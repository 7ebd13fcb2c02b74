// The review web app: a small HTTP server (cpp-httplib) over one database
// that serves the flagged-clip queue page, the clips' videos with byte
// ranges, decisions, and preference studies. See docs/review.md.
//
// Security model: it binds to loopback unless told otherwise; every
// state-changing request must carry the per-start random token embedded in
// the page (header X-Doasido-Token) and come from the server's own origin;
// requests naming another Host are refused (DNS rebinding); files are
// served only by database id, never by a path from the client.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace doasido::review {

// A reason code a reviewer can give, with the words shown for it.
struct ReasonChoice {
  std::string code;
  std::string label;
};

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = 8470;             // 0: any free port
  bool allow_remote = false;   // permit a non-loopback host
  std::string reviewer;        // default reviewer name shown on the page
  // The stages' reason codes (`doasido review serve` passes the stage
  // registry's, stages/stage_registry.h), offered before the review's own
  // (ReviewOnlyReasons), and for each filter stage the reason a rejection
  // of a clip it flagged takes by default.
  std::vector<ReasonChoice> stage_reasons;
  std::map<std::string, std::string> default_reasons;
};

// True for 127.0.0.0/8, ::1 and "localhost".
bool IsLoopbackHost(const std::string& host);

class ReviewServer {
 public:
  // Opens the database. Throws Error("remote_bind") for a non-loopback
  // host without allow_remote, and the database's errors.
  ReviewServer(const std::filesystem::path& db_path, const ServeOptions& options);
  ~ReviewServer();
  ReviewServer(const ReviewServer&) = delete;
  ReviewServer& operator=(const ReviewServer&) = delete;

  // Binds host:port (throws Error("bind") naming the address when it
  // cannot) and serves on a background thread. Returns the bound port.
  int Start();
  // Binds, calls on_listening(port), and serves on the calling thread
  // until Stop() (from another thread).
  void Serve(const std::function<void(int port)>& on_listening = {});
  void Stop();

  int port() const;
  // The per-start token state-changing requests must send.
  const std::string& token() const;
  // http://host:port, the origin the page is served from.
  std::string Origin() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace doasido::review
