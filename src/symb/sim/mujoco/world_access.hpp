// WorldAccess: the one way into a running 3D world for anyone but its runner's tick. It holds the
// world's lock (the runner steps under it; a connector's latch, a shell or a test acts under it)
// and the modules' nodes, whose logs hear of every docking change.
//
// Devices that act on the world at once (a connector's `latch` ioctl must answer with the world's
// verdict) hold it shared, and the runner closes it when it goes: later calls find no world and
// say so, instead of reaching a world that is gone.
//
// Docking log: the world appends every latch, unlatch and refusal to its docking log, whoever
// asked. take_dock_events() hands over what is new since the last call (under the lock), and
// log_dock_events() writes each to the logs of the nodes of both modules it names (outside the
// world's lock), so a latch commanded by one module shows in its partner's log too.
//
// Locks: the world lock, then (never inside it) the node lock, which guards the node table and is
// held while a log is written, so set_node(m, nullptr) returns only when no write to m's log is
// under way: then the node may go. A log sink must not call back into this object.
#pragma once

#include <cstddef>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "symb/os/syslog.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"

namespace symb::os {
class Node;
}

namespace symb::sim::mujoco {

// The device name of a connector: "connector_<its name in the kind>".
std::string connector_device_name(std::string_view connector);

class WorldAccess {
 public:
  explicit WorldAccess(MujocoWorld& world);
  WorldAccess(const WorldAccess&) = delete;
  WorldAccess& operator=(const WorldAccess&) = delete;

  // Runs fn(world) under the world's lock and returns true; false (fn not run) once closed.
  template <class F>
  bool with_world(F&& fn) {
    std::lock_guard lock(world_mu_);
    if (world_ == nullptr) return false;
    fn(*world_);
    return true;
  }
  // Under the world lock (inside with_world): the docking log's entries since the last call.
  std::vector<DockEvent> take_dock_events(const MujocoWorld& world);
  // The world is gone: with_world() runs nothing from now on. Detaches every node.
  void close();

  std::size_t module_count() const { return modules_; }
  // Throws std::out_of_range for a bad module.
  std::size_t connector_count(std::size_t module) const { return connector_names_.at(module).size(); }
  // The node whose log hears of module `module`'s docking changes; null detaches it. Throws
  // std::out_of_range for a bad module.
  void set_node(std::size_t module, os::Node* node);
  // Writes `events` to the logs of the nodes of the modules they name: a latch or an unlatch to
  // both (info), a refusal to the asking module's (warning). The source is the connector's device
  // name (connector_device_name).
  void log_dock_events(const std::vector<DockEvent>& events);
  // Writes one line to module `module`'s node log, when it has a node.
  void log(std::size_t module, os::LogLevel level, std::string_view source, std::string_view text);
  // ... to every node's log.
  void log_all(os::LogLevel level, std::string_view source, std::string_view text);

 private:
  std::mutex world_mu_;  // world_, cursor_
  MujocoWorld* world_;
  std::size_t cursor_ = 0;  // docking-log entries handed over so far
  const std::size_t modules_;
  // The world's names, copied once (they never change): "a", and "a.front" per connector.
  std::vector<std::string> module_names_;
  std::vector<std::vector<std::string>> connector_names_;
  std::mutex node_mu_;  // nodes_, and held while writing to their logs
  std::vector<os::Node*> nodes_;
};

}  // namespace symb::sim::mujoco
