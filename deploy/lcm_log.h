// Reading back what `deploy stream` published, from an lcm-logger file: the
// one loop both message types (arm_hand_command, bimanual_command) share.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/error.h"

namespace doasido::deploy {

// Every event on `channel` of the log at `path`, decoded as a Message and
// turned into a Record by `record(event, message)`, in log order. Throws
// Error("bad_log") for an unreadable log or an event that does not decode;
// `what` names the message type with its article ("an arm_hand_command").
template <typename Message, typename Record, typename ToRecord>
std::vector<Record> ReadLcmLog(const std::filesystem::path& path, const std::string& channel,
                               const std::string& what, ToRecord record) {
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) throw Error("bad_log", "cannot read LCM log", {.file = path.string()});
  std::vector<Record> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != channel) continue;
    Message msg;
    if (msg.decode(e->data, 0, e->datalen) < 0) {
      throw Error("bad_log", "event " + std::to_string(e->eventnum) + " is not " + what,
                  {.file = path.string(), .field = channel});
    }
    out.push_back(record(*e, msg));
  }
  return out;
}

}  // namespace doasido::deploy
