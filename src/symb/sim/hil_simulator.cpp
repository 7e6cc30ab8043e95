#include "symb/sim/hil_simulator.hpp"

#include <cstdio>
#include <stdexcept>
#include <thread>

#include "symb/io/fd_stream.hpp"
#include "symb/io/reopen_backoff.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

namespace {

using Clock = std::chrono::steady_clock;

std::string u(std::uint64_t v) { return std::to_string(v); }

}  // namespace

struct HilSimulator::Robot {
  io::FrameDecoder decoder{256};
  HilRobotStats stats;
  std::uint64_t quiet_steps = 0;  // steps since the last applied frame
  // A frame with seq 0 came: the board answered this run's handshake. Any other frame may be one
  // the board wrote for an earlier run (its watchdog's stop, with that run's last seq) that waited
  // on the line: it says nothing about whether the board has seen this run's seq 0.
  bool handshake_answered = false;
  io::ReopenBackoff backoff;
};

namespace {
kernel::Time steady_now() { return std::chrono::duration_cast<kernel::Duration>(Clock::now().time_since_epoch()); }
}  // namespace

std::string describe(const HilRobotStats& s) {
  return "sent " + u(s.frames_sent) + " (" + u(s.corrupted) + " corrupted, " + u(s.write_errors) + " not taken, " +
         u(s.unsent) + " not sent: line down); serial line " + (s.line_open ? "open" : "DOWN") + " (" +
         u(s.line_losses) + " lost, " + u(s.line_reopens) + " reopened, down " +
         u(static_cast<std::uint64_t>(kernel::to_milliseconds(s.line_down))) + " ms in all); received " +
         u(s.received) + " good, " + u(s.bad_frames()) + " bad; applied " + u(s.applied) + " (" + u(s.late) +
         " late), " + u(s.stale) + " stale, " + u(s.superseded) + " superseded, " + u(s.missing) +
         " steps without a new frame, " + u(s.silences) + " silences, " + u(s.recoveries) + " recoveries";
}

HilSimulator::HilSimulator(World& world, std::vector<std::shared_ptr<io::IOStream>> ports, HilSimulatorOptions options)
    : world_(world),
      options_(std::move(options)),
      dt_(std::chrono::duration<double>(options_.period).count()),
      hold_steps_(0),
      ports_(std::move(ports)),
      robots_(world.robot_count()),
      corruptor_(options_.corrupt, options_.seed, 0x48494c),
      buf_(4096) {
  if (ports_.size() != world.robot_count())
    throw std::invalid_argument("HilSimulator: " + u(ports_.size()) + " ports for " + u(world.robot_count()) +
                                " robots");
  for (const auto& p : ports_)
    if (!p) throw std::invalid_argument("HilSimulator: a port is missing");
  if (options_.period.count() <= 0 || options_.period > std::chrono::seconds(1))
    throw std::invalid_argument("HilSimulator: the period must be in (0, 1 s]");
  if (!(options_.corrupt >= 0 && options_.corrupt <= 1))
    throw std::invalid_argument("HilSimulator: corrupt must be in [0, 1]");
  if (options_.reopen_first.count() <= 0 || options_.reopen_most < options_.reopen_first)
    throw std::invalid_argument("HilSimulator: reopen_first must be positive and at most reopen_most");
  if (options_.lockstep && options_.answer_wait.count() <= 0)
    throw std::invalid_argument("HilSimulator: a lockstep run needs a positive answer_wait");
  hold_steps_ = static_cast<std::uint64_t>(std::max<std::int64_t>(1, options_.hold / options_.period));
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    robots_[i].stats.robot = world.robot_name(i);
    robots_[i].backoff = io::ReopenBackoff(options_.reopen_first, options_.reopen_most);
  }
}

HilSimulator::~HilSimulator() = default;

void HilSimulator::add_observer(StepObserver observer) { observers_.push_back(std::move(observer)); }

void HilSimulator::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

std::vector<HilRobotStats> HilSimulator::stats() const {
  std::lock_guard lock(stats_mu_);
  std::vector<HilRobotStats> out;
  out.reserve(robots_.size());
  for (const Robot& r : robots_) out.push_back(r.stats);
  return out;
}

kernel::Status HilSimulator::open_ports() {
  if (opened_) return {};
  for (auto& p : ports_) {
    if (!p->is_open())
      if (auto st = p->open(); !st) return kernel::Error{"cannot open '" + p->name() + "': " + st.error()};
    // What a previous run left in the line is not an answer to this one.
    (void)p->ioctl("flush");
    if (auto* fd = dynamic_cast<io::FdStream*>(p.get())) fd->set_write_timeout(options_.period / 4);
  }
  opened_ = true;
  return {};
}

