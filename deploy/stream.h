// `doasido deploy stream`: publishes a plan's commands (plan.h) as LCM
// messages doasido_lcm::arm_hand_command (deploy/arm_hand_command.lcm) on
// one channel, paced in real time at the plan's rate: command k is sent at
// start + k / rate on the monotonic clock (absolute sleeps, so the rate has
// no drift). With a dry-run log the messages go to an LCM log file
// instead (event times are the planned send times; nothing is sent and
// nothing waits).
#pragma once

#include <atomic>
#include <functional>
#include <filesystem>
#include <string>
#include <vector>

#include "deploy/plan.h"

namespace doasido::deploy {

// Loopback only: ttl=0 keeps multicast on this machine.
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
inline constexpr const char* kCommandChannel = "DOASIDO_COMMAND";

struct StreamOptions {
  std::string url = kDefaultLcmUrl;
  std::string channel = kCommandChannel;
  double rate_hz = 0;                  // 0 = the plan's rate
  std::filesystem::path dry_run_log;   // non-empty: write this LCM log instead of publishing
};

struct StreamResult {
  int sent = 0;
  bool stopped = false;  // `stop` was raised before the last command
};

// Throws Error("plan_failed_checks") for a plan that is not ok (nothing is
// sent), Error("lcm") when LCM cannot start or publish, Error("io") for an
// unwritable log. Returns early, cleanly, when `stop` becomes true.
StreamResult StreamPlan(const Plan& plan, const StreamOptions& options, const std::atomic<bool>& stop);

// Throws Error("bad_plan") unless command k is at k / rate_hz: the stream
// paces commands evenly, so a plan's times must be (re-timing changes which
// trajectory time each command holds, not the command spacing).
void RequireEvenlySpaced(const Plan& plan);

// An lcm-gen message's bytes.
template <typename Message>
std::vector<uint8_t> EncodeLcm(const Message& msg) {
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
  return buffer;
}

// The engine under StreamPlan (and the two-arm stream, bimanual.h): sends
// `count` messages, message k's bytes from encode(k, timestamp_us), paced
// at `rate` Hz, or writes them to options.dry_run_log. Throws as StreamPlan.
StreamResult StreamEncoded(size_t count, double rate, const StreamOptions& options,
                           const std::atomic<bool>& stop,
                           const std::function<std::vector<uint8_t>(size_t, int64_t)>& encode);

// One decoded command, as read back from an LCM log.
struct CommandRecord {
  int64_t log_time_us = 0;  // the log event's timestamp
  int64_t timestamp_us = 0;
  int64_t sequence = 0;
  double plan_time = 0;
  ArmQ arm = ArmQ::Zero();
  std::vector<double> hand;
};

// Every event on `channel` in an LCM log file (lcm-logger's or the dry
// run's), decoded. Throws Error("bad_log") naming the file.
std::vector<CommandRecord> ReadCommandLog(const std::filesystem::path& path,
                                          const std::string& channel = kCommandChannel);

}  // namespace doasido::deploy
