// Organisms' control: cell specialization (the `role` task) from docked faces alone, and failover
// of a service that one module runs (the `leader` task) when its module leaves or the service
// faults. Under virtual time, with connector readings scripted and the organism bus stood in for
// by a link task that forwards heartbeats between nodes while they are "docked".
#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/organism/leader_task.hpp"
#include "symb/control/organism/role_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

#include "support/virtual_time.hpp"

namespace symb::control::organism {
namespace {

using namespace std::chrono_literals;
using test_support::ms;

TEST(RoleRule, RolesFollowFromTheDockedFacesAlone) {
  EXPECT_EQ(role_of(0), Role::kAlone);
  EXPECT_EQ(role_of(kBack), Role::kHead);
  EXPECT_EQ(role_of(kFront | kBack), Role::kSpine);
  EXPECT_EQ(role_of(kFront), Role::kTail);
  EXPECT_EQ(role_of(kLeft), Role::kBranch);
  EXPECT_EQ(role_of(kFront | kBack | kRight), Role::kBranch);
}

// A connector's sensor task: sends [state, open, peer] at every tick.
class RoleConnector : public os::Task {
 public:
  float state = 0;

 protected:
  void on_tick() override { send(0, {state, 1.0f, state >= 2 ? 1.0f : -1.0f}); }
};

class RoleIdle : public os::Task {};

struct RoleRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node;
  std::array<RoleConnector*, 4> faces{};
  RoleTask* role = nullptr;

  RoleRig() : node(ex, {.name = "m", .seed = 1, .types = &types}) {
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
    const std::array<const char*, 4> names = {"connector_front", "connector_back", "connector_left", "connector_right"};
    for (std::size_t f = 0; f < 4; ++f) {
      auto c = std::make_unique<RoleConnector>();
      faces[f] = c.get();
      auto id = node.create(names[f], std::move(c), {.period = 30ms});
      EXPECT_TRUE(id.ok());
    }
    for (const char* name : {"crawl", "steer", "follow", "wander"})
      EXPECT_TRUE(node.create(name, std::make_unique<RoleIdle>()).ok());
    auto r = RoleTask::create({.alone = "wander",
                               .head = "steer crawl",
                               .spine = "crawl",
                               .tail = "crawl follow",
                               .branch = "",
                               .settle = 100ms});
    EXPECT_TRUE(r.ok());
    role = r->get();
    auto id = node.create("role", std::move(r).value(), {.period = 50ms});
    EXPECT_TRUE(id.ok());
    for (const char* name : names) EXPECT_TRUE(node.hook(*node.find(name), *id).ok());
  }
  bool running(const char* name) { return node.info(*node.find(name))->state == os::TaskState::kRunning; }
  std::string runs() {
    std::string s;
    for (const char* name : {"crawl", "steer", "follow", "wander"})
      if (running(name)) s += (s.empty() ? "" : " ") + std::string(name);
    return s;
  }
};

TEST(RoleTask, EachModuleRunsItsRolesTasksAndSwitchesWhenItsDockingChanges) {
  RoleRig rig;
  rig.ex.run_until(ms(200));
  ASSERT_TRUE(rig.role->role().has_value());
  EXPECT_EQ(*rig.role->role(), Role::kAlone);
  EXPECT_EQ(rig.runs(), "wander");

  rig.faces[1]->state = 2;  // back docked: the head of a chain
  rig.ex.run_until(ms(260));
  EXPECT_EQ(*rig.role->role(), Role::kAlone);  // not settled yet
  rig.ex.run_until(ms(400));
  EXPECT_EQ(*rig.role->role(), Role::kHead);
  EXPECT_EQ(rig.runs(), "crawl steer");

  rig.faces[0]->state = 2;  // and the front: spine
  rig.ex.run_until(ms(700));
  EXPECT_EQ(*rig.role->role(), Role::kSpine);
  EXPECT_EQ(rig.runs(), "crawl");

  rig.faces[1]->state = 1;  // the back module left (aligned is not docked): tail
  rig.ex.run_until(ms(1000));
  EXPECT_EQ(*rig.role->role(), Role::kTail);
  EXPECT_EQ(rig.runs(), "crawl follow");

  // A flicker shorter than `settle` changes nothing.
  rig.faces[2]->state = 2;
  rig.ex.run_until(ms(1060));
  rig.faces[2]->state = 0;
  rig.ex.run_until(ms(1300));
  EXPECT_EQ(*rig.role->role(), Role::kTail);
  const RoleStats s = rig.role->stats();
  EXPECT_EQ(s.changes, 4u);
  EXPECT_EQ(s.ignored, 0u);
  EXPECT_EQ(s.missing_tasks, 0u);
  EXPECT_GT(s.readings, 100u);
}

TEST(RoleTask, TheTypeRefusesRoleListsThatAreNotTaskNamesAndWarnsOfMissingTasks) {
  RoleRig rig;
  auto create = [&](std::string_view text) {
    auto params = os::parse_param_assignments(text);
    EXPECT_TRUE(params.ok());
    return rig.node.create("role", "role2", *params);
  };
  auto bad = create("head=\"steer 9lives\"");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("head: '9lives' is not a task name"), std::string::npos) << bad.error();
  ASSERT_TRUE(create("alone=\"ghost wander\"").ok());
  rig.ex.run_until(ms(300));
  std::size_t warnings = 0;
  for (const auto& e : rig.node.log().since(0))
    if (e.level == os::LogLevel::kWarn && e.text.find("no task named ghost") != std::string::npos) ++warnings;
  EXPECT_EQ(warnings, 1u);
}

