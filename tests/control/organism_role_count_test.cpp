// The `role` task's count of its organism (self-assembly's switch, docs/organism.md): heartbeats
// [module, place] heard on port 1 make the organism complete at `size` modules, only while docked;
// then the `complete` tasks run instead of the role's, and back when a module falls silent; the
// place in the chain follows the front peer's announced place and is written to `place_param`.
#include <array>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/organism/role_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

#include "support/virtual_time.hpp"

namespace symb::control::organism {
namespace {

using namespace std::chrono_literals;
using test_support::ms;

// A connector's sensor task: [state, open, peer] with a settable peer.
class CountConnector : public os::Task {
 public:
  float state = 0, peer = -1;

 protected:
  void on_tick() override { send(0, {state, 1.0f, state >= 2 ? peer : -1.0f}); }
};

// Another module's role task as the bus delivers it: [module, place] on port 1 while `on`.
class CountPeer : public os::Task {
 public:
  float module = 0, place = -1;
  bool on = false;

 protected:
  void on_tick() override {
    if (on) send(kRoleHeartbeatPort, {module, place});
  }
};

class CountIdle : public os::Task {};

struct CountRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node;
  CountConnector* front = nullptr;
  std::array<CountPeer*, 2> peers{};
  RoleTask* role = nullptr;
  os::TaskId osc{};

  CountRig() : node(ex, {.name = "m1", .seed = 1, .types = &types}) {
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
    auto c = std::make_unique<CountConnector>();
    front = c.get();
    const auto front_id = node.create("connector_front", std::move(c), {.period = 30ms});
    EXPECT_TRUE(front_id.ok());
    EXPECT_TRUE(node.create("seek", std::make_unique<CountIdle>()).ok());
    auto made_osc = node.create("oscillator", "osc", {});
    EXPECT_TRUE(made_osc.ok());
    osc = *made_osc;
    auto r = RoleTask::create({.alone = "seek",
                               .head = "",
                               .spine = "",
                               .tail = "",
                               .branch = "",
                               .settle = 100ms,
                               .size = 3,
                               .module = 1,
                               .complete = "osc",
                               .place_param = "osc.id",
                               .heard_timeout = 300ms});
    EXPECT_TRUE(r.ok());
    role = r->get();
    auto made = node.create("role", std::move(r).value(), {.period = 50ms});
    EXPECT_TRUE(made.ok());
    EXPECT_TRUE(node.hook(*front_id, *made).ok());
    for (std::size_t i = 0; i < peers.size(); ++i) {
      auto p = std::make_unique<CountPeer>();
      peers[i] = p.get();
      const auto id = node.create("peer" + std::to_string(i), std::move(p), {.period = 50ms});
      EXPECT_TRUE(id.ok());
      EXPECT_TRUE(node.hook(*id, *made, {.port = kRoleHeartbeatPort}).ok());
    }
    peers[0]->module = 0;  // the head
    peers[0]->place = 0;
    peers[1]->module = 2;  // the tail, behind this module
    peers[1]->place = 2;
  }
  bool running(const char* name) { return node.info(*node.find(name))->state == os::TaskState::kRunning; }
  std::int64_t osc_id() {
    auto p = node.parameters(osc);
    EXPECT_TRUE(p.ok());
    return p.ok() ? p->integer("id") : -1;
  }
};

TEST(RoleCount, TheOrganismIsCompleteAtSizeModulesHeardWhileDockedAndThePlaceFollowsTheFrontPeer) {
  CountRig rig;
  rig.ex.run_until(ms(300));
  EXPECT_EQ(*rig.role->role(), Role::kAlone);
  EXPECT_TRUE(rig.running("seek"));
  EXPECT_FALSE(rig.running("osc"));
  EXPECT_EQ(rig.role->organism_size(), 1);
  EXPECT_EQ(rig.role->place(), 0);  // front free: a head of itself

  // Everyone heard, but this module is not docked: not complete (it is no organism's part).
  rig.peers[0]->on = rig.peers[1]->on = true;
  rig.ex.run_until(ms(600));
  EXPECT_EQ(rig.role->organism_size(), 3);
  EXPECT_FALSE(rig.role->complete());
  EXPECT_TRUE(rig.running("seek"));

  // Docked at its front to module 0 (which announces place 0): tail, place 1, complete, osc runs.
  rig.front->state = 2;
  rig.front->peer = 0;
  rig.ex.run_until(ms(1000));
  EXPECT_EQ(*rig.role->role(), Role::kTail);
  EXPECT_TRUE(rig.role->complete());
  EXPECT_EQ(rig.role->place(), 1);
  EXPECT_EQ(rig.osc_id(), 1);
  EXPECT_TRUE(rig.running("osc"));
  EXPECT_FALSE(rig.running("seek"));

  // Module 2 falls silent for longer than heard_timeout: no longer complete, the tail's tasks (none).
  rig.peers[1]->on = false;
  rig.ex.run_until(ms(1600));
  EXPECT_EQ(rig.role->organism_size(), 2);
  EXPECT_FALSE(rig.role->complete());
  EXPECT_FALSE(rig.running("osc"));
  EXPECT_FALSE(rig.running("seek"));
  EXPECT_GT(rig.role->stats().heartbeats, 10u);
}

TEST(RoleCount, WithoutSizeNoHeartbeatIsSentAndNothingIsCounted) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node(ex, {.name = "m", .seed = 1, .types = &types});
  ASSERT_TRUE(register_control_task_types(types, {}).ok());
  auto made = node.create("role", "role", {});
  ASSERT_TRUE(made.ok());
  auto listener = std::make_unique<CountIdle>();
  const auto id = node.create("listener", std::move(listener));
  ASSERT_TRUE(id.ok());
  ASSERT_TRUE(node.hook(*made, *id, {.port = kRoleHeartbeatPort}).ok());
  ex.run_until(ms(500));
  EXPECT_EQ(node.info(*id)->traffic.attempted, 0u);
}

}  // namespace
}  // namespace symb::control::organism
