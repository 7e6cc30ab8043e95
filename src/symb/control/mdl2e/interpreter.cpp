#include "symb/control/mdl2e/interpreter.hpp"

namespace symb::control::mdl2e {

std::string_view event_kind_name(EventKind kind) {
  switch (kind) {
    case EventKind::kStarted: return "started";
    case EventKind::kInterrupted: return "interrupted";
    case EventKind::kTimedOut: return "timed_out";
    case EventKind::kCompleted: return "completed";
    case EventKind::kTaskAction: return "task_action";
    case EventKind::kDeviceAction: return "device_action";
    case EventKind::kPlanEnded: return "plan_ended";
    case EventKind::kTransitionLimit: return "transition_limit";
  }
  return "?";
}

Interpreter::Interpreter(const Program& program) : p_(&program) {}

void Interpreter::reset() {
  depth_ = 0;
  started_ = false;
  ended_ = false;
  last_ = {};
}

bool Interpreter::basic(std::uint8_t index, const InterruptInputs& in) const {
  const BasicInterrupt& b = p_->interrupts[index];
  if (b.external) return ((in.external >> b.slot) & 1u) != 0;
  if (b.slot >= in.sensors.size()) return false;
  const double v = in.sensors[b.slot];
  const double t = static_cast<double>(b.threshold);
  switch (b.cmp) {
    case Cmp::kLt: return v < t;
    case Cmp::kGt: return v > t;
    case Cmp::kLe: return v <= t;
    case Cmp::kGe: return v >= t;
  }
  return false;
}

bool Interpreter::eval(std::uint16_t offset, const InterruptInputs& in) const {
  std::array<bool, kMaxExprStack> st{};
  int sp = 0;
  const auto& code = p_->code;
  for (std::size_t i = offset; i < code.size();) {
    switch (static_cast<ExprOp>(code[i++])) {
      case ExprOp::kEnd: return sp > 0 && st[static_cast<std::size_t>(sp - 1)];
      case ExprOp::kBasic: st[static_cast<std::size_t>(sp++)] = basic(code[i++], in); break;
      case ExprOp::kTrue: st[static_cast<std::size_t>(sp++)] = true; break;
      case ExprOp::kFalse: st[static_cast<std::size_t>(sp++)] = false; break;
      case ExprOp::kNot: st[static_cast<std::size_t>(sp - 1)] = !st[static_cast<std::size_t>(sp - 1)]; break;
      case ExprOp::kAnd:
        --sp;
        st[static_cast<std::size_t>(sp - 1)] = st[static_cast<std::size_t>(sp - 1)] && st[static_cast<std::size_t>(sp)];
        break;
      case ExprOp::kOr:
        --sp;
        st[static_cast<std::size_t>(sp - 1)] = st[static_cast<std::size_t>(sp - 1)] || st[static_cast<std::size_t>(sp)];
        break;
    }
  }
  return false;
}

void Interpreter::emit(Output& out, EventKind kind, std::uint16_t node) const {
  if (out.event_count >= kMaxEventsPerStep) {
    ++out.events_dropped;
    return;
  }
  Event& e = out.events[out.event_count++];
  e = Event{};  // the array is reused from step to step: no field of an earlier event stays
  e.kind = kind;
  e.node = node;
  if (node != kNoIndex) {
    const Node& d = p_->nodes[node];
    e.name = p_->string(d.name);
    if (d.op == Op::kTask) e.task_action = static_cast<TaskAction>(d.arg);
    if (d.op == Op::kDevice) {
      e.command = p_->string(d.arg);
      e.has_argument = d.param_count == 1;
      e.argument = e.has_argument ? p_->params[d.param_offset] : 0.0f;
    }
  }
}

// Pushes `node` and, for a behaviour, its first child down to an atom or an action.
void Interpreter::enter(std::uint16_t node, kernel::Time now, Output& out) {
  for (;;) {
    path_[depth_] = node;
    frames_[depth_] = Frame{now, 0};
    ++depth_;
    const Node& d = p_->nodes[node];
    emit(out,
         d.op == Op::kTask     ? EventKind::kTaskAction
         : d.op == Op::kDevice ? EventKind::kDeviceAction
                               : EventKind::kStarted,
         node);
    if (d.op != Op::kBehaviour) return;
    node = d.first_child;
  }
}

// `child` has just ended and been popped; continue in its parent (the frame now on top).
void Interpreter::finish_child(std::uint16_t child, kernel::Time now, Output& out) {
  for (;;) {
    if (depth_ == 0) {
      ended_ = true;
      emit(out, EventKind::kPlanEnded, p_->root);
      return;
    }
    const std::uint16_t parent = path_[depth_ - 1];
    const Node& pd = p_->nodes[parent];
    std::uint16_t next = p_->nodes[child].next_sibling;
    if (next == kNoIndex && (pd.flags & kFlagLoop)) {
      Frame& f = frames_[depth_ - 1];
      if (f.passes < 0xFFFF) ++f.passes;
      if (pd.loop_count == 0 || f.passes < pd.loop_count) next = pd.first_child;
    }
    if (next != kNoIndex) {
      enter(next, now, out);
      return;
    }
    emit(out, EventKind::kCompleted, parent);
    --depth_;
    child = parent;
  }
}

Output Interpreter::step(kernel::Time now, const InterruptInputs& in) {
  Output out;
  if (started_ && now < last_) now = last_;
  last_ = now;
  if (!started_) {
    started_ = true;
    enter(p_->root, now, out);
  }
  // Each transition ends at least one component; a bound keeps one step short whatever the program.
  const std::size_t limit = 4 * p_->nodes.size() + 16;
  std::size_t transitions = 0;
  while (!ended_) {
    // Outer before inner: the first component in the chain that must end, ends.
    std::size_t i = 0;
    EventKind why = EventKind::kCompleted;
    for (; i < depth_; ++i) {
      const Node& d = p_->nodes[path_[i]];
      if (is_action(d.op)) {
        why = EventKind::kCompleted;  // an action is instantaneous; its event was emitted on entry
        break;
      }
      if (d.expr != kNoIndex && eval(d.expr, in)) {
        why = EventKind::kInterrupted;
        break;
      }
      if (d.duration_ms != 0 && now - frames_[i].start >= std::chrono::milliseconds(d.duration_ms)) {
        why = EventKind::kTimedOut;
        break;
      }
    }
    if (i == depth_) break;
    if (++transitions > limit) {
      emit(out, EventKind::kTransitionLimit, path_[i]);
      break;
    }
    const std::uint16_t node = path_[i];
    const Node& d = p_->nodes[node];
    // A component that times out ends at its deadline and its successor starts there, so timers
    // do not drift with the step period and several can run out in one late step.
    kernel::Time at = now;
    if (why == EventKind::kTimedOut) at = frames_[i].start + std::chrono::milliseconds(d.duration_ms);
    if (is_action(d.op)) at = frames_[i].start;
    if (!is_action(d.op)) emit(out, why, node);
    depth_ = i;
    finish_child(node, at, out);
  }
  out.running = !ended_;
  if (!ended_ && depth_ > 0) {
    const std::uint16_t top = path_[depth_ - 1];
    const Node& d = p_->nodes[top];
    if (d.op == Op::kAtom) {
      out.atom = top;
      out.primitive = static_cast<Primitive>(d.arg);
      out.primitive_name = primitives()[d.arg].name;
      out.param_count = d.param_count;
      std::array<float, 2> args{};
      for (std::size_t k = 0; k < d.param_count && k < 2; ++k) {
        args[k] = p_->params[d.param_offset + k];
        out.params[k] = static_cast<double>(args[k]);
      }
      primitive_wheels(out.primitive, std::span<const float>(args.data(), d.param_count), out.left, out.right);
    }
  }
  return out;
}

}  // namespace symb::control::mdl2e
