// The simulation rollouts' thread pool: a TaskPool (core/task_pool.h) with
// one read-only mjModel shared by every thread and one mjData per thread,
// made once (mj_makeData allocates; a rollout must not).
#pragma once

#include <functional>
#include <vector>

#include "core/task_pool.h"
#include "robot/mj_model.h"

namespace doasido::retarget {

class RolloutPool {
 public:
  // `threads` >= 1 counts the calling thread. `m` must outlive the pool.
  RolloutPool(const mjModel* m, int threads);

  int threads() const { return pool_.threads(); }
  // The scratch mjData of thread `i` (0 = the calling thread).
  mjData* data(int i) { return data_[i].get(); }

  // TaskPool::Run: task(index, thread) for index in [0, n); exceptions rethrown.
  void Run(int n, const std::function<void(int index, int thread)>& task) { pool_.Run(n, task); }

 private:
  std::vector<DataPtr> data_;
  TaskPool pool_;
};

}  // namespace doasido::retarget
