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
//       [state (0 free, 1 aligned, 2 docked), open, peer] (the 3D connector devices' reading)
//   out port 0: [role index] at every tick (kRoleNames order)
//
// Docking and undocking take a moment to settle (a latch is refused, a neighbour moves off), so a
// new role is taken only when the faces have shown it for `settle`. Senders that are not one of
// the four connector tasks, and malformed readings, are counted and ignored. Missing role tasks
// are warned about (at most once a second) and counted; the role is taken all the same.
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
};

struct RoleStats {
  std::uint64_t changes = 0;        // roles taken (the first one included)
  std::uint64_t readings = 0;       // connector readings taken
  std::uint64_t ignored = 0;        // malformed, or not from a connector task
  std::uint64_t missing_tasks = 0;  // a role's task that the node does not have
};

class RoleTask : public os::Task {
 public:
  // The role lists must hold task names; the error says which is not.
  static kernel::Result<std::unique_ptr<RoleTask>> create(RoleOptions options);

  // Any thread. Nothing before the first role is taken.
  std::optional<Role> role() const;
  RoleStats stats() const;

 protected:
  void on_message(const os::Message& m) override;
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  explicit RoleTask(RoleOptions options);
  static kernel::Result<std::array<std::vector<std::string>, 5>> role_tasks(const RoleOptions& o);
  void take(Role role);

  RoleOptions o_;
  std::array<std::vector<std::string>, 5> tasks_;  // per role
  std::array<bool, 4> docked_{};                   // front, back, left, right
  std::optional<Role> shown_;                      // what the faces show now, and since when
  kernel::Time shown_since_{0};
  std::atomic<int> role_{-1};
  os::WarningLimiter warning_;
  struct Counters {
    kernel::Counter changes, readings, ignored, missing_tasks;
  } counters_;
};

}  // namespace symb::control::organism
