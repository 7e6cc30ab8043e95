// WorkerPool: a ParallelFor on a fixed set of threads, the caller's thread being one of them, so
// a pool of one thread starts no thread at all and runs every job on the caller's thread. The
// other threads sleep on a condition variable between runs (this box's cores are shared: no
// spinning). A run cuts [0, n) into chunks a few times smaller than n / threads and hands them
// out through an atomic counter, so a slow chunk does not hold the others back; since jobs are
// independent (ParallelFor's contract), which thread takes which chunk changes no result. A worker
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
  void worker_loop();
  // Takes chunks of the current run until none is left.
  void take_chunks();

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
  std::size_t n_ = 0;
  std::size_t chunk_ = 1;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr error_;  // the first exception of the run, under mu_
  std::vector<std::thread> workers_;
};

}  // namespace symb::kernel
