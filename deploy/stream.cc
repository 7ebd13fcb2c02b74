#include "deploy/stream.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <functional>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "deploy/lcm_log.h"
#include "doasido_lcm/arm_hand_command.hpp"

namespace doasido::deploy {
namespace {

int64_t WallMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

doasido_lcm::arm_hand_command Message(const Plan& plan, size_t k, int64_t timestamp_us) {
  doasido_lcm::arm_hand_command msg;
  msg.timestamp_us = timestamp_us;
  msg.sequence = static_cast<int64_t>(k);
  msg.plan_time = plan.times[k];
  for (int i = 0; i < 6; ++i) msg.arm_q[i] = plan.arm[k][i];
  msg.num_hand = static_cast<int32_t>(plan.hand[k].size());
  msg.hand_q.assign(plan.hand[k].data(), plan.hand[k].data() + plan.hand[k].size());
  return msg;
}

void SleepUntil(const timespec& start, double seconds) {
  timespec at = start;
  const long long ns = static_cast<long long>(seconds * 1e9 + 0.5);
  at.tv_sec += ns / 1000000000LL;
  at.tv_nsec += ns % 1000000000LL;
  if (at.tv_nsec >= 1000000000L) {
    at.tv_sec += 1;
    at.tv_nsec -= 1000000000L;
  }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
  }
}

}  // namespace

void RequireEvenlySpaced(const Plan& plan) {
  for (size_t k = 0; k < plan.times.size(); ++k) {
    if (std::abs(plan.times[k] - k / plan.rate_hz) > 1e-6) {
      throw Error("bad_plan",
                  "command " + std::to_string(k) + " is at " + std::to_string(plan.times[k]) +
                      " s, not at k / rate_hz: a plan's commands are evenly spaced (its time map, source_times, "
                      "holds the re-timing)",
                  {.file = plan.source, .field = "times"});
    }
  }
}

StreamResult StreamEncoded(size_t count, double rate, const StreamOptions& options,
                           const std::atomic<bool>& stop,
                           const std::function<std::vector<uint8_t>(size_t, int64_t)>& encode) {
  StreamResult result;
  if (!options.dry_run_log.empty()) {
    lcm::LogFile log(options.dry_run_log.string(), "w");
    if (!log.good()) throw Error("io", "cannot write LCM log", {.file = options.dry_run_log.string()});
    const int64_t start = WallMicros();
    for (size_t k = 0; k < count && !stop; ++k) {
      const int64_t t = start + static_cast<int64_t>(k * 1e6 / rate + 0.5);
      std::vector<uint8_t> buffer = encode(k, t);
      lcm::LogEvent event{};
      event.eventnum = static_cast<int64_t>(k);
      event.timestamp = t;
      event.channel = options.channel;
      event.datalen = static_cast<int32_t>(buffer.size());
      event.data = buffer.data();
      if (log.writeEvent(&event) != 0) {
        throw Error("io", "cannot write LCM log event", {.file = options.dry_run_log.string()});
      }
      ++result.sent;
    }
  } else {
    lcm::LCM lcm(options.url);
    if (!lcm.good()) throw Error("lcm", "cannot start LCM on " + options.url, {.field = "url"});
    timespec start{};
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (size_t k = 0; k < count && !stop; ++k) {
      SleepUntil(start, k / rate);
      if (stop) break;
      const std::vector<uint8_t> buffer = encode(k, WallMicros());
      if (lcm.publish(options.channel, buffer.data(), static_cast<unsigned>(buffer.size())) != 0) {
        throw Error("lcm", "publish failed on " + options.url, {.field = options.channel});
      }
      ++result.sent;
    }
  }
  result.stopped = result.sent < static_cast<int>(count);
  return result;
}

StreamResult StreamPlan(const Plan& plan, const StreamOptions& options, const std::atomic<bool>& stop) {
  if (!plan.ok) {
    throw Error("plan_failed_checks",
                "refusing to stream: the plan has " + std::to_string(plan.unreachable.size()) +
                    " unreachable frames, " + std::to_string(plan.too_fast.size()) + " too-fast, " +
                    std::to_string(plan.over_acceleration.size()) + " too-abrupt and " +
                    std::to_string(plan.path_deviation.OffPathCommands()) + " off-path commands",
                {.file = plan.source, .field = "ok"});
  }
  RequireEvenlySpaced(plan);
  const double rate = options.rate_hz > 0 ? options.rate_hz : plan.rate_hz;
  return StreamEncoded(plan.arm.size(), rate, options, stop,
                       [&](size_t k, int64_t t) { return EncodeLcm(Message(plan, k, t)); });
}

std::vector<CommandRecord> ReadCommandLog(const std::filesystem::path& path, const std::string& channel) {
  return ReadLcmLog<doasido_lcm::arm_hand_command, CommandRecord>(
      path, channel, "an arm_hand_command", [](const lcm::LogEvent& e, const doasido_lcm::arm_hand_command& msg) {
        CommandRecord r{.log_time_us = e.timestamp, .timestamp_us = msg.timestamp_us,
                        .sequence = msg.sequence, .plan_time = msg.plan_time};
        for (int i = 0; i < 6; ++i) r.arm[i] = msg.arm_q[i];
        r.hand = msg.hand_q;
        return r;
      });
}

}  // namespace doasido::deploy
