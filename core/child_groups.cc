#include "core/child_groups.h"

#include <signal.h>

#include <mutex>
#include <set>

namespace doasido {
namespace {

std::mutex& Mutex() {
  static std::mutex m;
  return m;
}

std::set<pid_t>& Groups() {
  static std::set<pid_t> groups;
  return groups;
}

}  // namespace

void AddChildGroup(pid_t group) {
  std::lock_guard lock(Mutex());
  Groups().insert(group);
}

void RemoveChildGroup(pid_t group) {
  std::lock_guard lock(Mutex());
  Groups().erase(group);
}

void KillChildGroups() {
  std::lock_guard lock(Mutex());
  for (const pid_t group : Groups()) ::kill(-group, SIGKILL);
}

}  // namespace doasido
