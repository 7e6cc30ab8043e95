#include "symb/control/organism/organism_task_types.hpp"

#include <memory>

#include "symb/control/organism/leader_task.hpp"
#include "symb/control/organism/role_task.hpp"

namespace symb::control {

using namespace std::chrono_literals;

kernel::Status register_organism_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
  {
    using organism::RoleOptions;
    os::ParamTable<RoleOptions> p;
    p.add("front", &RoleOptions::front).range(1, 63).doc("the front connector's sensor task");
    p.add("back", &RoleOptions::back).range(1, 63).doc("the back connector's sensor task");
    p.add("left", &RoleOptions::left).range(1, 63).doc("the left connector's sensor task");
    p.add("right", &RoleOptions::right).range(1, 63).doc("the right connector's sensor task");
    p.add("alone", &RoleOptions::alone).range(0, 1024).doc("tasks run when no face is docked").live();
    p.add("head", &RoleOptions::head).range(0, 1024).doc("tasks run when only the back is docked").live();
    p.add("spine", &RoleOptions::spine).range(0, 1024).doc("tasks run when front and back are docked").live();
    p.add("tail", &RoleOptions::tail).range(0, 1024).doc("tasks run when only the front is docked").live();
    p.add("branch", &RoleOptions::branch).range(0, 1024).doc("tasks run when a side is docked").live();
    p.add("settle", &RoleOptions::settle).range(0.0, 3600.0).doc("faces must show a new role this long").live();
    auto t = os::declare_task_type(
        "role",
        "cell specialization: connector readings [state, open, peer] in; takes a role from the docked faces "
        "and runs that role's tasks; [role] out on port 0",
        std::move(p), [](const RoleOptions& o) { return organism::RoleTask::create(o); });
    t.defaults = os::TaskOptions{.priority = 3, .period = 50ms, .queue_capacity = 16};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using organism::LeaderOptions;
    os::ParamTable<LeaderOptions> p;
    p.add("rank", &LeaderOptions::rank).range(0, 1 << 20).doc("unique among the candidates; the lowest leads");
    p.add("service", &LeaderOptions::service).range(0, 63).doc("the task this module runs while it leads");
    p.add("timeout", &LeaderOptions::timeout)
        .range(0.001, 3600.0)
        .doc("a candidate not heard from for this long is gone");
    auto t = os::declare_task_type(
        "leader", "failover: heartbeats [rank, leading, eligible] in and out on port 1; runs `service` while it leads",
        std::move(p), [](const LeaderOptions& o) { return organism::LeaderTask::create(o); });
    t.defaults = os::TaskOptions{.priority = 3, .period = 100ms, .queue_capacity = 16};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
