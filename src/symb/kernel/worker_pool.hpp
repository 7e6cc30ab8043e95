// WorkerPool: a ParallelFor on a fixed set of threads, the caller's thread being one of them, so
// a pool of one thread starts no thread at all and runs every job on the caller's thread. The
// other threads sleep on a condition variable between runs (this box's cores are shared: no
// spinning). A run gives each thread a share of [0, n), the same share at every run of the same
// n, so that what a job touches (a robot's node, lane after lane, step after step) stays in that
// core's cache; a thread takes its share in chunks a few times smaller than n / threads, through
// an atomic counter, and then the chunks still left in the others' shares, so a slow chunk or a
// late thread does not hold the run back. Since jobs are independent (ParallelFor's contract),
// which thread takes which chunk changes no result. A worker
// that the OS has not woken by the time the caller has taken every chunk sits the run out: the
// caller waits only for chunks under way, never for a thread to be scheduled (on a loaded box
// that wait would be a whole time slice per run).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "symb/kernel/parallel_for.hpp"

namespace symb::kernel {

class WorkerPool final : public ParallelFor {
 public:
  struct Options {
    unsigned threads = 1;  // counting the caller's; 0 is taken as 1
    // Pins worker k (the caller is worker 0 and is left alone) to CPU k modulo the CPUs the
    // process may use: steadier timings on a loaded box. A refused pin is ignored.
    bool pin = false;
  };
  WorkerPool() : WorkerPool(Options{}) {}
  explicit WorkerPool(Options options);
  // Joins the threads. Must not be called during run().
  ~WorkerPool() override;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned threads() const override { return threads_; }
  // See ParallelFor::run. One run at a time: a second caller waits for the first to finish.
  void run(std::size_t n, const std::function<void(std::size_t begin, std::size_t end)>& fn) override;

 private:
  void worker_loop(unsigned self);
  // Takes chunks of the current run until none is left: thread `self`'s share first.
  void take_chunks(unsigned self);

  const unsigned threads_;
  std::mutex run_mu_;  // one run at a time
  std::mutex mu_;
  std::condition_variable start_cv_;
  std::condition_variable done_cv_;
  std::uint64_t generation_ = 0;  // bumped per run; workers wait for a new one
  bool quit_ = false;
  bool open_ = false;  // workers may still join the current run
  unsigned busy_ = 0;  // workers that joined the current run and have not left it
  // The current run, written under mu_ before the generation is bumped.
  const std::function<void(std::size_t, std::size_t)>* fn_ = nullptr;
  std::size_t chunk_ = 1;
  // Thread k's share of the current run: [next, end), taken from the front by whoever takes it.
  // A cache line each: the threads' counters are written at every chunk.
  struct alignas(64) Share {
    std::atomic<std::size_t> next{0};
    std::size_t end = 0;
  };
  std::vector<Share> shares_;
  std::exception_ptr error_;  // the first exception of the run, under mu_
  std::vector<std::thread> workers_;
};

}  // namespace symb::kernel
