// A fixed pool of threads for simulation rollouts, in the manner of MuJoCo
// MPC's planners: one read-only mjModel shared by every thread and one
// mjData per thread, made once (mj_makeData allocates; a rollout must not).
// Tasks 0..n-1 are claimed from an atomic counter by the calling thread and
// the workers; a task's result must depend only on its index (never on
// which thread ran it), which makes a run deterministic for any thread count.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "retarget/mj_model.h"

namespace doasido::retarget {

class RolloutPool {
 public:
  // `threads` >= 1 counts the calling thread. `m` must outlive the pool.
  RolloutPool(const mjModel* m, int threads);
  ~RolloutPool();
  RolloutPool(const RolloutPool&) = delete;
  RolloutPool& operator=(const RolloutPool&) = delete;

  int threads() const { return static_cast<int>(data_.size()); }
  // The scratch mjData of thread `i` (0 = the calling thread).
  mjData* data(int i) { return data_[i].get(); }

  // Runs task(index, thread) for index in [0, n) on all threads and returns
  // when every task is done. The first exception thrown by a task is
  // rethrown here (the remaining tasks still run).
  void Run(int n, const std::function<void(int index, int thread)>& task);

 private:
  void Work(int thread);
  void Drain(int thread);

  std::vector<DataPtr> data_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int, int)>* task_ = nullptr;
  int n_ = 0;
  std::atomic<int> next_{0};
  int busy_ = 0;
  long generation_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace doasido::retarget
