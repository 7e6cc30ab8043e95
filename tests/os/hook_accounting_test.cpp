// The accounting law per hook (hook.hpp), exactly, with no slack: every send of a sender is
// offered or skipped at each of its hooks, and every message offered through a hook is handled,
// dropped for a reason, or still queued. One sender, a hook into each way a message can go
// (keep-newest overflow, refusal, another port, disabled, suppressed, inhibited, unhooked with
// messages in flight, receiver deleted with messages queued), checked at every step of the run.
#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using testing::Collector;
using testing::Scripted;

std::string describe(const HookInfo& h) {
  const HookTraffic& a = h.accounting;
  return h.sender_name + " -> " + h.receiver_name + ": sent " + std::to_string(a.sent) + " skipped " +
         std::to_string(a.skipped) + " attempted " + std::to_string(a.traffic.attempted) + " delivered " +
         std::to_string(a.traffic.delivered) + " dropped " + std::to_string(a.traffic.dropped()) + " queued " +
         std::to_string(a.queued);
}

TEST(HookAccounting, EverySendIsAccountedForAtEachHookExactly) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  std::uint64_t own_sends = 0;
  auto tx_task = std::make_unique<Scripted>();
  tx_task->tick = [&own_sends](Scripted& self) {
    for (int k = 0; k < 3; ++k) {
      self.send(static_cast<Port>(own_sends % 2), {static_cast<float>(own_sends)});
      ++own_sends;
    }
  };
  const TaskId tx = *node.create("tx", std::move(tx_task), {.period = 1ms});
  auto rx = [&](const std::string& name, std::size_t capacity) {
    return *node.create(name, std::make_unique<Collector>(), {.queue_capacity = capacity});
  };
  const TaskId slow = rx("slow", 4), strict = rx("strict", 2), port1 = rx("port1", 16), toggled = rx("toggled", 16),
               low = rx("low", 16), inhibited = rx("inhibited", 16), unhooked = rx("unhooked", 64),
               doomed = rx("doomed", 64);
  ASSERT_TRUE(node.hook(tx, slow, {.policy = QueuePolicy::kKeepNewest}));
  ASSERT_TRUE(node.hook(tx, strict, {.policy = QueuePolicy::kRefuse}));
  ASSERT_TRUE(node.hook(tx, port1, {.port = 1}));
  const HookId toggle = *node.hook(tx, toggled);
  ASSERT_TRUE(node.hook(tx, low));
  ASSERT_TRUE(node.hook(tx, inhibited));
  const HookId goes = *node.hook(tx, unhooked);
  ASSERT_TRUE(node.hook(tx, doomed));
  // A higher-priority hook into `low` whose deliveries suppress tx's for 2 ms.
  auto boss = std::make_unique<testing::Emitter>();
  const TaskId b = *node.create("boss", std::move(boss), {.period = 7ms});
  ASSERT_TRUE(node.hook(b, low, {.priority = 5, .suppress_window = 2ms}));

  auto check_every_hook = [&](const char* when) {
    for (const HookInfo& h : node.hooks()) {
      EXPECT_TRUE(h.accounting.closes()) << when << ": " << describe(h);
      if (h.sender == tx) {
        // Made before tx's first send: the hook saw every one of them.
        EXPECT_EQ(h.accounting.sent, own_sends) << when << ": " << describe(h);
        if (h.receiver != port1 && h.receiver != toggled) {
          EXPECT_EQ(h.accounting.sent, h.accounting.traffic.attempted) << when << ": " << describe(h);
        }
      }
    }
    EXPECT_TRUE(node.hook_traffic().closes()) << when;
  };

  for (int ms = 10; ms <= 600; ms += 10) {
    ex.run_until(Time{std::chrono::milliseconds(ms)});
    switch (ms) {
      case 50: (void)node.suspend(slow), (void)node.suspend(strict); break;
      case 80: (void)node.resume(slow), (void)node.resume(strict); break;
      case 100: ASSERT_TRUE(node.set_hook_enabled(toggle, false)); break;
      case 200: ASSERT_TRUE(node.set_hook_enabled(toggle, true)); break;
      case 250: ASSERT_TRUE(node.inhibit(tx, inhibited, 30ms)); break;
      case 290: (void)node.suspend(unhooked), (void)node.suspend(doomed); break;
      case 300: ASSERT_TRUE(node.unhook(goes)); break;  // 30 messages of it still queued
      case 320: ASSERT_TRUE(node.resume(unhooked)); break;
      case 330: ASSERT_TRUE(node.remove(doomed)); break;  // with 64 messages queued
      default: break;
    }
    check_every_hook(("at " + std::to_string(ms) + " ms").c_str());
  }

  // Each way a message can go was taken.
  const HookTraffic all = node.hook_traffic();
  EXPECT_GT(all.skipped, 0u);
  EXPECT_GT(all.traffic.overwritten, 0u);
  EXPECT_GT(all.traffic.refused, 0u);
  EXPECT_GT(all.traffic.suppressed, 0u);
  EXPECT_GT(all.traffic.inhibited, 0u);
  EXPECT_GT(all.traffic.discarded, 0u);
  EXPECT_TRUE(all.closes());
  // Nothing was posted: the hooks' sum is the receivers' sum.
  const TrafficCounters t = node.traffic();
  EXPECT_EQ(all.traffic.attempted, t.attempted);
  EXPECT_EQ(all.traffic.delivered, t.delivered);
  EXPECT_EQ(all.traffic.dropped(), t.dropped());
  EXPECT_EQ(all.queued, node.queued());
  // Every send of tx, times its 8 hooks while they lived: 7 for the whole run, `unhooked` until
  // 300 ms, `doomed` until 330 ms, boss's hook into `low` besides.
  const std::uint64_t tx_sends = 600 * 3;
  const std::uint64_t boss_sends = node.info(b)->sent;
  EXPECT_EQ(own_sends, tx_sends);
  EXPECT_EQ(all.sent, 6 * tx_sends + 300 * 3 + 330 * 3 + boss_sends);
}

