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
  parts_state_ = std::vector<Part>(static_cast<size_t>(size));
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

void WorkerPool::drain(int part) {
  auto& p = parts_state_[static_cast<size_t>(part)];
  for (;;) {
    if (p.failed.load(std::memory_order_relaxed)) return;
    const int begin = p.next.fetch_add(grain_, std::memory_order_relaxed);
    if (begin >= p.end) return;
    const int end = std::min(p.end, begin + grain_);
    for (int i = begin; i < end; ++i) {
      try {
        (*job_)(i);
      } catch (...) {
        p.failed.store(true, std::memory_order_relaxed);
        std::lock_guard<std::mutex> lock(error_mu_);
        if (!error_ || i < error_index_) {
          error_ = std::current_exception();
          error_index_ = i;
        }
        return;
      }
    }
  }
}

void WorkerPool::run_parts(int t) {
  // Its own part first, then what is left of the others (in the order of the parts after it).
  for (int k = 0; k < parts_; ++k) drain((t + k) % parts_);
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
    // Every worker counts in the job's barrier, a part or not, so that the caller cannot set up
    // the next job while one still reads this one's fields.
    if (t < parts_) run_parts(t);
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
  error_ = nullptr;
  job_ = &f;
  parts_ = parts;
  // Grains of about 1/32 of a part (at most 128 indices): few enough that claiming them costs
  // nothing next to the job, many enough that a thread that finishes early takes a fair share of
  // what the other has left.
  grain_ = std::clamp(count / (parts * 32), 1, 128);
  for (int t = 0; t < parts; ++t) {
    auto& p = parts_state_[static_cast<size_t>(t)];
    p.next.store(static_cast<int>(static_cast<std::int64_t>(count) * t / parts),
                 std::memory_order_relaxed);
    p.end = static_cast<int>(static_cast<std::int64_t>(count) * (t + 1) / parts);
    p.failed.store(false, std::memory_order_relaxed);
  }
  pending_.store(size() - 1, std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(mu_);  // see wait_for
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  run_parts(0);
  wait_for(done_, [&] { return pending_.load(std::memory_order_acquire) == 0; });
  job_ = nullptr;
  if (error_) std::rethrow_exception(error_);
}

}  // namespace netvmo::obs
