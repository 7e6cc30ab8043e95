// Mdl2eTask: the MDL2e controller task (paper Fig. 3 and section V-A). It sits between a sensor
// task and an actuator task, stepping a compiled MDL2e program's interpreter with the newest sensor
// vector and sending the wheel speeds of the active atom:
//
//   stream task -> sensor task --port 0--> Mdl2eTask --port 0--> actuator task
//                                          ^ port 1: external interrupt bits
//
// Contract (docs/mdl2e.md, "The controller task"):
//  - In, port 0 (kSensorPort): the program's flat sensor vector, exactly Program::sensor_count
//    finite numbers (7 for `sensor ir[7]`). Anything else (wrong count, NaN or infinity, a blob)
//    is counted and ignored, with a warning at a limited rate; the last good vector stays in use.
//  - In, port 1 (kExternalPort): [bit, 0 or 1] sets or clears external interrupt bit `bit` (0..63,
//    the program's `external` interrupts in declaration order). Malformed ones are ignored too.
//    Messages on other ports are ignored.
//  - Steps: at every tick (its TaskOptions period; the task type's default is 30 ms), and at once
//    on every good input message (a sensor vector, an external bit), so a new reading is acted on
//    at the instant it arrives. A tick does not step when an input message is already waiting in
//    the queue (that message steps right after, at the same instant) or when a step was already
//    taken at this instant. So when a vector and a tick meet at one instant, what happens depends
//    on who runs first, which under virtual time is the higher priority:
//      - the sensor task above the controller (the type defaults: 1 and 0): the vector comes
//        before the tick, one step, on the newest data (should a message waiting in the queue at
//        the tick turn out to be bad, the tick's step is taken then);
//      - the controller above the sensor: the tick steps on the previous vector, then the vector
//        steps again; two commands at one instant, the last one computed from the newest data.
//  - Takes its messages at once (Task::take_messages_at_once): under a non-concurrent executor a
//    vector sent from the sensor task's handler is handled, and the wheel command sent, inside that
//    send; a robot's step spares the controller's queue round trip and its input event.
//  - Start: the plan is entered at the first good sensor vector; until then ticks send nothing
//    (no wheel command is better than one computed from no data; an actuator watchdog stops the
//    wheels). A program that declares no sensors starts at its first tick or input message.
//  - Out, port 0 (kWheelPort): [left, right] after every step, each clamped to +-speed_limit
//    (Thymio motor units; default 500), never NaN (a non-finite speed is sent as 0).
//  - Task actions (`task start|suspend|resume|delete NAME`) are carried out at once on this task's
//    node (found by name); a missing task or a refused action is a warning, never a fault.
//  - Plan end: logged once; from then on every step sends [0, 0].
//  - Suspended, it handles nothing and sends nothing; node time keeps running, so on resume the
//    program's timers that ran out meanwhile end at the first step (at their deadlines).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/control/mdl2e/bytecode.hpp"
#include "symb/control/mdl2e/interpreter.hpp"
#include "symb/io/device.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control {

inline constexpr os::Port kSensorPort = 0;
inline constexpr os::Port kExternalPort = 1;
inline constexpr os::Port kWheelPort = 0;

// The device a `device NAME COMMAND` action names, or null when the node has none by that name.
using DeviceLookup = std::function<std::shared_ptr<io::Device>(std::string_view name)>;

struct Mdl2eTaskOptions {
  double speed_limit = 500;  // > 0
  kernel::Duration warn_interval = std::chrono::seconds(1);
};

// The mdl2e task type's parameters: the task's options and the program to read.
struct Mdl2eParams : Mdl2eTaskOptions {
  std::string program;  // a reference the node resolves (ControlResources::read_program)
};

struct Mdl2eStats {
  std::uint64_t steps = 0;                 // interpreter steps (each sent one wheel command)
  std::uint64_t tick_steps = 0;            // ... of them at a tick
  std::uint64_t skipped_ticks = 0;         // ticks at an instant that had already stepped
  std::uint64_t idle_ticks = 0;            // ticks before the first sensor vector
  std::uint64_t sensor_messages = 0;       // good sensor vectors
  std::uint64_t external_messages = 0;     // good external bit messages
  std::uint64_t ignored = 0;               // every message ignored, the sum of the next four
  std::uint64_t wrong_count = 0;           // a sensor vector of the wrong length
  std::uint64_t not_finite = 0;            // a sensor vector with NaN or infinity
  std::uint64_t bad_external = 0;          // a malformed external bit message
  std::uint64_t other = 0;                 // a blob, or an unknown port
  std::uint64_t task_actions = 0;          // task and device actions carried out
  std::uint64_t task_action_failures = 0;  // missing task or device, refused action or command
  std::uint64_t clamped = 0;               // wheel speeds cut to the speed limit
};

