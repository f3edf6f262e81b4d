#include "netvmo/observer/worker_pool.hpp"

#include <algorithm>

namespace netvmo::obs {

namespace {
// A hint to the core that this is a polling loop (x86 PAUSE), so the poll yields the pipeline
// and draws less power; elsewhere nothing.
inline void relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}
}  // namespace

WorkerPool::WorkerPool(int size, std::chrono::microseconds spin) : spin_(spin) {
  if (size <= 0) size = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  errors_.resize(static_cast<size_t>(size));
  workers_.reserve(static_cast<size_t>(size - 1));
  for (int t = 1; t < size; ++t) workers_.emplace_back([this, t] { work(t); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_.store(true);
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
}

template <class Ready>
void WorkerPool::wait_for(std::condition_variable& cv, Ready ready) {
  if (ready()) return;
  if (spin_.count() > 0) {
    const auto until = std::chrono::steady_clock::now() + spin_;
    do {
      for (int k = 0; k < 64; ++k) {
        relax();
        if (ready()) return;
      }
    } while (std::chrono::steady_clock::now() < until);
  }
  // The state a waiter tests changes under mu_ whenever it is to wake one (for_each advances
  // generation_ under it, the last worker to finish takes it before notifying), so a wake-up
  // cannot fall between the test and the wait.
  std::unique_lock<std::mutex> lock(mu_);
  cv.wait(lock, ready);
}

void WorkerPool::run_chunk(int t) {
  const auto begin = static_cast<int>(static_cast<std::int64_t>(count_) * t / parts_);
  const auto end = static_cast<int>(static_cast<std::int64_t>(count_) * (t + 1) / parts_);
  for (int i = begin; i < end; ++i) {
    try {
      (*job_)(i);
    } catch (...) {
      errors_[static_cast<size_t>(t)] = std::current_exception();
      return;
    }
  }
}

void WorkerPool::work(int t) {
  std::uint64_t seen = 0;
  for (;;) {
    std::uint64_t now = seen;
    wait_for(start_, [&] {
      now = generation_.load(std::memory_order_acquire);
      return stop_.load(std::memory_order_acquire) || now != seen;
    });
    if (stop_.load(std::memory_order_acquire)) return;
    seen = now;
    // Every worker counts in the job's barrier, a chunk or not, so that the caller cannot set up
    // the next job while one still reads this one's fields.
    if (t < parts_) run_chunk(t);
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard<std::mutex> lock(mu_);  // see wait_for
      done_.notify_one();
    }
  }
}

void WorkerPool::for_each(int count, int parts, const std::function<void(int)>& f) {
  parts = std::clamp(parts, 1, size());
  if (parts == 1) {  // a plain loop in the caller
    for (int i = 0; i < count; ++i) f(i);
    return;
  }
  std::fill(errors_.begin(), errors_.end(), nullptr);
  job_ = &f;
  count_ = count;
  parts_ = parts;
  pending_.store(size() - 1, std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(mu_);  // see wait_for
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  run_chunk(0);
  wait_for(done_, [&] { return pending_.load(std::memory_order_acquire) == 0; });
  job_ = nullptr;
  for (int t = 0; t < parts; ++t)  // chunks are in index order: the first error is the smallest
    if (errors_[static_cast<size_t>(t)]) std::rethrow_exception(errors_[static_cast<size_t>(t)]);
}

}  // namespace netvmo::obs
