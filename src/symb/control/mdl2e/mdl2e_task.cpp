#include "symb/control/mdl2e/mdl2e_task.hpp"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "symb/kernel/prefetch.hpp"
#include "symb/kernel/source_text.hpp"
#include "symb/os/message.hpp"
#include "symb/os/node.hpp"

namespace symb::control {

using kernel::Error;
using mdl2e::EventKind;

namespace {

std::string count_text(std::uint64_t n, const char* what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

// The wheel speed actually sent: finite, within +-limit. Counts a cut in `clamped`.
float condition_speed(double v, double limit, std::uint64_t& clamped) {
  if (!std::isfinite(v)) {
    ++clamped;
    return 0.0f;
  }
  if (v > limit || v < -limit) {
    ++clamped;
    v = std::clamp(v, -limit, limit);
  }
  return static_cast<float>(v);
}

}  // namespace

kernel::Result<std::unique_ptr<Mdl2eTask>> Mdl2eTask::create(std::shared_ptr<const mdl2e::Program> program,
                                                             Mdl2eTaskOptions options, DeviceLookup devices) {
  if (!program) return Error{"mdl2e controller: no program"};
  if (auto st = mdl2e::verify(*program); !st) return Error{"mdl2e controller: bad program: " + st.error()};
  if (program->sensor_count > os::Payload::kInlineValues)
    return Error{"mdl2e controller: the program reads " + std::to_string(program->sensor_count) +
                 " sensor values, more than one message carries (" + std::to_string(os::Payload::kInlineValues) + ")"};
  if (!std::isfinite(options.speed_limit) || options.speed_limit <= 0)
    return Error{"mdl2e controller: speed_limit must be a positive number"};
  if (options.warn_interval.count() < 0) return Error{"mdl2e controller: warn_interval must not be negative"};
  return std::unique_ptr<Mdl2eTask>(new Mdl2eTask(std::move(program), options, std::move(devices)));
}

Mdl2eTask::Mdl2eTask(std::shared_ptr<const mdl2e::Program> program, Mdl2eTaskOptions options, DeviceLookup devices)
    : program_(std::move(program)),
      options_(options),
      devices_(std::move(devices)),
      interpreter_(*program_),
      sensors_(program_->sensor_count, 0.0),
      have_input_(program_->sensor_count == 0) {
  bind_parameters(options_);
  take_messages_at_once();
}

void Mdl2eTask::prefetch(int level) const {
  // The interpreter's frames and this task's step state are in the object; the sensor vector
  // is a block of its own.
  if (level == 0)
    kernel::prefetch_bytes(this, sizeof(*this));
  else if (!sensors_.empty())
    kernel::prefetch_bytes(sensors_.data(), sensors_.size() * sizeof(double));
}

Mdl2eStats Mdl2eTask::stats() const { return counters_.snapshot(); }

Mdl2eState Mdl2eTask::state() const {
  std::lock_guard lock(mu_);
  Mdl2eState s;
  s.started = started_;
  s.ended = ended_;
  for (std::size_t k = 0; k < depth_; ++k) {
    if (k > 0) s.active_path += '/';
    s.active_path += program_->string(program_->nodes[path_[k]].name);
  }
  s.left = left_;
  s.right = right_;
  s.external = external_;
  s.stats = counters_.snapshot();
  return s;
}

void Mdl2eTask::ignore(kernel::Counter Counters::*counter, const std::string& why) {
  counters_.ignored.bump();
  (counters_.*counter).bump();
  if (ignored_warning_.note(now(), options_.warn_interval)) {
    log(os::LogLevel::kWarn, count_text(ignored_warning_.count(), "message") + " ignored, latest: " + why);
  }
  // A tick of this instant left its step to this message; it must not be lost to bad input.
  if (deferred_tick_ && deferred_at_ == now() && !(stepped_ && last_step_ == now())) step(true);
}

void Mdl2eTask::on_message(const os::Message& m) {
  if (m.payload.blob) {
    ignore(&Counters::other, "a blob on port " + std::to_string(m.port) + " (numbers expected)");
    return;
  }
  const std::span<const float> v = m.numbers();
  if (m.port == kSensorPort) {
    if (v.size() != sensors_.size()) {
      ignore(&Counters::wrong_count, "a sensor vector of " + std::to_string(v.size()) + " values; the program reads " +
                                         std::to_string(sensors_.size()));
      return;
    }
    for (std::size_t k = 0; k < v.size(); ++k)
      if (!std::isfinite(v[k])) {
        ignore(&Counters::not_finite, "a sensor vector with " + std::string(std::isnan(v[k]) ? "NaN" : "infinity") +
                                          " at index " + std::to_string(k) + " (previous vector kept)");
        return;
      }
    std::copy(v.begin(), v.end(), sensors_.begin());
    have_input_ = true;
    counters_.sensor_messages.bump();
    step(false);
    return;
  }
  if (m.port == kExternalPort) {
    const bool shape_ok =
        v.size() == 2 && v[0] >= 0 && v[0] <= 63 && std::floor(v[0]) == v[0] && (v[1] == 0.0f || v[1] == 1.0f);
    if (!shape_ok) {
      ignore(&Counters::bad_external, "an external interrupt message must be [bit 0..63, 0 or 1], got " +
                                          std::to_string(v.size()) + " value(s)");
      return;
    }
    const std::uint64_t bit = std::uint64_t{1} << static_cast<unsigned>(v[0]);
    {
      std::lock_guard lock(mu_);
      external_ = v[1] != 0.0f ? (external_ | bit) : (external_ & ~bit);
    }
    counters_.external_messages.bump();
    if (have_input_) step(false);
    return;
  }
  ignore(&Counters::other, "a message on port " + std::to_string(m.port) + " (sensor vectors on " +
                               std::to_string(kSensorPort) + ", external bits on " + std::to_string(kExternalPort) +
                               ")");
}

void Mdl2eTask::on_tick() {
  if (!have_input_) {
    counters_.idle_ticks.bump();
    return;
  }
  if (stepped_ && last_step_ == now()) {
    counters_.skipped_ticks.bump();
    return;
  }
  if (pending_messages() > 0) {
    deferred_tick_ = true;
    deferred_at_ = now();
    counters_.skipped_ticks.bump();
    return;
  }
  step(true);
}

void Mdl2eTask::step(bool at_tick) {
  const kernel::Time t = now();
  const mdl2e::Output out = interpreter_.step(t, {sensors_, external_});
  stepped_ = true;
  last_step_ = t;
  // A tick of this instant still to come would find this step and skip: the executor may leave
  // it out (one event fewer at every robot's step in a swarm), counted as the tick would count it.
  if (!at_tick) counters_.skipped_ticks.bump(skip_ticks_before(t + kernel::Duration{1}));
  for (const mdl2e::Event& e : out.event_list()) {
    if (e.kind == EventKind::kTaskAction) {
      carry_out(e);
    } else if (e.kind == EventKind::kDeviceAction) {
      carry_out_device(e);
    } else if (e.kind == EventKind::kPlanEnded && !plan_end_logged_) {
      plan_end_logged_ = true;
      log(os::LogLevel::kInfo,
          "plan '" + std::string(program_->string(program_->nodes[program_->root].name)) + "' ended; wheels stopped");
    } else if (e.kind == EventKind::kTransitionLimit && limit_warning_.note(t, options_.warn_interval)) {
      log(os::LogLevel::kWarn, count_text(limit_warning_.count(), "step") +
                                   " hit the transition limit; the program goes on at the next step");
    }
  }
  std::uint64_t clamped = 0;
  const float left = out.running ? condition_speed(out.left, options_.speed_limit, clamped) : 0.0f;
  const float right = out.running ? condition_speed(out.right, options_.speed_limit, clamped) : 0.0f;
  counters_.steps.bump();
  if (at_tick) counters_.tick_steps.bump();
  counters_.clamped.bump(clamped);
  // What state() reads is written under its lock only when it changed: this context is its only
  // writer, so it may compare without the lock, and a controller that keeps its course (most
  // steps) takes no lock at all.
  const auto path = interpreter_.active_path();
  const std::size_t depth = out.running ? path.size() : 0;
  if (!started_ || depth != depth_ || left != left_ || right != right_ || ended_ != !out.running ||
      !std::equal(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(depth), path_.begin())) {
    std::lock_guard lock(mu_);
    depth_ = depth;
    std::copy_n(path.begin(), depth_, path_.begin());
    left_ = left;
    right_ = right;
    started_ = true;
    ended_ = !out.running;
  }
  send(kWheelPort, {left, right});
}

void Mdl2eTask::carry_out(const mdl2e::Event& e) {
  os::Node& n = node();
  const std::string_view action = mdl2e::task_action_name(e.task_action);
  kernel::Status st;
  if (auto target = n.find(e.name)) {
    switch (e.task_action) {
      case mdl2e::TaskAction::kStart: {
        // Starting a task that already runs is what the program wants anyway.
        const auto info = n.info(*target);
        if (!info || info->state != os::TaskState::kRunning) st = n.start(*target);
        break;
      }
      case mdl2e::TaskAction::kSuspend: st = n.suspend(*target); break;
      case mdl2e::TaskAction::kResume: st = n.resume(*target); break;
      case mdl2e::TaskAction::kDelete: st = n.remove(*target); break;
    }
  } else {
    st = Error{"no task named '" + std::string(e.name) + "' on this node"};
  }
  if (!st) return action_failed("task " + std::string(action) + " " + std::string(e.name), st.error());
  counters_.task_actions.bump();
}

// An ioctl on the robot's own device: a connector's `latch` is how a program docks.
void Mdl2eTask::carry_out_device(const mdl2e::Event& e) {
  const std::string what = "device " + std::string(e.name) + " " + std::string(e.command) +
                           (e.has_argument ? " " + kernel::shortest_text(e.argument) : std::string());
  std::shared_ptr<io::Device> device = devices_ ? devices_(e.name) : nullptr;
  if (!device) return action_failed(what, "no device named '" + std::string(e.name) + "' on this robot");
  auto reply = device->ioctl(e.command, e.has_argument ? kernel::shortest_text(e.argument) : std::string());
  if (!reply) return action_failed(what, reply.error());
  counters_.task_actions.bump();
  log(os::LogLevel::kInfo, what + ": " + *reply);
}

void Mdl2eTask::action_failed(const std::string& what, const std::string& why) {
  counters_.task_action_failures.bump();
  if (!action_warning_.note(now(), options_.warn_interval)) return;
  log(os::LogLevel::kWarn, what + " not done: " + why +
                               (action_warning_.count() > 1
                                    ? " (" + count_text(action_warning_.count(), "failure") + " since the last warning)"
                                    : std::string()));
}

}  // namespace symb::control
