#include "app/hil_tasks.hpp"

#include <bit>
#include <cmath>
#include <cstdio>
#include <string>

#include "symb/io/frame_sequence.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/ports.hpp"
#include "symb/robot/thymio_ir.hpp"

namespace symb::board {

namespace {

constexpr std::size_t kIrValues = robot::thymio::kIrCount;
constexpr float kWheelMax = 500.0f;
constexpr std::size_t kMaxFrame = 256;

// Numbers of a number frame ('N', float32 LE each) into `out`; how many, or -1 when the frame is
// not one or holds more than out.size().
int decode_numbers_into(std::span<const std::byte> frame, std::span<float> out) {
  if (frame.empty() || frame[0] != std::byte{'N'} || (frame.size() - 1) % 4 != 0) return -1;
  const std::size_t n = (frame.size() - 1) / 4;
  if (n > out.size()) return -1;
  for (std::size_t k = 0; k < n; ++k) {
    std::uint32_t bits = 0;
    for (std::size_t i = 0; i < 4; ++i) bits |= static_cast<std::uint32_t>(frame[1 + 4 * k + i]) << (8 * i);
    out[k] = std::bit_cast<float>(bits);
  }
  return static_cast<int>(n);
}

class LinkTask final : public os::Task {
 public:
  LinkTask(std::shared_ptr<io::IOStream> port, HilStats& stats)
      : port_(std::move(port)), stats_(stats), decoder_(kMaxFrame), bad_warning_(std::chrono::seconds(1)) {}

 protected:
  void on_start() override {
    if (!port_->is_open())
      if (auto st = port_->open(); !st) log(os::LogLevel::kWarn, "cannot open '" + port_->name() + "': " + st.error());
  }
  void on_tick() override {
    for (;;) {
      auto got = port_->read_some(in_, kernel::Duration{0});
      if (!got || *got == 0) break;
      decoder_.feed(std::span<const std::byte>(in_.data(), *got), [&](std::span<const std::byte> frame) {
        float v[1 + kIrValues];
        if (decode_numbers_into(frame, v) != static_cast<int>(1 + kIrValues)) {
          ++stats_.malformed;
          return;
        }
        send(robot::kDataPort, std::span<const float>(v, 1 + kIrValues));
      });
      stats_.decoder = decoder_.stats();
    }
    const std::uint64_t bad = stats_.decoder.dropped();
    if (bad > reported_bad_) {
      if (bad_warning_.note(now(), bad - reported_bad_)) {
        char buf[120];
        std::snprintf(buf, sizeof buf, "%lu bad frame(s) dropped (so far: crc %lu)",
                      static_cast<unsigned long>(bad_warning_.count()),
                      static_cast<unsigned long>(stats_.decoder.crc_errors));
        log(os::LogLevel::kWarn, buf);
      }
      reported_bad_ = bad;
    }
  }
  void on_message(const os::Message& m) override {
    const std::span<const float> v = m.numbers();
    std::array<std::byte, 1 + 4 * 3> payload{};
    payload[0] = std::byte{'N'};
    for (std::size_t k = 0; k < 3 && k < v.size(); ++k) {
      const auto bits = std::bit_cast<std::uint32_t>(v[k]);
      for (std::size_t i = 0; i < 4; ++i) payload[1 + 4 * k + i] = static_cast<std::byte>((bits >> (8 * i)) & 0xff);
    }
    const std::size_t n = io::encode_frame(payload, out_);
    const bool written = port_->is_open() && port_->write_all(std::span<const std::byte>(out_.data(), n));
    ++(written ? stats_.frames_written : stats_.frames_unsent);
  }

 private:
  std::shared_ptr<io::IOStream> port_;
  HilStats& stats_;
  io::FrameDecoder decoder_;
  os::WarningLimiter bad_warning_;
  std::uint64_t reported_bad_ = 0;
  std::array<std::byte, 64> in_{};
  std::array<std::byte, 64> out_{};
};

class IrTask final : public os::Task {
 public:
  IrTask(HilStats& stats, const HilOptions& o)
      : stats_(stats), sequence_(o.control_period * o.lost_periods), order_warning_(std::chrono::seconds(1)) {
    ranges_.fill(robot::ChannelRange{0.0f, static_cast<float>(robot::thymio::kIrMax)});
  }

 protected:
  void on_start() override { sequence_.start(now()); }

  void on_message(const os::Message& m) override {
    const std::span<const float> v = m.numbers();
    const float seq_f = v[0];
    bool nan = false;
    for (float x : v) nan = nan || std::isnan(x);
    if (nan || !(seq_f >= 0 && seq_f <= 16777215.0f && std::floor(seq_f) == seq_f)) {
      ++stats_.malformed;
      return;
    }
    const auto seq = static_cast<std::uint32_t>(seq_f);
    const io::SequenceStep step = sequence_.on_frame(seq, now());
    if (!step.accepted) {
      ++stats_.out_of_order;
      if (order_warning_.note(now()))
        log(os::LogLevel::kWarn,
            std::to_string(order_warning_.count()) + " out-of-order frame(s) dropped, latest: " + step.out_of_order);
      return;
    }
    if (!step.note_restart.empty()) log(os::LogLevel::kInfo, step.note_restart);
    if (!step.note_link.empty()) log(os::LogLevel::kInfo, step.note_link);
    float out[kIrValues];
    const robot::Conditioned c = robot::condition_sample(ranges_, v.subspan(1), out);
    ++stats_.ir_frames;
    stats_.missed += step.missed;
    stats_.restarts += step.restart ? 1 : 0;
    stats_.clamped += c.clamped;
    stats_.link_recoveries += step.recovered ? 1 : 0;
    stats_.link_up = true;
    stats_.last_seq = seq;
    send(robot::kDataPort, std::span<const float>(out, kIrValues));
  }

