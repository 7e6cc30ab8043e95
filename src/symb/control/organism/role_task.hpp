// RoleTask: cell specialization (paper section VI-B). Each module of an organism takes its role
// from local information only, the way a cell of an embryo does: which of its faces are docked.
// In a chain whose modules dock back to front, the module with only its back docked leads (the
// head), the one with only its front docked ends it (the tail), the ones docked at both ends are
// the spine; a module docked at a side is a branch, one docked nowhere is alone. Each role names
// the tasks it runs; on taking a role the module starts or resumes that role's tasks and suspends
// every other task any role names, so one module's node holds every role's controller and the
// role decides which run.
//
//   in  any port, from the connector sensor tasks named by `front`, `back`, `left`, `right`:
//       [state (0 free, 1 aligned, 2 docked), open, peer, ...] (the 3D connector devices' reading;
//       the first three are read)
//   out port 0: [role index] at every tick (kRoleNames order)
//
// Docking and undocking take a moment to settle (a latch is refused, a neighbour moves off), so a
// new role is taken only when the faces have shown it for `settle`. Senders that are not one of
// the four connector tasks, and malformed readings, are counted and ignored. Missing role tasks
// are warned about (at most once a second) and counted; the role is taken all the same.
//
// Completion (self-assembly, docs/organism.md): with `size` > 0 the module also counts the modules
// of its organism from their heartbeats: every tick it sends [module, place] on port 1 (`module`
// its own index, the number its neighbours' connectors report as their peer; `place` its place in
// the chain, 0 for a module whose front is free, else its front peer's place + 1, -1 while that
// is not known), hooked over the organism bus to the other modules' role tasks. The bus carries
// only within a docked component, so what a module hears is its own organism: local information.
// While docked (any role but alone) and hearing size - 1 others within `heard_timeout`, the module
// runs the `complete` tasks instead of its role's. `place_param` ("TASK.PARAM", e.g. "osc.id")
// is set to the module's place whenever that becomes known or changes, so a chain's oscillators
// number themselves from the head whatever the order they docked in.
// Probe "role": [role index, docked faces as bits front 1, back 2, left 4, right 8].
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/counter.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control::organism {

enum class Role : std::uint8_t { kAlone, kHead, kSpine, kTail, kBranch };
inline constexpr std::array<std::string_view, 5> kRoleNames = {"alone", "head", "spine", "tail", "branch"};
inline constexpr os::Port kRolePort = 0;
inline constexpr os::Port kRoleHeartbeatPort = 1;

// Docked faces, as bits.
inline constexpr unsigned kFront = 1, kBack = 2, kLeft = 4, kRight = 8;

// The role a module with these docked faces takes (the rule above).
Role role_of(unsigned docked_faces);

struct RoleOptions {
  std::string front = "connector_front";
  std::string back = "connector_back";
  std::string left = "connector_left";
  std::string right = "connector_right";
  // The tasks each role runs: names separated by spaces.
  std::string alone, head, spine, tail, branch;
  kernel::Duration settle = std::chrono::milliseconds(200);
  int size = 0;               // modules of the complete organism; 0: no count, no heartbeats
  int module = 0;             // this module's index (what its neighbours' connectors report)
  std::string complete{};     // tasks run while docked in a complete organism
  std::string place_param{};  // "TASK.PARAM" given this module's place in the chain; empty: none
  kernel::Duration heard_timeout = std::chrono::milliseconds(500);
};

struct RoleStats {
  std::uint64_t changes = 0;        // roles taken (the first one included)
  std::uint64_t readings = 0;       // connector readings taken
  std::uint64_t ignored = 0;        // malformed, or not from a connector task
  std::uint64_t missing_tasks = 0;  // a role's task that the node does not have
  std::uint64_t heartbeats = 0;     // heard from other modules
};

class RoleTask : public os::Task {
 public:
  // The role lists must hold task names; the error says which is not.
  static kernel::Result<std::unique_ptr<RoleTask>> create(RoleOptions options);

  // Any thread. Nothing before the first role is taken.
  std::optional<Role> role() const;
  RoleStats stats() const;
  // The modules heard from (itself included) and whether the organism is complete. Any thread.
  int organism_size() const { return heard_count_.load(std::memory_order_relaxed); }
  bool complete() const { return complete_.load(std::memory_order_relaxed); }
  int place() const { return place_.load(std::memory_order_relaxed); }

 protected:
  void on_message(const os::Message& m) override;
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  explicit RoleTask(RoleOptions options);
  // Per role, then the `complete` list last.
  static kernel::Result<std::array<std::vector<std::string>, 6>> role_tasks(const RoleOptions& o);
  void take(Role role, bool complete);
  void count_heard(kernel::Time t);

  RoleOptions o_;
  std::array<std::vector<std::string>, 6> tasks_;  // per role, then `complete`
  int front_peer_ = -1;
  struct Heard {
    kernel::Time at{0};
    int place = -1;
  };
  std::vector<std::pair<int, Heard>> heard_;  // per module heard, at most 4096
  std::atomic<int> heard_count_{1};
  std::atomic<bool> complete_{false};  // what the tasks taken are for
  bool running_complete_ = false;
  std::atomic<int> place_{-1};
  std::array<bool, 4> docked_{};  // front, back, left, right
  std::optional<Role> shown_;     // what the faces show now, and since when
  kernel::Time shown_since_{0};
  std::atomic<int> role_{-1};
  os::WarningLimiter warning_;
  struct Counters {
    kernel::Counter changes, readings, ignored, missing_tasks, heartbeats;
  } counters_;
};

}  // namespace symb::control::organism
