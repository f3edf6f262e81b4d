// A fixed set of worker threads that run one job over index ranges, for the per-camera steps of
// NetworkedObserver. The calling thread takes part, so a pool of size 1 starts no thread and runs
// everything in the caller, in index order.
//
// Determinism: for_each(count, parts, f) splits [0, count) into T = min(size(), parts)
// contiguous parts whose bounds depend on count and T only, and every call is a barrier. Thread t
// runs part t in small grains from its start, then takes the grains the others have not reached
// yet (so a thread that a virtual machine slows down, or that got the costlier cameras, does not
// hold up the barrier). Which thread runs an index varies, what f(i) computes does not: a job
// whose iterations touch disjoint state (camera i writes only camera i's state) gives
// bit-identical results for any pool size.
//
// Waiting: a frame of the observer is ~15 jobs of well under a millisecond each, so the time a
// sleeping thread takes to wake (a futex wake-up is tens of microseconds on a virtual machine)
// would eat the second core's gain. A waiting thread (a worker between jobs, the caller for the
// workers' parts) therefore first polls for up to `spin` (the constructor's), then blocks on
// a condition variable. The spin is bounded in time, so a loaded machine loses at most that much
// CPU per job and never waits on a spinning thread for longer.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace netvmo::obs {

class WorkerPool {
 public:
  /// How long a waiting thread polls before it blocks (see above).
  static constexpr std::chrono::microseconds kDefaultSpin{200};

  /// size - 1 worker threads (size >= 1; 0 means std::thread::hardware_concurrency()).
  explicit WorkerPool(int size, std::chrono::microseconds spin = kDefaultSpin);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  /// Calls f(i) exactly once for every i in [0, count), on the T = min(size(), parts) threads
  /// (0: the caller; see above), and returns when all are done. A part stops at its first
  /// exception: the thread that caught it runs no more of its grain, and no thread claims a grain
  /// of that part once it has seen the exception; after all threads have finished, the exception
  /// of the smallest index is rethrown (with T = 1: exactly a plain loop).
  void for_each(int count, int parts, const std::function<void(int)>& f);

 private:
  void work(int t);
  void run_parts(int t);
  void drain(int part);
  /// Polls `ready` for up to spin_, then blocks on `cv` under mu_ until it holds.
  template <class Ready>
  void wait_for(std::condition_variable& cv, Ready ready);

  const std::chrono::microseconds spin_;
  std::mutex mu_;
  std::condition_variable start_, done_;
  std::atomic<std::uint64_t> generation_{0};  ///< counts jobs; a worker runs each generation once
  std::atomic<int> pending_{0};  ///< workers not yet done with the current job (all count)
  std::atomic<bool> stop_{false};
  // The current job (written before generation_ is advanced, read after it is seen).
  const std::function<void(int)>* job_ = nullptr;
  int parts_ = 1, grain_ = 1;
  /// Part t of the current job: the next index not yet claimed, its end, and whether an index of
  /// it threw. One cache line each, so that claiming a grain of one's own part shares nothing.
  struct alignas(64) Part {
    std::atomic<int> next{0};
    int end = 0;
    std::atomic<bool> failed{false};
  };
  std::vector<Part> parts_state_;
  std::mutex error_mu_;
  std::exception_ptr error_;  ///< the exception of the smallest index that threw (under error_mu_)
  int error_index_ = 0;
  std::vector<std::thread> workers_;
};

}  // namespace netvmo::obs