  void on_tick() override {
    if (!sequence_.lost(now())) return;
    ++stats_.link_losses;
    stats_.link_up = false;
    log(os::LogLevel::kWarn, sequence_.lost_note(now()));
  }

 private:
  HilStats& stats_;
  std::array<robot::ChannelRange, kIrValues> ranges_;
  io::FrameSequence sequence_;
  os::WarningLimiter order_warning_;
};

class WheelsTask final : public os::Task {
 public:
  WheelsTask(HilStats& stats, const HilOptions& o)
      : stats_(stats),
        timeout_(std::chrono::duration_cast<kernel::Duration>(o.control_period * o.watchdog_periods)),
        reject_warning_(std::chrono::seconds(1)),
        timeout_warning_(std::chrono::seconds(1)) {
    ranges_.fill(robot::ChannelRange{-kWheelMax, kWheelMax});
  }

 protected:
  void on_start() override { last_command_ = now(); }

  void on_message(const os::Message& m) override {
    float out[2];
    robot::Conditioned c;
    if (m.payload.blob)
      c.fault = robot::SampleFault::kWrongCount;
    else
      c = robot::condition_sample(ranges_, m.numbers(), out);
    if (!c.ok()) {
      ++stats_.wheel_rejected;
      if (reject_warning_.note(now()))
        log(os::LogLevel::kWarn, std::to_string(reject_warning_.count()) + " wheel command(s) refused, latest: " +
                                     robot::to_string(c.fault) + "; previous speeds kept");
      return;
    }
    last_command_ = now();
    timed_out_ = false;
    ++stats_.wheel_commands;
    stats_.wheel_clamped += c.clamped;
    send(robot::kDataPort, {static_cast<float>(stats_.last_seq), out[0], out[1]});
  }

  void on_tick() override {
    if (timeout_.count() <= 0 || timed_out_ || now() - last_command_ < timeout_) return;
    timed_out_ = true;
    ++stats_.watchdog_stops;
    send(robot::kDataPort, {static_cast<float>(stats_.last_seq), 0.0f, 0.0f});
    if (timeout_warning_.note(now()))
      log(os::LogLevel::kWarn, std::to_string(timeout_warning_.count()) + " timeout(s): no command for " +
                                   std::to_string(kernel::to_milliseconds(timeout_)) + " ms, wheels stopped");
  }

 private:
  HilStats& stats_;
  std::array<robot::ChannelRange, 2> ranges_;
  const kernel::Duration timeout_;
  os::WarningLimiter reject_warning_;
  os::WarningLimiter timeout_warning_;
  kernel::Time last_command_{0};
  bool timed_out_ = false;
};

}  // namespace

kernel::Status make_hil_tasks(os::Node& node, std::shared_ptr<io::IOStream> port, HilStats& stats,
                              const HilOptions& options) {
  os::TaskOptions link_options;
  link_options.period = options.poll;
  link_options.queue_capacity = 2;
  os::TaskOptions device_options;
  device_options.period = options.control_period;
  device_options.queue_capacity = 2;
  auto link = node.create("link", std::make_unique<LinkTask>(std::move(port), stats), link_options);
  if (!link) return kernel::Error{"link: " + link.error()};
  auto ir = node.create("ir", std::make_unique<IrTask>(stats, options), device_options);
  if (!ir) return kernel::Error{"ir: " + ir.error()};
  auto wheels = node.create("wheels", std::make_unique<WheelsTask>(stats, options), device_options);
  if (!wheels) return kernel::Error{"wheels: " + wheels.error()};
  if (auto h = node.hook(*link, *ir); !h) return kernel::Error{"hook link -> ir: " + h.error()};
  if (auto h = node.hook(*wheels, *link); !h) return kernel::Error{"hook wheels -> link: " + h.error()};
  return {};
}

void format_board_stats(const HilStats& s, char* out, std::size_t size) {
  std::snprintf(out, size,
                "board-stats: good=%lu bad=%lu missed=%lu out_of_order=%lu malformed=%lu losses=%lu "
                "recoveries=%lu wheels=%lu watchdog=%lu sent=%lu unsent=%lu crc=%lu",
                static_cast<unsigned long>(s.ir_frames), static_cast<unsigned long>(s.bad_frames()),
                static_cast<unsigned long>(s.missed), static_cast<unsigned long>(s.out_of_order),
                static_cast<unsigned long>(s.malformed), static_cast<unsigned long>(s.link_losses),
                static_cast<unsigned long>(s.link_recoveries), static_cast<unsigned long>(s.wheel_commands),
                static_cast<unsigned long>(s.watchdog_stops), static_cast<unsigned long>(s.frames_written),
                static_cast<unsigned long>(s.frames_unsent), static_cast<unsigned long>(s.decoder.crc_errors));
}

}  // namespace symb::board
