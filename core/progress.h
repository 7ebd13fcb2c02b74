// Progress of long work. On a terminal it redraws one bar on stderr
// ("ingest  [#####.....]  52%  5200/10000  1234/s  eta 4s"); otherwise
// (CI, pipes, log files) it logs a plain line at most every `log_every`
// seconds and once at the end, so logs stay readable.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace doasido {

class Progress {
 public:
  // total = 0 means unknown (no percentage or eta).
  Progress(std::string label, std::uint64_t total, double log_every_s = 5.0);
  ~Progress();  // calls Finish() if not done yet

  void Add(std::uint64_t n = 1);
  void Set(std::uint64_t done);
  void SetTotal(std::uint64_t total);
  void Finish();

  // Whether stderr is a terminal and DOASIDO_NO_PROGRESS is unset.
  static bool Interactive();

 private:
  void Draw(bool force);

  std::string label_;
  std::uint64_t total_;
  std::uint64_t done_ = 0;
  double log_every_s_;
  bool interactive_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace doasido
