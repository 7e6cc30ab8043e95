#include "symb/sim/board_link.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "symb/io/bytes.hpp"
#include "symb/io/fd_stream.hpp"
#include "symb/io/frame_sequence.hpp"
#include "symb/io/reopen_backoff.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/ports.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

namespace {

using LinkShared = BoardLink::Shared;

// The serial line. A StreamTask in frames mode that also copies its counters into the shared
// stats (at every message and tick) and reports bad frames in the node's log.
class HilLinkTask final : public io::StreamTask {
 public:
  HilLinkTask(std::shared_ptr<io::IOStream> port, std::shared_ptr<LinkShared> shared, const BoardLinkOptions& o)
      : io::StreamTask(std::move(port), Options{io::StreamMode::kFrames, 4096, 256, std::chrono::milliseconds(20)}),
        shared_(std::move(shared)),
        bad_warning_(o.warn_interval),
        backoff_(o.reopen_first, o.reopen_most),
        reopen_first_(o.reopen_first),
        reopen_most_(o.reopen_most) {}

 protected:
  void on_start() override {
    io::StreamTask::on_start();
    watch_line();
    refresh();
  }
  void on_message(const os::Message& m) override {
    if (!m.source.valid()) {  // from the line
      io::StreamTask::on_message(m);
      refresh();
      return;
    }
    // A wheel frame for the line: counted sent only when the line took it.
    bool written = false;
    if (stream().is_open()) {
      const std::uint64_t errors = stats().write_errors;
      io::StreamTask::on_message(m);
      written = stats().write_errors == errors;
    }
    {
      std::lock_guard lock(shared_->mu);
      ++(written ? shared_->stats.frames_written : shared_->stats.frames_unsent);
    }
    if (!written) watch_line();
    refresh();
  }
  void on_tick() override {
    watch_line();
    refresh();
  }
  void on_stop() override {
    io::StreamTask::on_stop();
    refresh();
  }

 private:
  // Notices a line that went away and reopens it by its path with backoff.
  void watch_line() {
    const kernel::Time t = now();
    if (stream().is_open()) {
      if (backoff_.down()) reopened(t);
      return;
    }
    if (!backoff_.down()) {
      backoff_.lost(t);
      const auto* fd = dynamic_cast<const io::FdStream*>(&stream());
      const std::string why = fd != nullptr ? fd->failure() : std::string();
      log(os::LogLevel::kWarn, "serial line '" + stream().name() + "' down" + (why.empty() ? "" : " (" + why + ")") +
                                   ": reopening it at once, then after " +
                                   std::to_string(kernel::to_milliseconds(reopen_first_)) + " ms, doubling up to " +
                                   std::to_string(kernel::to_milliseconds(reopen_most_)) + " ms");
    }
    if (!backoff_.due(t)) return;
    if (auto st = stream().open(); st) {
      reopened(t);
    } else {
      const kernel::Duration wait = backoff_.failed(t);
      log(os::LogLevel::kInfo, "reopen attempt " + std::to_string(backoff_.attempts()) + " failed: " + st.error() +
                                   "; next in " + std::to_string(kernel::to_milliseconds(wait)) + " ms");
    }
  }
  void reopened(kernel::Time t) {
    const kernel::Duration outage = backoff_.reopened(t);
    log(os::LogLevel::kInfo, "serial line '" + stream().name() + "' open again after " +
                                 std::to_string(kernel::to_milliseconds(outage)) + " ms (" +
                                 std::to_string(backoff_.attempts()) + " attempt(s))");
  }