void HilSimulator::send_ir(std::size_t i, std::uint32_t seq) {
  HilIrFrame f;
  f.seq = seq;
  f.ir = world_.ir(i);
  frame_.clear();
  io::encode_frame(encode_ir_payload(f), frame_);
  const bool hit = corruptor_.roll() && corrupt_frame(frame_, corruptor_.random());
  corruptor_.count(hit);
  // Into a line that is down nothing is written, and nothing is counted sent.
  const bool open = ports_[i]->is_open();
  const bool sent = open && ports_[i]->write_all(frame_).ok();
  std::lock_guard lock(stats_mu_);
  HilRobotStats& s = robots_[i].stats;
  s.frames_sent += sent ? 1 : 0;
  s.corrupted += sent && hit ? 1 : 0;
  s.write_errors += open && !sent ? 1 : 0;
  s.unsent += open ? 0 : 1;
}

void HilSimulator::watch_line(std::size_t i) {
  io::IOStream& port = *ports_[i];
  Robot& r = robots_[i];
  const kernel::Time t = steady_now();
  std::string note;
  if (!port.is_open()) {
    if (!r.backoff.down()) {
      r.backoff.lost(t);
      const auto* fd = dynamic_cast<const io::FdStream*>(&port);
      const std::string why = fd != nullptr ? fd->failure() : std::string();
      event("robot " + r.stats.robot + ": serial line '" + port.name() + "' down" +
            (why.empty() ? "" : " (" + why + ")") + ": reopening it with backoff");
    }
    if (r.backoff.due(t)) {
      if (auto st = port.open(); st) {
        (void)port.ioctl("flush");
        if (auto* fd = dynamic_cast<io::FdStream*>(&port)) fd->set_write_timeout(options_.period / 4);
        note = "robot " + r.stats.robot + ": serial line '" + port.name() + "' open again after " +
               std::to_string(kernel::to_milliseconds(r.backoff.reopened(t))) + " ms";
      } else {
        const kernel::Duration wait = r.backoff.failed(t);
        event("robot " + r.stats.robot + ": reopen attempt " + std::to_string(r.backoff.attempts()) +
              " failed: " + st.error() + "; next in " + std::to_string(kernel::to_milliseconds(wait)) + " ms");
      }
    }
  }
  {
    std::lock_guard lock(stats_mu_);
    r.stats.line_losses = r.backoff.losses();
    r.stats.line_reopens = r.backoff.reopens();
    r.stats.line_down = r.backoff.down_for(t);
    r.stats.line_open = !r.backoff.down();
  }
  if (!note.empty()) event(note);
}

std::optional<HilWheelFrame> HilSimulator::read_wheels(std::size_t i, bool& any_frame, std::uint32_t want,
                                                       kernel::Duration wait) {
  Robot& r = robots_[i];
  std::optional<HilWheelFrame> best;
  std::uint64_t received = 0, malformed = 0, stale = 0, superseded = 0;
  any_frame = false;
  const auto deadline = Clock::now() + wait;
  // A zero timeout polls; the loop ends as soon as nothing more is there, once the answer awaited
  // (if any) came or its wait ran out.
  for (int rounds = 0; rounds < 64;) {
    const bool awaiting = want > 0 && (!best || best->seq < want);
    const auto left = awaiting ? std::max(Clock::duration{0}, deadline - Clock::now()) : Clock::duration{0};
    auto got = ports_[i]->read_some(buf_, std::chrono::duration_cast<kernel::Duration>(left));
    if (!got) {
      // The line is gone (watch_line reopens it): nothing comes before the deadline, and a
      // lockstep run does not race through the outage.
      if (awaiting) std::this_thread::sleep_until(deadline);
      break;
    }
    if (*got == 0) {
      if (awaiting && Clock::now() < deadline) continue;
      break;
    }
    ++rounds;
    r.decoder.feed(std::span<const std::byte>(buf_.data(), *got), [&](std::span<const std::byte> payload) {
      auto f = decode_wheel_payload(payload);
      if (!f) {
        ++malformed;
        return;
      }
      ++received;
      any_frame = true;
      if (f->seq == 0) {  // an answer to the handshake: never applied
        r.handshake_answered = true;
        return;
      }
      // Older than one applied, or newer than any IR frame sent: the latter was written for an
      // earlier run, and applying it would make this run's answers look stale.
      if (f->seq < r.stats.last_applied || f->seq > seq_) {
        ++stale;
        return;
      }
      if (best) ++superseded;  // the one of the two not kept
      if (!best || f->seq >= best->seq) best = *f;
    });
  }
  std::lock_guard lock(stats_mu_);
  r.stats.received += received;
  r.stats.malformed += malformed;
  r.stats.stale += stale;
  r.stats.superseded += superseded;
  r.stats.decoder = r.decoder.stats();
  return best;
}

