#include "symb/sim/frame_clock_board.hpp"

#include <stdexcept>

#include "symb/sim/periodic_runner.hpp"

namespace symb::sim {

// Where the world's runner stands in process: the same priority and period. Tick k publishes the
// sensor frame meant for it, when it came.
class FrameClockBoard::Clock final : public PeriodicRunner {
 public:
  Clock(FrameClockBoard& board, PeriodicRunner::Options options)
      : PeriodicRunner(board.executor_, std::move(options)), board_(board) {}
  ~Clock() override { halt(); }

  // Ticks run so far (only the serving thread reads it, between runs of the executor).
  std::int64_t tick() const { return tick_; }
  // The frame for tick `tick`, published then.
  void hold(std::int64_t tick, std::vector<float> values) {
    pending_tick_ = tick;
    pending_ = std::move(values);
    have_pending_ = true;
  }
  void drop() { have_pending_ = false; }

 private:
  kernel::Status step_once(kernel::Time now) override {
    ++tick_;
    if (!have_pending_ || pending_tick_ != tick_) return {};
    have_pending_ = false;
    board_.publish(pending_, now);
    return {};
  }

  FrameClockBoard& board_;
  // Only the serving thread touches these: serve() and the executor it runs.
  std::int64_t tick_ = 0;
  std::int64_t pending_tick_ = 0;
  bool have_pending_ = false;
  std::vector<float> pending_;
};

std::string describe(const FrameClockStats& s, const std::string& answers_extra) {
  const auto n = [](std::uint64_t v) { return std::to_string(v); };
  return "frames " + n(s.frames) + " good, " + n(s.bad_frames()) + " bad (crc " + n(s.decoder.crc_errors) +
         ", malformed " + n(s.malformed) + "), " + n(s.missed) + " missed, " + n(s.out_of_order) + " out of order, " +
         n(s.jumps) + " jumps; answers " + n(s.answers) + answers_extra + ", not taken " + n(s.write_errors) +
         "; runs " + n(s.handshakes > 0 ? 1 + s.restarts : s.restarts) + "; link lost " + n(s.link_losses) + ", back " +
         n(s.link_recoveries);
}

FrameClockBoard::FrameClockBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                                 FrameClockBoardOptions options, std::string frame_name)
    : executor_(executor),
      port_(std::move(port)),
      options_(std::move(options)),
      sequence_(options_.control_period * options_.lost_periods, std::move(frame_name)),
      buf_(4096) {
  if (options_.control_period <= kernel::Duration{0} || options_.control_period > std::chrono::seconds(1))
    throw std::invalid_argument("the board's control period must be in (0, 1 s]");
  if (options_.lost_periods <= 0) throw std::invalid_argument("the board's lost_periods must be positive");
  if (options_.max_catch_up < 1) throw std::invalid_argument("the board's max_catch_up must be at least 1");
  PeriodicRunner::Options co;
  co.period = options_.control_period;
  co.name = "link";
  clock_ = std::make_unique<Clock>(*this, co);
}

FrameClockBoard::~FrameClockBoard() { stop_clock(); }

void FrameClockBoard::stop_clock() { clock_.reset(); }

kernel::Status FrameClockBoard::start() {
  if (started_) return kernel::Error{"the board's clock is already running"};
  if (!clock_) return kernel::Error{"the board's clock is gone"};
  if (!port_->is_open())
    if (auto st = port_->open(); !st) return kernel::Error{"cannot open the serial line: " + st.error()};
  started_ = true;
  sequence_.start(wall_.now());
  return clock_->start();
}

void FrameClockBoard::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

bool FrameClockBoard::send(const std::vector<std::byte>& payload) {
  frame_.clear();
  io::encode_frame(payload, frame_);
  return static_cast<bool>(port_->write_all(frame_));
}

void FrameClockBoard::handle(std::span<const std::byte> payload, std::size_t& handled) {
  auto f = decode(payload);
  if (!f) {
    std::lock_guard lock(stats_mu_);
    ++stats_.malformed;
    return;
  }
  const std::uint32_t seq = f->seq;
  const io::SequenceStep step = sequence_.on_frame(seq, wall_.now());
  if (!step.accepted) {
    std::lock_guard lock(stats_mu_);
    ++stats_.out_of_order;
    return;
  }
  if (!step.note_restart.empty()) event(step.note_restart + "; its run goes on from this node's time");
  if (!step.note_link.empty()) event(step.note_link);
  const std::int64_t now_tick = clock_->tick();
  bool jump = false;
  if (seq == 0) {
    if (step.restart) {
      // The new run's frame k is k ticks after the last tick the node ran.
      base_tick_ = now_tick;
      clock_->drop();
    }
  } else if (base_tick_ + seq > now_tick + static_cast<std::int64_t>(options_.max_catch_up)) {
    // Further ahead than the node may catch up with: this frame is the next tick's.
    jump = true;
    base_tick_ = now_tick + 1 - static_cast<std::int64_t>(seq);
    event("seq " + std::to_string(seq) + " is over " + std::to_string(options_.max_catch_up) +
          " periods ahead of the node: its clock moves one period, not all of them");
  }
  {
    std::lock_guard lock(stats_mu_);
    stats_.missed += step.missed;
    stats_.last_seq = seq;
    if (step.recovered) ++stats_.link_recoveries;
    if (jump) ++stats_.jumps;
    if (seq == 0) ++(step.restart ? stats_.restarts : stats_.handshakes);
  }
  if (seq != 0) {
    const std::int64_t tick = base_tick_ + seq;
    clock_->hold(tick, std::move(f).value().values);
    // Everything the node does before the world's next step: up to just before tick `tick` + 1.
    executor_.run_until(options_.control_period * (tick + 1) - kernel::Duration{1});
    ++handled;
  }
  // A handshake's answer is never applied; it tells the simulator that this board is there.
  const bool taken = answer(seq);
  std::lock_guard lock(stats_mu_);
  ++(taken ? stats_.answers : stats_.write_errors);
  if (seq != 0) ++stats_.frames;
}

kernel::Result<std::size_t> FrameClockBoard::serve(kernel::Duration timeout) {
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

FrameClockStats FrameClockBoard::link_stats() const {
  std::lock_guard lock(stats_mu_);
  return stats_;
}

}  // namespace symb::sim
