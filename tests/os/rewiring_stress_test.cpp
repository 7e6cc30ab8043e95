// Rewiring under load: while eight tasks exchange messages at full speed on the thread executor,
// tasks are created, hooked, unhooked, suspended, resumed, re-prioritised and deleted 10,000
// times, from outside and from a task's own handler. Nothing may crash or deadlock (TSan runs
// this too), and the accounting must close exactly, per receiver and per hook (hook.hpp): every
// send of a sender was offered or skipped at each of its hooks, and every message offered to a
// queue was delivered, counted as dropped by its policy, or is still queued. The per-hook law is
// checked while the traffic flows, hook by hook, and summed over every hook at the end.
#include <atomic>
#include <chrono>
#include <future>
#include <thread>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"

#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;

// ThreadSanitizer slows every memory access by an order of magnitude; at the same tick rates the
// workers would eat both cores and starve the driver. Same operations, gentler traffic.
#if defined(__SANITIZE_THREAD__)
constexpr auto kWorkerPeriod = 2ms;
constexpr auto kTempPeriod = 5ms;
#else
constexpr auto kWorkerPeriod = 200us;
constexpr auto kTempPeriod = 500us;
#endif

// Sends a burst on every tick and one message for each message it gets from an even-numbered
// source, so traffic both flows and echoes without growing without bound.
class Worker : public Task {
 public:
  explicit Worker(std::atomic<std::uint64_t>& handled) : handled_(handled) {}

 protected:
  void on_tick() override {
    for (int i = 0; i < 8; ++i) send(0, {1, 2, 3, 4, 5, 6, 7, 8});
  }
  void on_message(const Message& m) override {
    handled_.fetch_add(1, std::memory_order_relaxed);
    if (m.source.valid() && m.source.index % 2 == 0 && m.port == 0) send(1, {m.numbers()[0]});
  }

 private:
  std::atomic<std::uint64_t>& handled_;
};

// Rewires the node from inside a handler: suspends and resumes its neighbours, and hooks and
// unhooks itself.
class Chaos : public Task {
 public:
  explicit Chaos(std::vector<TaskId> workers, std::atomic<int>& ops) : workers_(std::move(workers)), ops_(ops) {}

 protected:
  void on_tick() override {
    TaskId w = workers_[random().below(workers_.size())];
    switch (random().below(4)) {
      case 0: (void)node().suspend(w); break;
      case 1: (void)node().resume(w); break;
      case 2:
        if (auto h = node().hook(id(), w, {.policy = QueuePolicy::kRefuse})) hooks_.push_back(*h);
        break;
      case 3:
        if (!hooks_.empty()) {
          (void)node().unhook(hooks_.back());
          hooks_.pop_back();
        }
        break;
    }
    send(0, {static_cast<float>(ops_.fetch_add(1))});
  }

 private:
  std::vector<TaskId> workers_;
  std::vector<HookId> hooks_;
  std::atomic<int>& ops_;
};