kernel::Status HilSimulator::wait_for_boards(kernel::Duration timeout) {
  if (auto st = open_ports(); !st) return st;
  const auto deadline = Clock::now() + timeout;
  auto due = Clock::now();
  // The handshake goes out again each period, or each answer wait in lockstep (a board kept off
  // its core for longer than a period would otherwise answer two); answers are looked for each
  // period.
  const auto resend_every = std::chrono::duration_cast<Clock::duration>(
      options_.lockstep ? std::max(options_.period, options_.answer_wait) : options_.period);
  auto resend = Clock::now();
  for (;;) {
    bool all = true;
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      watch_line(i);
      bool any = false;
      (void)read_wheels(i, any);
      bool answered = false;
      {
        std::lock_guard lock(stats_mu_);
        if (robots_[i].handshake_answered && !robots_[i].stats.answered) robots_[i].stats.answered = answered = true;
        all = all && robots_[i].stats.answered;
      }
      if (answered) event("robot " + robots_[i].stats.robot + ": board answered");
    }
    if (all) return {};
    if (stop_.load()) return kernel::Error{"stopped while waiting for the boards"};
    if (Clock::now() >= deadline) {
      std::string missing;
      for (const Robot& r : robots_)
        if (!r.stats.answered) missing += (missing.empty() ? "" : ", ") + r.stats.robot;
      return kernel::Error{"no answer from the board of " + missing + " within " +
                           u(std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count()) + " ms"};
    }
    if (Clock::now() >= resend) {
      for (std::size_t i = 0; i < robots_.size(); ++i)
        if (!robots_[i].stats.answered) send_ir(i, 0);
      resend = Clock::now() + resend_every;
    }
    due += options_.period;
    std::this_thread::sleep_until(due);
  }
}

kernel::Result<std::uint64_t> HilSimulator::run_for(kernel::Duration duration) {
  if (auto st = open_ports(); !st) return kernel::Error{st.error()};
  const auto total = static_cast<std::uint64_t>(duration / options_.period);
  auto start = Clock::now();
  std::uint64_t done = 0;
  StepRecord record;
  record.robots.resize(robots_.size());
  for (std::uint64_t k = 1; k <= total && !stop_.load(); ++k) {
    if (seq_ >= kHilMaxSequence)
      return kernel::Error{"the sequence numbers are used up (" + u(kHilMaxSequence) + " steps)"};
    const auto due =
        start + std::chrono::duration_cast<Clock::duration>(options_.period * static_cast<std::int64_t>(k));
    if (!options_.lockstep) std::this_thread::sleep_until(due);
    if (!options_.lockstep && Clock::now() - due > options_.period) {
      // Far behind (a stopped process, a loaded machine): resume the beat from now instead of
      // stepping in a burst, which the boards could not follow.
      overruns_.fetch_add(1);
      start =
          Clock::now() - std::chrono::duration_cast<Clock::duration>(options_.period * static_cast<std::int64_t>(k));
    }

    // 1. wheels from the newest answer, or the last speeds, or a stop after `hold`.
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      watch_line(i);
      bool any = false;
      const auto f = options_.lockstep ? read_wheels(i, any, seq_, options_.answer_wait) : read_wheels(i, any);
      Robot& r = robots_[i];
      std::string note;
      {
        std::lock_guard lock(stats_mu_);
        HilRobotStats& s = r.stats;
        if (any) s.answered = true;
        if (f) {
          ++s.applied;
          s.late += f->seq < seq_ ? 1 : 0;
          s.last_applied = f->seq;
          if (s.silent) {
            s.silent = false;
            ++s.recoveries;
            note = "robot " + s.robot + ": board answers again after " + u(r.quiet_steps) + " steps";
          }
          r.quiet_steps = 0;
        } else {
          ++s.missing;
          ++r.quiet_steps;
          if (!s.silent && r.quiet_steps >= hold_steps_ && s.applied > 0) {
            s.silent = true;
            ++s.silences;
            note = "robot " + s.robot + ": board silent for " + u(r.quiet_steps) + " steps: wheels stopped";
          }
        }
      }
      if (f)
        world_.set_wheels(i, wheel_units_to_cm_per_s(f->left), wheel_units_to_cm_per_s(f->right));
      else if (!note.empty())
        world_.set_wheels(i, 0, 0);
      if (!note.empty()) event(note);
    }

    // 2. physics.
    world_.step(dt_);
    seq_ = static_cast<std::uint32_t>(k);

    // 3. the boards' next input; 4. the observers.
    record.step = world_.steps();
    record.time = kernel::Time{options_.period * static_cast<std::int64_t>(k)};
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      send_ir(i, seq_);
      record.robots[i].state = world_.state(i);
      record.robots[i].ir = world_.ir(i);
    }
    for (const auto& o : observers_) o(record);
    ++done;
    steps_.store(done);
  }
  return done;
}

}  // namespace symb::sim
