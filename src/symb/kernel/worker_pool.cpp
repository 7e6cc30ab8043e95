#include "symb/kernel/worker_pool.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <utility>

namespace symb::kernel {

WorkerPool::WorkerPool(Options options) : threads_(std::max(1u, options.threads)), shares_(threads_) {
  std::vector<int> cpus;
  if (options.pin) {
    cpu_set_t allowed;
    CPU_ZERO(&allowed);
    if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0)
      for (int c = 0; c < CPU_SETSIZE; ++c)
        if (CPU_ISSET(c, &allowed)) cpus.push_back(c);
  }
  for (unsigned k = 1; k < threads_; ++k) {
    workers_.emplace_back([this, k] { worker_loop(k); });
    if (!cpus.empty()) {
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(cpus[k % cpus.size()], &one);
      (void)pthread_setaffinity_np(workers_.back().native_handle(), sizeof(one), &one);
    }
  }
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(mu_);
    quit_ = true;
  }
  start_cv_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::run(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) {
  if (n == 0) return;
  if (workers_.empty()) {
    fn(0, n);
    return;
  }
  std::lock_guard run_lock(run_mu_);
  {
    std::lock_guard lock(mu_);
    fn_ = &fn;
    // Four chunks per thread: small enough to even out uneven jobs, few enough that taking one
    // (an atomic add) costs nothing beside the jobs.
    chunk_ = std::max<std::size_t>(1, n / (4 * std::size_t{threads_}));
    for (unsigned k = 0; k < threads_; ++k) {
      shares_[k].next.store(n * k / threads_, std::memory_order_relaxed);
      shares_[k].end = n * (k + 1) / threads_;
    }
    error_ = nullptr;
    busy_ = 0;
    open_ = true;
    ++generation_;
  }
  start_cv_.notify_all();
  take_chunks(0);
  std::exception_ptr error;
  {
    std::unique_lock lock(mu_);
    open_ = false;  // every chunk is taken: a worker waking from now on has nothing to do
    done_cv_.wait(lock, [&] { return busy_ == 0; });
    fn_ = nullptr;
    error = std::exchange(error_, nullptr);
  }
  if (error) std::rethrow_exception(error);
}

void WorkerPool::take_chunks(unsigned self) {
  for (unsigned r = 0; r < threads_; ++r) {
    Share& share = shares_[(self + r) % threads_];
    for (;;) {
      const std::size_t begin = share.next.fetch_add(chunk_, std::memory_order_relaxed);
      if (begin >= share.end) break;
      const std::size_t end = std::min(share.end, begin + chunk_);
      try {
        (*fn_)(begin, end);
      } catch (...) {
        std::lock_guard lock(mu_);
        if (!error_) error_ = std::current_exception();
      }
    }
  }
}

void WorkerPool::worker_loop(unsigned self) {
  std::uint64_t seen = 0;
  std::unique_lock lock(mu_);
  for (;;) {
    start_cv_.wait(lock, [&] { return quit_ || generation_ != seen; });
    if (quit_) return;
    seen = generation_;
    if (!open_) continue;  // woken too late for this run
    ++busy_;
    lock.unlock();
    take_chunks(self);
    lock.lock();
    if (--busy_ == 0) done_cv_.notify_one();
  }
}

}  // namespace symb::kernel
