#include "symb/sim/hil_robot_board.hpp"

#include <stdexcept>

#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/periodic_runner.hpp"

namespace symb::sim {

struct HilRobotBoard::Shared {
  std::mutex mu;  // pending_tick, have_pending, pending
  std::uint64_t pending_tick = 0;
  bool have_pending = false;
  IrReadings pending{};  // the newest IR frame's readings
  std::shared_ptr<SimIrSensor> ir;
  std::shared_ptr<SimWheels> wheels;
};

// Where the WorldRunner stands in process: the same priority and period; tick k publishes the IR
// frame meant for it, when it came.
class HilRobotBoard::Clock final : public PeriodicRunner {
 public:
  Clock(kernel::Executor& executor, std::shared_ptr<Shared> shared, PeriodicRunner::Options options)
      : PeriodicRunner(executor, options), shared_(std::move(shared)) {}
  ~Clock() override { halt(); }

  // Ticks run so far (the clock's own count: ticks() counts the same, but atomically for others).
  std::uint64_t tick() const { return tick_; }

 private:
  kernel::Status step_once(kernel::Time now) override {
    ++tick_;
    IrReadings readings;
    {
      std::lock_guard lock(shared_->mu);
      if (!shared_->have_pending || shared_->pending_tick != tick_) return {};
      readings = shared_->pending;
      shared_->have_pending = false;
    }
    shared_->ir->publish_readings(readings, now);
    return {};
  }

  std::shared_ptr<Shared> shared_;
  std::uint64_t tick_ = 0;
};

std::string describe(const HilRobotBoardStats& s) {
  return "frames " + std::to_string(s.frames) + " good, " + std::to_string(s.bad_frames()) + " bad (crc " +
         std::to_string(s.decoder.crc_errors) + ", malformed " + std::to_string(s.malformed) + "), " +
         std::to_string(s.missed) + " missed, " + std::to_string(s.out_of_order) + " out of order; answers " +
         std::to_string(s.answers) + ", not taken " + std::to_string(s.write_errors) + "; runs " +
         std::to_string(s.handshakes > 0 ? 1 + s.restarts : 0) + "; link lost " + std::to_string(s.link_losses) +
         ", back " + std::to_string(s.link_recoveries);
}

HilRobotBoard::HilRobotBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                             HilRobotBoardOptions options)
    : executor_(executor),
      port_(std::move(port)),
      options_(std::move(options)),
      shared_(std::make_shared<Shared>()),
      sequence_(options_.control_period * options_.lost_periods),
      buf_(4096) {
  if (options_.control_period <= kernel::Duration{0} || options_.control_period > std::chrono::seconds(1))
    throw std::invalid_argument("HilRobotBoard: the control period must be in (0, 1 s]");
  if (options_.lost_periods <= 0) throw std::invalid_argument("HilRobotBoard: lost_periods must be positive");
  // Only this board's thread touches the devices: serve() runs the node, and a shell's commands
  // reach them as work injected into the same executor.
  shared_->ir = std::make_shared<SimIrSensor>("ir", robot::DeviceThreads::kOneAtATime);
  shared_->wheels = std::make_shared<SimWheels>("wheels", robot::DeviceThreads::kOneAtATime);
  PeriodicRunner::Options co;
  co.period = options_.control_period;
  co.name = "link";
  clock_ = std::make_unique<Clock>(executor_, shared_, co);
}

HilRobotBoard::~HilRobotBoard() { clock_.reset(); }

RobotDevices HilRobotBoard::devices() const {
  RobotDevices d;
  d.ir = shared_->ir;
  d.wheels = shared_->wheels;
  return d;
}

std::vector<std::shared_ptr<io::Device>> HilRobotBoard::device_list() const { return {shared_->ir, shared_->wheels}; }

kernel::Status HilRobotBoard::start() {
  if (started_) return kernel::Error{"the board's clock is already running"};
  if (!port_->is_open())
    if (auto st = port_->open(); !st) return kernel::Error{"cannot open the serial line: " + st.error()};
  started_ = true;
  sequence_.start(wall_.now());
  return clock_->start();
}

void HilRobotBoard::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

void HilRobotBoard::answer(std::uint32_t seq) {
  const std::vector<float> out = shared_->wheels->output();
  HilWheelFrame w;
  w.seq = seq;
  if (out.size() == 2) {
    w.left = out[0];
    w.right = out[1];
  }
  frame_.clear();
  io::encode_frame(encode_wheel_payload(w), frame_);
  const bool ok = static_cast<bool>(port_->write_all(frame_));
  std::lock_guard lock(stats_mu_);
  ++(ok ? stats_.answers : stats_.write_errors);
}

void HilRobotBoard::handle(std::span<const std::byte> payload, std::size_t& handled) {
  auto f = decode_ir_payload(payload);
  if (!f) {
    std::lock_guard lock(stats_mu_);
    ++stats_.malformed;
    return;
  }
  const io::SequenceStep step = sequence_.on_frame(f->seq, wall_.now());
  if (!step.accepted) {
    std::lock_guard lock(stats_mu_);
    ++stats_.out_of_order;
    return;
  }
  if (!step.note_restart.empty()) event(step.note_restart + "; its run goes on from this node's time");
  if (!step.note_link.empty()) event(step.note_link);
  {
    std::lock_guard lock(stats_mu_);
    stats_.missed += step.missed;
    stats_.last_seq = f->seq;
    if (step.recovered) ++stats_.link_recoveries;
    if (f->seq == 0) ++(step.restart ? stats_.restarts : stats_.handshakes);
  }
  if (f->seq == 0) {
    if (step.restart) {
      // The new run's frame k is k ticks after the last tick the node ran.
      base_tick_ = clock_->tick();
      std::lock_guard lock(shared_->mu);
      shared_->have_pending = false;
    }
    answer(0);  // the handshake's answer, never applied
    return;
  }
  const std::uint64_t tick = base_tick_ + f->seq;
  {
    std::lock_guard lock(shared_->mu);
    shared_->pending_tick = tick;
    shared_->pending = f->ir;
    shared_->have_pending = true;
  }
  // Everything the node does before the world's next step: up to just before tick `tick` + 1.
  const kernel::Time until = options_.control_period * static_cast<std::int64_t>(tick + 1) - kernel::Duration{1};
  executor_.run_until(until);
  answer(f->seq);
  ++handled;
  std::lock_guard lock(stats_mu_);
  ++stats_.frames;
}

kernel::Result<std::size_t> HilRobotBoard::serve(kernel::Duration timeout) {
  if (!started_) return kernel::Error{"the board's clock has not started"};
  std::size_t handled = 0;
  auto got = port_->read_some(buf_, timeout);
  if (!got) return kernel::Error{"the serial line is gone: " + got.error()};
  decoder_.feed(std::span<const std::byte>(buf_.data(), *got),
                [&](std::span<const std::byte> payload) { handle(payload, handled); });
  const kernel::Time now = wall_.now();
  const bool lost = sequence_.lost(now);
  if (lost) event(sequence_.lost_note(now));
  std::lock_guard lock(stats_mu_);
  stats_.bytes_in += *got;
  stats_.decoder = decoder_.stats();
  if (lost) ++stats_.link_losses;
  return handled;
}

HilRobotBoardStats HilRobotBoard::stats() const {
  std::lock_guard lock(stats_mu_);
  return stats_;
}

}  // namespace symb::sim