TEST(RewiringUnderLoad, TenThousandOperationsAccountingClosesExactly) {
  kernel::ThreadExecutor ex;
  std::atomic<std::uint64_t> handled{0};
  std::atomic<int> chaos_ops{0};
  TrafficCounters t;
  HookTraffic hooks_total;
  std::uint64_t queued_after = 1;
  int ops = 0;
  int hook_checks = 0;
  std::string open_hook;  // the first hook whose books did not close
  {
    Node node(ex, {"stress", 99});
    std::vector<TaskId> workers;
    for (int i = 0; i < 8; ++i) {
      auto id = node.create("w" + std::to_string(i), std::make_unique<Worker>(handled),
                            {.priority = i % 3, .period = kWorkerPeriod, .queue_capacity = 32});
      ASSERT_TRUE(id) << id.error();
      workers.push_back(*id);
    }
    for (int i = 0; i < 8; ++i) {
      ASSERT_TRUE(node.hook(workers[i], workers[(i + 1) % 8], {.policy = QueuePolicy::kKeepNewest}));
      ASSERT_TRUE(node.hook(workers[i], workers[(i + 3) % 8], {.priority = 1, .policy = QueuePolicy::kRefuse}));
    }
    ASSERT_TRUE(node.create("chaos", std::make_unique<Chaos>(workers, chaos_ops), {.period = kWorkerPeriod}));

    // The driver runs in its own thread so a deadlock fails the test instead of hanging it.
    auto driver = std::async(std::launch::async, [&] {
      kernel::RandomStream rnd(2026, 0);
      std::vector<TaskId> temps;
      std::vector<HookId> hooks;
      int serial = 0;
      auto any_task = [&] {
        if (!temps.empty() && rnd.below(2) == 0) return temps[rnd.below(temps.size())];
        return workers[rnd.below(workers.size())];
      };
      while (ops < 10000) {
        switch (rnd.below(8)) {
          case 0: {  // create, with a hook in each direction
            auto id =
                node.create("t" + std::to_string(serial++), std::make_unique<Worker>(handled),
                            {.priority = static_cast<int>(rnd.below(5)), .period = kTempPeriod, .queue_capacity = 8});
            if (!id) break;
            temps.push_back(*id);
            if (auto h = node.hook(workers[rnd.below(8)], *id)) hooks.push_back(*h);
            if (auto h = node.hook(*id, workers[rnd.below(8)], {.policy = QueuePolicy::kRefuse})) hooks.push_back(*h);
            break;
          }
          case 1:  // delete
            if (!temps.empty()) {
              const std::size_t k = rnd.below(temps.size());
              (void)node.remove(temps[k]);
              temps.erase(temps.begin() + static_cast<std::ptrdiff_t>(k));
            }
            break;
          case 2: {
            auto h = node.hook(any_task(), any_task(),
                               {.priority = static_cast<int>(rnd.below(4)),
                                .policy = rnd.below(2) ? QueuePolicy::kRefuse : QueuePolicy::kKeepNewest});
            if (h) hooks.push_back(*h);
            break;
          }
          case 3:
            if (!hooks.empty()) {
              const std::size_t k = rnd.below(hooks.size());
              (void)node.unhook(hooks[k]);  // may already be gone with a deleted task
              hooks.erase(hooks.begin() + static_cast<std::ptrdiff_t>(k));
            }
            break;
          case 4: (void)node.suspend(any_task()); break;
          case 5: (void)node.resume(any_task()); break;
          case 6: (void)node.set_priority(any_task(), static_cast<int>(rnd.below(7)) - 3); break;
          case 7: (void)node.suppress(any_task(), 2, 100us); break;
        }
        ++ops;
        if (ops % 64 == 0) std::this_thread::yield();  // let the workers make progress
        if (ops % 500 == 0) {
          // Each hook's snapshot is taken under its sender's and receiver's locks: exact even now.
          for (const HookInfo& h : node.hooks()) {
            ++hook_checks;
            if (!h.accounting.closes() && open_hook.empty())
              open_hook = h.sender_name + " -> " + h.receiver_name + ": sent " + std::to_string(h.accounting.sent) +
                          ", skipped " + std::to_string(h.accounting.skipped) + ", attempted " +
                          std::to_string(h.accounting.traffic.attempted) + ", delivered " +
                          std::to_string(h.accounting.traffic.delivered) + ", dropped " +
                          std::to_string(h.accounting.traffic.dropped()) + ", queued " +
                          std::to_string(h.accounting.queued);
          }
        }
      }
    });
    ASSERT_EQ(driver.wait_for(240s), std::future_status::ready) << "driver stuck: deadlock?";
    driver.get();

    // The node still works after all that: a fresh receiver gets traffic.
    auto c = std::make_unique<testing::Collector>();
    c->on_each = [&handled](const Message&) { handled.fetch_add(1, std::memory_order_relaxed); };
    testing::Collector* col = c.get();
    auto probe = *node.create("probe", std::move(c), {.queue_capacity = 64});
    for (TaskId w : workers) (void)node.resume(w);
    ASSERT_TRUE(node.hook(workers[0], probe));
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (col->count() < 10 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
    EXPECT_GE(col->count(), 10u);

    for (const auto& info : node.tasks()) ASSERT_TRUE(node.remove(info.id));
    node.wait_released();
    t = node.traffic();
    hooks_total = node.hook_traffic();
    queued_after = node.queued();
  }
  EXPECT_EQ(ops, 10000);
  EXPECT_GT(chaos_ops.load(), 10);
  EXPECT_EQ(queued_after, 0u);
  EXPECT_GT(t.delivered, 10000u);
  EXPECT_GT(t.dropped(), 0u);  // the load is meant to overflow some queues
  EXPECT_EQ(t.attempted, t.delivered + t.dropped());
  // Per hook, while the traffic flowed and over every hook the node ever had.
  EXPECT_GT(hook_checks, 100);
  EXPECT_EQ(open_hook, "");
  EXPECT_TRUE(hooks_total.closes());
  EXPECT_GT(hooks_total.skipped + hooks_total.traffic.attempted, 10000u);
  EXPECT_EQ(hooks_total.sent, hooks_total.skipped + hooks_total.traffic.attempted);
  // Nothing was posted: every message offered to a queue came through a hook.
  EXPECT_EQ(hooks_total.traffic.attempted, t.attempted);
  EXPECT_EQ(hooks_total.traffic.delivered, t.delivered);
  EXPECT_EQ(hooks_total.traffic.dropped(), t.dropped());
  EXPECT_EQ(hooks_total.queued, 0u);
  // The tasks' own count of handled messages (the probe's included) matches the node's books.
  EXPECT_EQ(handled.load(), t.delivered);
  std::printf("attempted %llu delivered %llu overwritten %llu refused %llu suppressed %llu discarded %llu\n",
              static_cast<unsigned long long>(t.attempted), static_cast<unsigned long long>(t.delivered),
              static_cast<unsigned long long>(t.overwritten), static_cast<unsigned long long>(t.refused),
              static_cast<unsigned long long>(t.suppressed), static_cast<unsigned long long>(t.discarded));
}

}  // namespace
}  // namespace symb::os