  void refresh() {
    const io::StreamStats s = stats();
    const kernel::Time t = now();
    {
      std::lock_guard lock(shared_->mu);
      shared_->stats.bytes_in = s.bytes_in;
      shared_->stats.bytes_out = s.bytes_out;
      shared_->stats.write_errors = s.write_errors;
      shared_->stats.decoder = s.frames;
      shared_->stats.line_losses = backoff_.losses();
      shared_->stats.line_reopens = backoff_.reopens();
      shared_->stats.line_down = backoff_.down_for(t);
      shared_->stats.line_open = !backoff_.down() && s.open;
    }
    const std::uint64_t bad = s.frames.dropped();
    if (bad > reported_bad_) {
      if (bad_warning_.note(now(), bad - reported_bad_)) {
        char buf[200];
        std::snprintf(
            buf, sizeof buf,
            "%llu bad frame(s) dropped (so far: crc %llu, truncated %llu, encoding %llu, version %llu, "
            "oversized %llu)",
            static_cast<unsigned long long>(bad_warning_.count()), static_cast<unsigned long long>(s.frames.crc_errors),
            static_cast<unsigned long long>(s.frames.truncated), static_cast<unsigned long long>(s.frames.bad_encoding),
            static_cast<unsigned long long>(s.frames.bad_version), static_cast<unsigned long long>(s.frames.oversized));
        log(os::LogLevel::kWarn, buf);
      }
      reported_bad_ = bad;
    }
  }

  std::shared_ptr<LinkShared> shared_;
  os::WarningLimiter bad_warning_;
  io::ReopenBackoff backoff_;
  const kernel::Duration reopen_first_;
  const kernel::Duration reopen_most_;
  std::uint64_t reported_bad_ = 0;
};

// IR frames in, the 7 values out on port 0; sequence checks and the lost-link report.
class HilIrTask final : public os::Task {
 public:
  HilIrTask(std::shared_ptr<LinkShared> shared, const BoardLinkOptions& o)
      : shared_(std::move(shared)),
        channels_(SimIrSensor::channel_specs()),
        sequence_(o.control_period * o.lost_periods),
        malformed_warning_(o.warn_interval),
        order_warning_(o.warn_interval) {}

 protected:
  void on_start() override { sequence_.start(now()); }

  void on_message(const os::Message& m) override {
    const io::Bytes* bytes = io::bytes_of(m);
    if (bytes == nullptr && m.port == io::StreamTask::kEndPort) return;  // the line's loss: the link reports it
    auto frame = bytes ? decode_ir_payload(bytes->data) : kernel::Error{"a message without frame bytes"};
    if (!frame) {
      bump([](BoardLinkStats& s) { ++s.malformed; });
      if (malformed_warning_.note(now()))
        log(os::LogLevel::kWarn,
            std::to_string(malformed_warning_.count()) + " malformed frame(s), latest: " + frame.error());
      return;
    }
    const std::uint32_t seq = frame->seq;
    const io::SequenceStep step = sequence_.on_frame(seq, now());
    if (!step.accepted) {
      bump([](BoardLinkStats& s) { ++s.out_of_order; });
      if (order_warning_.note(now()))
        log(os::LogLevel::kWarn,
            std::to_string(order_warning_.count()) + " out-of-order frame(s) dropped, latest: " + step.out_of_order);
      return;
    }
    const std::uint64_t missed = step.missed;
    const bool restart = step.restart, recovered = step.recovered;
    if (!step.note_restart.empty()) log(os::LogLevel::kInfo, step.note_restart);
    if (!step.note_link.empty()) log(os::LogLevel::kInfo, step.note_link);

    float out[kIrCount];
    const robot::Conditioned c = robot::condition_sample(channels_, frame->ir, out);
    bump([&](BoardLinkStats& s) {
      ++s.ir_frames;
      s.missed += missed;
      s.restarts += restart ? 1 : 0;
      s.clamped += c.clamped;
      s.link_recoveries += recovered ? 1 : 0;
      s.link_up = true;
      s.last_seq = seq;
    });
    if (c.ok()) send(robot::kDataPort, std::span<const float>(out, kIrCount));
  }

  void on_tick() override {
    count_stale();
    if (!sequence_.lost(now())) return;
    bump([](BoardLinkStats& s) {
      ++s.link_losses;
      s.link_up = false;
    });
    log(os::LogLevel::kWarn, sequence_.lost_note(now()));
  }

  void on_stop() override { count_stale(); }

