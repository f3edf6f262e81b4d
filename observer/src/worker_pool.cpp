#include "netvmo/observer/worker_pool.hpp"

#include <algorithm>

namespace netvmo::obs {

WorkerPool::WorkerPool(int size) {
  if (size <= 0) size = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  errors_.resize(static_cast<size_t>(size));
  workers_.reserve(static_cast<size_t>(size - 1));
  for (int t = 1; t < size; ++t) workers_.emplace_back([this, t] { work(t); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
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
    {
      std::unique_lock<std::mutex> lock(mu_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (t >= parts_) continue;  // not needed for this job
    }
    run_chunk(t);
    std::lock_guard<std::mutex> lock(mu_);
    if (--pending_ == 0) done_.notify_one();
  }
}

void WorkerPool::for_each(int count, int parts, const std::function<void(int)>& f) {
  parts = std::clamp(parts, 1, size());
  if (parts == 1) {  // a plain loop in the caller
    for (int i = 0; i < count; ++i) f(i);
    return;
  }
  std::fill(errors_.begin(), errors_.end(), nullptr);
  {
    std::lock_guard<std::mutex> lock(mu_);
    job_ = &f;
    count_ = count;
    parts_ = parts;
    pending_ = parts - 1;
    ++generation_;
  }
  start_.notify_all();
  run_chunk(0);
  {
    std::unique_lock<std::mutex> lock(mu_);
    done_.wait(lock, [&] { return pending_ == 0; });
    job_ = nullptr;
  }
  for (int t = 0; t < parts; ++t)  // chunks are in index order: the first error is the smallest
    if (errors_[static_cast<size_t>(t)]) std::rethrow_exception(errors_[static_cast<size_t>(t)]);
}

}  // namespace netvmo::obs
