// A fixed set of worker threads that run one job over index ranges, for the per-camera steps of
// NetworkedObserver. The calling thread takes part, so a pool of size 1 starts no thread and runs
// everything in the caller, in index order.
//
// Determinism: for_each(count, f) splits [0, count) into size() contiguous chunks whose bounds
// depend on count and size() only, and every call is a barrier. A job whose iterations touch
// disjoint state (camera i writes only camera i's state) therefore gives bit-identical results
// for any pool size.
#pragma once

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
  /// size - 1 worker threads (size >= 1; 0 means std::thread::hardware_concurrency()).
  explicit WorkerPool(int size);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  /// Calls f(i) for every i in [0, count), chunk t = [count t / T, count (t + 1) / T) of the
  /// T = min(size(), parts) chunks on thread t (0: the caller), and returns when all are done.
  /// A chunk stops at its first exception; after all chunks have finished, the exception of
  /// the smallest index is rethrown (with T = 1: exactly a plain loop).
  void for_each(int count, int parts, const std::function<void(int)>& f);

 private:
  void work(int t);
  void run_chunk(int t);

  std::mutex mu_;
  std::condition_variable start_, done_;
  std::uint64_t generation_ = 0;  ///< counts jobs; a worker runs each generation once
  int pending_ = 0;               ///< workers still running the current job
  bool stop_ = false;
  // The current job.
  const std::function<void(int)>* job_ = nullptr;
  int count_ = 0, parts_ = 1;
  std::vector<std::exception_ptr> errors_;  ///< per chunk: its first exception
  std::vector<std::thread> workers_;
};

}  // namespace netvmo::obs
