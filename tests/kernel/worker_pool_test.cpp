#include "symb/kernel/worker_pool.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;

// Every index of [0, n) is covered exactly once, whatever the number of threads and n.
TEST(WorkerPool, CoversEveryIndexExactlyOnce) {
  for (unsigned threads : {1u, 2u, 4u}) {
    WorkerPool pool({.threads = threads});
    EXPECT_EQ(pool.threads(), threads);
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      std::vector<std::atomic<int>> hits(n);
      pool.run(n, [&](std::size_t begin, std::size_t end) {
        ASSERT_LE(begin, end);
        ASSERT_LE(end, n);
        for (std::size_t i = begin; i < end; ++i) hits[i].fetch_add(1);
      });
      for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(hits[i].load(), 1) << threads << " threads, n " << n << ", i " << i;
    }
  }
}

TEST(WorkerPool, OneThreadRunsEverythingOnTheCaller) {
  WorkerPool pool;
  EXPECT_EQ(pool.threads(), 1u);
  std::vector<std::thread::id> who;
  pool.run(5, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) who.push_back(std::this_thread::get_id());
  });
  ASSERT_EQ(who.size(), 5u);
  for (auto id : who) EXPECT_EQ(id, std::this_thread::get_id());
}

// Two jobs that each wait for the other to have started can only both see it when they run at
// the same time: the pool really runs them on two threads. (The wait is bounded so a serial pool
// fails the test instead of hanging.)
TEST(WorkerPool, TwoThreadsRunTwoJobsAtOnce) {
  WorkerPool pool({.threads = 2});
  std::mutex mu;
  std::condition_variable cv;
  int started = 0;
  std::atomic<int> met{0};
  std::vector<std::thread::id> who(2);
  pool.run(2, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      who[i] = std::this_thread::get_id();
      std::unique_lock lock(mu);
      ++started;
      cv.notify_all();
      if (cv.wait_for(lock, 20s, [&] { return started == 2; })) met.fetch_add(1);
    }
  });
  EXPECT_EQ(met.load(), 2);
  EXPECT_NE(who[0], who[1]);
}

// The other thread starts on its own share of the range (the second half of 8 jobs on two
// threads), not on the next chunk after the caller's: a robot's lane runs on the same core from
// step to step. Job 0 holds the caller until another thread has started a job. (Bounded wait: a
// pool that never starts its worker fails instead of hanging.)
TEST(WorkerPool, EachThreadStartsOnItsOwnShare) {
  WorkerPool pool({.threads = 2});
  for (int run = 0; run < 3; ++run) {
    const std::thread::id caller = std::this_thread::get_id();
    std::atomic<long> first_other{-1};
    pool.run(8, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        if (std::this_thread::get_id() != caller) {
          long none = -1;
          first_other.compare_exchange_strong(none, static_cast<long>(i));
        }
        if (i == 0)
          for (int spin = 0; spin < 10000 && first_other.load() < 0; ++spin) std::this_thread::sleep_for(1ms);
      }
    });
    EXPECT_EQ(first_other.load(), 4) << "run " << run;
  }
}

// An exception in one job reaches the caller after every other job ran; the pool goes on working.
TEST(WorkerPool, AnExceptionIsRethrownAfterEveryJobRan) {
  for (unsigned threads : {1u, 2u, 4u}) {
    WorkerPool pool({.threads = threads});
    std::vector<std::atomic<int>> hits(100);
    EXPECT_THROW(pool.run(100,
                          [&](std::size_t begin, std::size_t end) {
                            for (std::size_t i = begin; i < end; ++i) {
                              hits[i].fetch_add(1);
                              if (i == 37) throw std::runtime_error("job 37");
                            }
                          }),
                 std::runtime_error);
    // The call holding job 37 stops there; every other call (a chunk of its own once there are
    // several threads) runs to its end.
    EXPECT_EQ(hits[0].load(), 1);
    EXPECT_EQ(hits[37].load(), 1);
    if (threads > 1) {
      EXPECT_EQ(hits[99].load(), 1) << threads;
    }
    std::atomic<int> again{0};
    pool.run(10, [&](std::size_t begin, std::size_t end) { again.fetch_add(static_cast<int>(end - begin)); });
    EXPECT_EQ(again.load(), 10);
  }
}

TEST(WorkerPool, PinnedPoolStillCoversEverything) {
  WorkerPool pool({.threads = 3, .pin = true});
  std::atomic<std::size_t> sum{0};
  pool.run(300, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) sum.fetch_add(i);
  });
  EXPECT_EQ(sum.load(), 299u * 300u / 2u);
}

}  // namespace
}  // namespace symb::kernel
