// Process groups this process started and still owns (model commands run in
// groups of their own so a timeout reaches every descendant). A worker that
// ends itself because a stage hung (pipeline/worker.h) kills them first, so
// nothing it started outlives it.
#pragma once

#include <sys/types.h>

namespace doasido {

void AddChildGroup(pid_t group);
void RemoveChildGroup(pid_t group);
// Sends SIGKILL to every group still registered.
void KillChildGroups();

}  // namespace doasido
