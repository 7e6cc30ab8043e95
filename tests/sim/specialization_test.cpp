// Cell specialization and failover in an organism (scenarios/specialization.yaml): four docked
// modules take their roles from their docked faces alone; the camera module that leads runs the
// vision task, and when it is undocked the other camera module starts vision within the leader's
// timeout and one period. Everything runs through the session: connector device tasks, the bus
// carrying the leaders' heartbeats, events undocking a module.
#include <array>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/organism/role_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;
using control::organism::Role;

struct SpecializationRig {
  kernel::VirtualTimeExecutor ex;
  std::unique_ptr<OrganismSession> session;
  std::array<int, 4> role{-1, -1, -1, -1};  // each module's newest role, from its probe

  SpecializationRig() {
    auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/specialization.yaml");
    EXPECT_TRUE(sc.ok()) << sc.error();
    auto made = OrganismSession::create(*sc, ex);
    EXPECT_TRUE(made.ok()) << made.error();
    session = std::move(made).value();
    for (std::size_t m = 0; m < 4; ++m)
      session->robot(m).node().set_probe_sink([this, m](const os::ProbeSample& p) {
        if (p.channel == "role" && !p.values.empty()) role[m] = static_cast<int>(p.values[0]);
      });
    session->start();
  }
  os::TaskState state(std::size_t module, std::string_view task) {
    os::Node& n = session->robot(module).node();
    return n.info(*n.find(task))->state;
  }
  std::array<int, 4> roles_now() const { return role; }
};

constexpr int r(Role role) { return static_cast<int>(role); }

TEST(Specialization, RolesFollowFromPositionAndVisionFailsOverWhenItsModuleIsUndocked) {
  SpecializationRig rig;
  rig.ex.run_for(3s);
  EXPECT_EQ(rig.roles_now(), (std::array{r(Role::kHead), r(Role::kSpine), r(Role::kSpine), r(Role::kTail)}));
  for (std::size_t m = 0; m < 4; ++m) EXPECT_EQ(rig.state(m, "crawl"), os::TaskState::kRunning) << m;
  EXPECT_EQ(rig.state(1, "vision"), os::TaskState::kRunning);  // rank 0 leads
  EXPECT_EQ(rig.state(3, "vision"), os::TaskState::kSuspended);

  // At 6 s the events undock m1 from both neighbours: the bus sees it at the end of that tick, and
  // m3 last heard m1 at its tick of 6.0 s at the latest.
  rig.ex.run_for(3s + 299ms);  // 6.299 s: not yet
  EXPECT_EQ(rig.state(3, "vision"), os::TaskState::kSuspended);
  rig.ex.run_for(151ms);  // 6.45 s: within the timeout (350 ms) and one period (100 ms)
  EXPECT_EQ(rig.state(3, "vision"), os::TaskState::kRunning);
  EXPECT_EQ(rig.state(1, "vision"), os::TaskState::kRunning);  // alone, m1 still leads itself

  rig.ex.run_for(550ms);  // 7 s: the roles have settled
  EXPECT_EQ(rig.roles_now(), (std::array{r(Role::kAlone), r(Role::kAlone), r(Role::kHead), r(Role::kTail)}));
  EXPECT_EQ(rig.state(0, "crawl"), os::TaskState::kSuspended);
  EXPECT_EQ(rig.state(1, "crawl"), os::TaskState::kSuspended);
  EXPECT_EQ(rig.state(2, "crawl"), os::TaskState::kRunning);
  EXPECT_EQ(rig.state(3, "crawl"), os::TaskState::kRunning);
  EXPECT_TRUE(rig.session->error().empty()) << rig.session->error();
}

}  // namespace
}  // namespace symb::sim::mujoco
