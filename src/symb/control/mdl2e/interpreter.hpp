// The MDL2e interpreter: a pure, deterministic state machine over a verified byte-code Program.
// The caller (a controller task) calls step(now, inputs) at its control period and on each new
// sensor message; step never allocates, never throws and reads no clock of its own. It returns the
// active atom's primitive and wheel speeds plus the events of this step (components started,
// interrupted, timed out, completed, task actions to carry out, plan end).
//
// Semantics (docs/mdl2e.md): a component's timer starts when it is entered; at each step the
// active chain is checked from the plan down (outer before inner), the first component whose
// interrupt holds or whose timer has run out ends with everything inside it, and execution goes on
// with its next sibling; a behaviour's body runs once, or again and again with `loop`; when the
// plan ends the output is `stop` from then on.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "symb/control/mdl2e/bytecode.hpp"
#include "symb/kernel/time.hpp"

namespace symb::control::mdl2e {

// What the basic interrupts are computed from: the flat sensor vector (layout: Program::channels;
// a slot beyond its end reads as "condition false") and the external interrupt bits.
struct InterruptInputs {
  std::span<const double> sensors;
  std::uint64_t external = 0;
};

enum class EventKind : std::uint8_t {
  kStarted,          // a component was entered
  kInterrupted,      // its interrupt held: it ended, with everything inside it
  kTimedOut,         // its timer ran out
  kCompleted,        // a behaviour's body finished (the last pass, if it loops)
  kTaskAction,       // carry out task_action on the task called `name`
  kDeviceAction,     // send `command` (with `argument` when has_argument) to the device called `name`
  kPlanEnded,        // the plan is over; output is stop from now on
  kTransitionLimit,  // too many transitions in one step; the rest waits for the next step
};
std::string_view event_kind_name(EventKind kind);

struct Event {
  EventKind kind = EventKind::kStarted;
  std::uint16_t node = kNoIndex;
  std::string_view name;  // the node's name (for kTaskAction: the task's name; kDeviceAction: the device's)
  TaskAction task_action = TaskAction::kStart;
  std::string_view command;  // kDeviceAction
  bool has_argument = false;
  float argument = 0;
};

inline constexpr std::size_t kMaxEventsPerStep = 32;

struct Output {
  bool running = false;           // false once the plan has ended
  std::uint16_t atom = kNoIndex;  // the active atom's node, or kNoIndex
  Primitive primitive = Primitive::kStop;
  std::string_view primitive_name = "stop";
  std::array<double, 2> params{};  // the primitive's arguments
  std::uint8_t param_count = 0;
  double left = 0;  // wheel speeds from the primitive table
  double right = 0;
  std::array<Event, kMaxEventsPerStep> events{};
  std::uint8_t event_count = 0;
  std::uint16_t events_dropped = 0;  // events beyond kMaxEventsPerStep in this step

  std::span<const Event> event_list() const { return {events.data(), event_count}; }
};

class Interpreter {
 public:
  // `program` must be verified (compile() and decode() do so) and outlive the interpreter.
  explicit Interpreter(const Program& program);

  // Advances to time `now` with these inputs. The first call enters the plan at `now`.
  // Times before the last step's are treated as equal to it.
  Output step(kernel::Time now, const InterruptInputs& inputs);

  // Back to before the first step.
  void reset();
  bool started() const { return started_; }
  bool ended() const { return ended_; }
  // The active chain, plan first.
  std::span<const std::uint16_t> active_path() const { return {path_.data(), depth_}; }

 private:
  struct Frame {
    kernel::Time start{};
    std::uint16_t passes = 0;
  };
  bool basic(std::uint8_t index, const InterruptInputs& in) const;
  bool eval(std::uint16_t offset, const InterruptInputs& in) const;
  void emit(Output& out, EventKind kind, std::uint16_t node) const;
  void enter(std::uint16_t node, kernel::Time now, Output& out);
  void finish_child(std::uint16_t child, kernel::Time now, Output& out);

  const Program* p_;
  std::array<std::uint16_t, kMaxDepth> path_{};
  std::array<Frame, kMaxDepth> frames_{};
  std::size_t depth_ = 0;
  kernel::Time last_{};
  bool started_ = false;
  bool ended_ = false;
};

}  // namespace symb::control::mdl2e