TEST(HookAccounting, AHookRemovedAndMadeAgainKeepsItsOwnBooks) {
  // The receiver's slot of a removed hook is reused only once its messages are gone; a new hook
  // between the same tasks starts its books from zero.
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  auto s = std::make_unique<Scripted>();
  Scripted* sender = s.get();
  const TaskId tx = *node.create("tx", std::move(s));
  const TaskId rx = *node.create("rx", std::make_unique<Collector>(), {.queue_capacity = 8});
  ex.run_until(Time{1ms});
  ASSERT_TRUE(node.suspend(rx));
  for (int round = 0; round < 3; ++round) {
    const HookId h = *node.hook(tx, rx);
    for (int k = 0; k < 3; ++k) sender->send(0, {1});
    const auto hooks = node.hooks();
    ASSERT_EQ(hooks.size(), 1u);
    EXPECT_EQ(hooks[0].accounting.sent, 3u);
    EXPECT_EQ(hooks[0].accounting.queued, 3u);
    EXPECT_TRUE(hooks[0].accounting.closes());
    ASSERT_TRUE(node.unhook(h));
    EXPECT_EQ(node.hook_traffic().queued, std::min(3u * (round + 1), 8u));  // the 9th overwrites the 1st
    EXPECT_TRUE(node.hook_traffic().closes());
  }
  ASSERT_TRUE(node.resume(rx));
  ex.run_until(Time{2ms});
  const HookTraffic all = node.hook_traffic();
  EXPECT_EQ(all.sent, 9u);
  EXPECT_EQ(all.traffic.delivered, 8u);
  EXPECT_EQ(all.traffic.overwritten, 1u);
  EXPECT_EQ(all.queued, 0u);
  EXPECT_TRUE(all.closes());
}

}  // namespace
}  // namespace symb::os