// --- failover ---------------------------------------------------------------------------------------

// Throws on any message: posting to it faults it.
class LeaderService : public os::Task {
 protected:
  void on_message(const os::Message&) override { throw std::runtime_error("camera gone"); }
};

struct LeaderRig;

// Stands for the organism bus: forwards this node's heartbeats to the leader tasks of the other
// nodes, while both ends are docked.
class LeaderLink : public os::Task {
 public:
  LeaderLink(LeaderRig& rig, std::size_t me) : rig_(rig), me_(me) {}

 protected:
  void on_message(const os::Message& m) override;

 private:
  LeaderRig& rig_;
  std::size_t me_;
};

struct LeaderRig {
  static constexpr std::size_t kModules = 3;
  kernel::VirtualTimeExecutor ex;
  std::vector<std::unique_ptr<os::Node>> nodes;
  std::array<LeaderTask*, kModules> leaders{};
  std::array<os::TaskId, kModules> leader_ids{}, vision_ids{};
  std::array<bool, kModules> docked{true, true, true};

  LeaderRig() {
    for (std::size_t i = 0; i < kModules; ++i) {
      nodes.push_back(std::make_unique<os::Node>(ex, os::NodeConfig{.name = "m" + std::to_string(i), .seed = i}));
      os::Node& n = *nodes.back();
      vision_ids[i] = *n.create("vision", std::make_unique<LeaderService>());
      auto l = LeaderTask::create({.rank = static_cast<std::int64_t>(i), .service = "vision", .timeout = 350ms});
      EXPECT_TRUE(l.ok());
      leaders[i] = l->get();
      leader_ids[i] = *n.create("leader", std::move(l).value(), {.period = 100ms});
      auto link = *n.create("link", std::make_unique<LeaderLink>(*this, i));
      EXPECT_TRUE(n.hook(leader_ids[i], link, {.port = kHeartbeatPort}).ok());
    }
  }
  os::TaskState vision(std::size_t i) { return nodes[i]->info(vision_ids[i])->state; }
  std::string leading() {
    std::string s;
    for (std::size_t i = 0; i < kModules; ++i)
      if (leaders[i]->leading()) s += "m" + std::to_string(i);
    return s;
  }
};

void LeaderLink::on_message(const os::Message& m) {
  for (std::size_t j = 0; j < LeaderRig::kModules; ++j) {
    if (j == me_ || !rig_.docked[me_] || !rig_.docked[j]) continue;
    os::Message copy;
    copy.port = m.port;
    copy.payload = m.payload;
    (void)rig_.nodes[j]->post(rig_.leader_ids[j], copy);
  }
}

TEST(LeaderTask, TheLowestRankLeadsAndAnotherTakesOverWhenItLeavesOrItsServiceFaults) {
  LeaderRig rig;
  rig.ex.run_until(ms(350));
  EXPECT_EQ(rig.leading(), "");  // still listening
  EXPECT_EQ(rig.vision(0), os::TaskState::kSuspended);
  rig.ex.run_until(ms(450));
  EXPECT_EQ(rig.leading(), "m0");
  EXPECT_EQ(rig.vision(0), os::TaskState::kRunning);
  EXPECT_EQ(rig.vision(1), os::TaskState::kSuspended);
  EXPECT_EQ(rig.vision(2), os::TaskState::kSuspended);

  // m0 is undocked at 1000 ms: the others stop hearing it and, after the timeout, m1 takes over.
  rig.ex.run_until(ms(1000));
  rig.docked[0] = false;
  rig.ex.run_until(ms(1350));
  EXPECT_EQ(rig.leading(), "m0");
  rig.ex.run_until(ms(1450));        // within timeout + one period
  EXPECT_EQ(rig.leading(), "m0m1");  // m0 leads alone, m1 the rest of the organism
  EXPECT_EQ(rig.vision(1), os::TaskState::kRunning);
  EXPECT_EQ(rig.vision(2), os::TaskState::kSuspended);

  // Docked again: two leaders hear each other; the higher rank yields.
  rig.docked[0] = true;
  rig.ex.run_until(ms(2150));
  EXPECT_EQ(rig.leading(), "m0");
  EXPECT_EQ(rig.vision(1), os::TaskState::kSuspended);

  // m0's camera fails: it steps down at its next tick and m1 takes over at the tick after that,
  // without waiting for a timeout.
  os::Message shot;
  ASSERT_TRUE(rig.nodes[0]->post(rig.vision_ids[0], shot).ok());
  rig.ex.run_until(ms(2301));
  EXPECT_EQ(rig.vision(0), os::TaskState::kFaulted);
  EXPECT_EQ(rig.leading(), "m1");
  EXPECT_EQ(rig.vision(1), os::TaskState::kRunning);
  EXPECT_EQ(rig.leaders[0]->stats().yielded, 1u);
  EXPECT_EQ(rig.leaders[1]->stats().took_lead, 2u);
  EXPECT_EQ(rig.leaders[1]->stats().yielded, 1u);
  EXPECT_EQ(rig.leaders[2]->stats().took_lead, 0u);
}

TEST(LeaderTask, TheTypeNeedsAServiceName) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node(ex, {.name = "m", .seed = 1, .types = &types});
  ASSERT_TRUE(register_control_task_types(types, {}).ok());
  auto params = os::parse_param_assignments("rank=2");
  ASSERT_TRUE(params.ok());
  auto made = node.create("leader", "l", *params);
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.error().find("service"), std::string::npos) << made.error();
}

}  // namespace
}  // namespace symb::control::organism
