#include "symb/control/organism/organism_task_types.hpp"

#include <memory>

#include "symb/control/organism/dock_seek_task.hpp"
#include "symb/control/organism/leader_task.hpp"
#include "symb/control/organism/role_task.hpp"

namespace symb::control {

using namespace std::chrono_literals;

kernel::Status register_organism_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
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
    p.add("size", &RoleOptions::size).range(0, 1 << 20).doc("modules of the complete organism; 0: no count");
    p.add("module", &RoleOptions::module).range(0, 1 << 20).doc("this module's index, sent in heartbeats");
    p.add("complete", &RoleOptions::complete)
        .range(0, 1024)
        .doc("tasks run while docked in a complete organism")
        .live();
    p.add("place_param", &RoleOptions::place_param).range(0, 127).doc("TASK.PARAM set to the place in the chain");
    p.add("heard_timeout", &RoleOptions::heard_timeout)
        .range(0.001, 3600.0)
        .doc("a module not heard for this long is gone");
    auto t = os::declare_task_type(
        "role",
        "cell specialization: connector readings [state, open, peer, ...] in; takes a role from the docked faces "
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
  {
    using organism::DockSeekOptions;
    os::ParamTable<DockSeekOptions> p;
    p.add("connector", &DockSeekOptions::connector).range(1, 63).doc("the seeking connector's sensor task and device");
    p.add("back", &DockSeekOptions::back)
        .range(1, 63)
        .doc("the connector device closed while free, opened once docked");
    p.add("ir", &DockSeekOptions::ir).range(1, 63).doc("the IR sensor task (front proximity first)");
    p.add("imu", &DockSeekOptions::imu).range(1, 63).doc("the IMU sensor task (gyro z the 6th channel)");
    p.add("predock", &DockSeekOptions::predock).range(0.0, 1.0).doc("m: the pre-dock point out from the target");
    p.add("axle", &DockSeekOptions::axle).range(0.0, 1.0).doc("m: the wheel axle behind the seeking connector");
    p.add("half_track", &DockSeekOptions::half_track).range(0.001, 1.0).doc("m: half the wheel track");
    p.add("max_speed", &DockSeekOptions::max_speed).range(0.001, 10.0).doc("m/s: what 500 wheel units mean");
    p.add("ir_range", &DockSeekOptions::ir_range).range(0.001, 10.0).doc("m: the IR sensor's range");
    p.add("search_spin", &DockSeekOptions::search_spin).range(0.0, 3600.0).doc("s spinning on the spot per search");
    p.add("search_drive", &DockSeekOptions::search_drive).range(0.0, 3600.0).doc("s driving on per search");
    p.add("stuck_time", &DockSeekOptions::stuck_time).range(0.1, 3600.0).doc("s without motion that mean stuck");
    p.add("backoff_time", &DockSeekOptions::backoff_time).range(0.0, 3600.0).doc("s reversing when blocked");
    auto t = os::declare_task_type(
        "dock_seek",
        "self-assembly seeker: its connector's beacon, IR and IMU in; wheels [left, right] out on port 0; latches "
        "its connector when aligned",
        std::move(p),
        [devices = resources.device](const DockSeekOptions& o) -> kernel::Result<std::unique_ptr<os::Task>> {
          return std::unique_ptr<os::Task>(new organism::DockSeekTask(o, devices));
        });
    t.defaults = os::TaskOptions{.priority = 3, .period = 30ms, .queue_capacity = 32};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
