#include "core/progress.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include <spdlog/spdlog.h>

#include "core/stage_progress.h"

namespace doasido {

bool Progress::Interactive() {
  return isatty(STDERR_FILENO) && std::getenv("DOASIDO_NO_PROGRESS") == nullptr;
}

Progress::Progress(std::string label, std::uint64_t total, double log_every_s)
    : label_(std::move(label)),
      total_(total),
      log_every_s_(log_every_s),
      interactive_(Interactive()),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { Finish(); }

void Progress::Add(std::uint64_t n) { Set(done_ + n); }

void Progress::Set(std::uint64_t done) {
  if (done != done_) ReportStageProgress();
  done_ = done;
  Draw(false);
}

void Progress::SetTotal(std::uint64_t total) { total_ = total; }

void Progress::Finish() {
  if (finished_) return;
  Draw(true);
  if (interactive_) std::fputc('\n', stderr);
  finished_ = true;
}

void Progress::Draw(bool force) {
  const auto now = std::chrono::steady_clock::now();
  const double since_draw = std::chrono::duration<double>(now - last_draw_).count();
  const double interval = interactive_ ? 0.1 : log_every_s_;
  if (!force && since_draw < interval) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  char tail[128];
  if (total_ > 0) {
    const double frac = std::min(1.0, static_cast<double>(done_) / total_);
    const double eta = rate > 0 ? (total_ - std::min(done_, total_)) / rate : 0.0;
    std::snprintf(tail, sizeof tail, "%3.0f%%  %llu/%llu  %.0f/s  eta %.0fs", 100 * frac,
                  static_cast<unsigned long long>(done_), static_cast<unsigned long long>(total_),
                  rate, eta);
    if (interactive_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(frac * kWidth);
      std::string bar(filled, '#');
      bar.append(kWidth - filled, '.');
      std::fprintf(stderr, "\r%-10s [%s] %s ", label_.c_str(), bar.c_str(), tail);
      std::fflush(stderr);
      return;
    }
  } else {
    std::snprintf(tail, sizeof tail, "%llu done  %.0f/s", static_cast<unsigned long long>(done_),
                  rate);
    if (interactive_) {
      std::fprintf(stderr, "\r%-10s %s ", label_.c_str(), tail);
      std::fflush(stderr);
      return;
    }
  }
  spdlog::info("{}: {}", label_, tail);
}

}  // namespace doasido