// A snapshot for the shell and tests.
struct Mdl2eState {
  bool started = false;  // the plan was entered
  bool ended = false;    // the plan is over
  // The active chain, plan first, as names joined by '/' ("avoid/explore/forward"); atoms show
  // their primitive. Empty before the start and after the end.
  std::string active_path;
  float left = 0, right = 0;   // the last wheel command sent
  std::uint64_t external = 0;  // the external interrupt bits
  Mdl2eStats stats;
};

class Mdl2eTask : public os::Task {
 public:
  // Checks the program (verify(), and at most Payload::kInlineValues sensor values, the most one
  // message carries) and the options; the error says what is wrong.
  // `devices` finds the devices the program's `device` actions name (null or empty: there are
  // none, and every device action fails with a warning).
  static kernel::Result<std::unique_ptr<Mdl2eTask>> create(std::shared_ptr<const mdl2e::Program> program,
                                                           Mdl2eTaskOptions options = {}, DeviceLookup devices = {});

  const mdl2e::Program& program() const { return *program_; }
  // Safe from any thread.
  Mdl2eState state() const;
  Mdl2eStats stats() const;
  void prefetch(int level) const override;

 protected:
  void on_message(const os::Message& m) override;
  void on_tick() override;

 private:
  Mdl2eTask(std::shared_ptr<const mdl2e::Program> program, Mdl2eTaskOptions options, DeviceLookup devices);
  void step(bool at_tick);
  void carry_out(const mdl2e::Event& e);
  void carry_out_device(const mdl2e::Event& e);
  void action_failed(const std::string& what, const std::string& why);
  struct Counters;
  void ignore(kernel::Counter Counters::*counter, const std::string& why);

  std::shared_ptr<const mdl2e::Program> program_;
  Mdl2eTaskOptions options_;
  DeviceLookup devices_;
  mdl2e::Interpreter interpreter_;
  std::vector<double> sensors_;
  bool have_input_ = false;  // a sensor vector arrived (or the program needs none)
  bool stepped_ = false;
  kernel::Time last_step_{0};
  bool deferred_tick_ = false;  // a tick left its step to a message waiting at deferred_at_
  kernel::Time deferred_at_{0};
  bool plan_end_logged_ = false;
  os::WarningLimiter ignored_warning_;
  os::WarningLimiter action_warning_;
  os::WarningLimiter limit_warning_;

  struct Counters {  // kernel/counter.hpp
    // The ones of every step first, side by side (in a swarm each task is out of the cache at each step).
    kernel::Counter steps, tick_steps, clamped, sensor_messages, skipped_ticks, idle_ticks, external_messages, ignored,
        wrong_count, not_finite, bad_external, other, task_actions, task_action_failures;
    Mdl2eStats snapshot() const {
      return {.steps = steps.load(),
              .tick_steps = tick_steps.load(),
              .skipped_ticks = skipped_ticks.load(),
              .idle_ticks = idle_ticks.load(),
              .sensor_messages = sensor_messages.load(),
              .external_messages = external_messages.load(),
              .ignored = ignored.load(),
              .wrong_count = wrong_count.load(),
              .not_finite = not_finite.load(),
              .bad_external = bad_external.load(),
              .other = other.load(),
              .task_actions = task_actions.load(),
              .task_action_failures = task_action_failures.load(),
              .clamped = clamped.load()};
    }
  } counters_;
  mutable std::mutex mu_;  // what state() reads besides the counters: the fields below
  std::array<std::uint16_t, mdl2e::kMaxDepth> path_{};
  std::size_t depth_ = 0;
  float left_ = 0, right_ = 0;
  bool started_ = false, ended_ = false;
  std::uint64_t external_ = 0;  // written on the task's context only
};

}  // namespace symb::control