 private:
  template <class F>
  void bump(F&& f) {
    std::lock_guard lock(shared_->mu);
    f(shared_->stats);
  }

  // The frames this task's queue let go unhandled (a keep-newest hook overwrites the oldest):
  // the node's own books for the task, read here rather than counted twice.
  void count_stale() {
    const auto info = node().info(id());
    if (!info) return;
    const std::uint64_t stale = info->traffic.overwritten;
    bump([stale](BoardLinkStats& s) { s.stale = stale; });
  }

  std::shared_ptr<LinkShared> shared_;
  const std::vector<robot::ChannelSpec> channels_;
  io::FrameSequence sequence_;
  os::WarningLimiter malformed_warning_;
  os::WarningLimiter order_warning_;
};

// [left, right] in, [seq, left, right] out to the link; the watchdog stops a silent controller.
class HilWheelsTask final : public os::Task {
 public:
  HilWheelsTask(std::shared_ptr<LinkShared> shared, const BoardLinkOptions& o)
      : shared_(std::move(shared)),
        channels_(SimWheels::channel_specs()),
        timeout_(std::chrono::duration_cast<kernel::Duration>(o.control_period * o.watchdog_periods)),
        reject_warning_(o.warn_interval),
        clamp_warning_(o.warn_interval),
        timeout_warning_(o.warn_interval) {}

 protected:
  void on_start() override { last_command_ = now(); }

  void on_message(const os::Message& m) override {
    float out[2];
    robot::Conditioned c;
    if (m.payload.blob)
      c.fault = robot::SampleFault::kWrongCount;
    else
      c = robot::condition_sample(channels_, m.numbers(), out);
    if (!c.ok()) {
      {
        std::lock_guard lock(shared_->mu);
        ++shared_->stats.wheel_rejected;
      }
      if (reject_warning_.note(now()))
        log(os::LogLevel::kWarn, std::to_string(reject_warning_.count()) +
                                     " wheel command(s) refused, latest: " + robot::to_string(c.fault) + " (" +
                                     std::to_string(m.numbers().size()) + " values); previous speeds kept");
      return;
    }
    if (c.clamped > 0 && clamp_warning_.note(now(), c.clamped))
      log(os::LogLevel::kWarn, std::to_string(clamp_warning_.count()) + " wheel value(s) outside +-500, clamped");
    last_command_ = now();
    timed_out_ = false;
    transmit(out[0], out[1], [&](BoardLinkStats& s) {
      ++s.wheel_commands;
      s.wheel_clamped += c.clamped;
    });
  }

  void on_tick() override {
    if (timeout_.count() <= 0 || timed_out_ || now() - last_command_ < timeout_) return;
    // Once per silence, as the in-process actuator_sink does.
    timed_out_ = true;
    transmit(0.0f, 0.0f, [](BoardLinkStats& s) { ++s.watchdog_stops; });
    if (timeout_warning_.note(now()))
      log(os::LogLevel::kWarn, std::to_string(timeout_warning_.count()) + " timeout(s): no command for " +
                                   std::to_string(kernel::to_milliseconds(timeout_)) + " ms, wheels stopped");
  }

 private:
  template <class F>
  void transmit(float left, float right, F&& count) {
    std::uint32_t seq = 0;
    {
      std::lock_guard lock(shared_->mu);
      seq = shared_->stats.last_seq;
      count(shared_->stats);
    }
    send(robot::kDataPort, {static_cast<float>(seq), left, right});
  }

  std::shared_ptr<LinkShared> shared_;
  const std::vector<robot::ChannelSpec> channels_;
  const kernel::Duration timeout_;
  os::WarningLimiter reject_warning_;
  os::WarningLimiter clamp_warning_;
  os::WarningLimiter timeout_warning_;
  kernel::Time last_command_{0};
  bool timed_out_ = false;
};

}  // namespace

BoardLink::BoardLink(std::shared_ptr<io::IOStream> port, BoardLinkOptions options)
    : port_(std::move(port)), options_(options), shared_(std::make_shared<Shared>()) {}

