// A fixed pool of threads for batches of independent tasks, in the manner of
// MuJoCo MPC's planners: the threads are made once, and tasks 0..n-1 are
// claimed from an atomic counter by the calling thread and the workers. A
// task's result must depend only on its index (never on which thread ran
// it); that makes a run deterministic for any thread count. Per-thread
// scratch (an mjData, a ray caster) is indexed by the `thread` argument.
#pragma once

#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace doasido {

class TaskPool {
 public:
  // `threads` >= 1 counts the calling thread (1 = no worker threads).
  explicit TaskPool(int threads);
  ~TaskPool();
  TaskPool(const TaskPool&) = delete;
  TaskPool& operator=(const TaskPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Runs task(index, thread) for index in [0, n) on all threads (thread 0 is
  // the caller) and returns when every task is done. The first exception
  // thrown by a task is rethrown here (the remaining tasks still run). Not
  // reentrant: one Run at a time.
  void Run(int n, const std::function<void(int index, int thread)>& task);

 private:
  void Work(int thread);
  void Drain(int thread);

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

}  // namespace doasido