std::shared_ptr<BoardLink> BoardLink::create(std::shared_ptr<io::IOStream> port, BoardLinkOptions options) {
  if (!port) throw std::invalid_argument("BoardLink: no port");
  if (options.control_period.count() <= 0 || options.lost_periods < 1 || !(options.watchdog_periods >= 0))
    throw std::invalid_argument("BoardLink: control period, lost_periods and watchdog_periods must be positive");
  if (options.reopen_first.count() <= 0 || options.reopen_most < options.reopen_first)
    throw std::invalid_argument("BoardLink: reopen_first must be positive and at most reopen_most");
  return std::shared_ptr<BoardLink>(new BoardLink(std::move(port), options));
}

kernel::Status BoardLink::make_device_tasks(os::Node& node) {
  os::TaskOptions link_options;
  link_options.period = options_.control_period;
  link_options.queue_capacity = 64;
  os::TaskOptions device_options;
  device_options.period = options_.control_period;
  device_options.queue_capacity = 8;
  auto link =
      node.create(std::string(kLinkTaskName), std::make_unique<HilLinkTask>(port_, shared_, options_), link_options);
  if (!link) return kernel::Error{"link: " + link.error()};
  os::TaskOptions ir_options = device_options;
  ir_options.ports = device_task_ports(kIrTaskName);
  auto ir = node.create(std::string(kIrTaskName), std::make_unique<HilIrTask>(shared_, options_), ir_options);
  if (!ir) return kernel::Error{"ir: " + ir.error()};
  os::TaskOptions wheel_options = device_options;
  wheel_options.ports = device_task_ports(kWheelsTaskName);
  auto wheels =
      node.create(std::string(kWheelsTaskName), std::make_unique<HilWheelsTask>(shared_, options_), wheel_options);
  if (!wheels) return kernel::Error{"wheels: " + wheels.error()};
  // Sensor data keeps the newest; wheel commands too: a stale speed is worth less than a new one.
  if (auto h = node.hook(*link, *ir); !h) return kernel::Error{"hook link -> ir: " + h.error()};
  if (auto h = node.hook(*wheels, *link); !h) return kernel::Error{"hook wheels -> link: " + h.error()};
  return {};
}

std::function<kernel::Status(os::Node&)> BoardLink::device_tasks() {
  return [self = shared_from_this()](os::Node& node) { return self->make_device_tasks(node); };
}

BoardLinkStats BoardLink::stats() const {
  std::lock_guard lock(shared_->mu);
  return shared_->stats;
}

std::string describe(const BoardLinkStats& s) {
  char buf[600];
  std::snprintf(
      buf, sizeof buf,
      "frames %llu good, %llu bad (crc %llu), %llu missed (%llu stale), %llu out of order; link %s (%llu lost, "
      "%llu back), last seq %u; wheels %llu commands, %llu refused, %llu watchdog stops; frames %llu "
      "sent, %llu not sent; serial line %s (%llu lost, %llu reopened, down %lld ms in all)",
      static_cast<unsigned long long>(s.ir_frames), static_cast<unsigned long long>(s.bad_frames()),
      static_cast<unsigned long long>(s.decoder.crc_errors), static_cast<unsigned long long>(s.missed),
      static_cast<unsigned long long>(s.stale), static_cast<unsigned long long>(s.out_of_order),
      s.link_up ? "up" : "down", static_cast<unsigned long long>(s.link_losses),
      static_cast<unsigned long long>(s.link_recoveries), static_cast<unsigned>(s.last_seq),
      static_cast<unsigned long long>(s.wheel_commands), static_cast<unsigned long long>(s.wheel_rejected),
      static_cast<unsigned long long>(s.watchdog_stops), static_cast<unsigned long long>(s.frames_written),
      static_cast<unsigned long long>(s.frames_unsent), s.line_open ? "open" : "DOWN",
      static_cast<unsigned long long>(s.line_losses), static_cast<unsigned long long>(s.line_reopens),
      static_cast<long long>(kernel::to_milliseconds(s.line_down)));
  return buf;
}

}  // namespace symb::sim
