#include "symb/sim/mujoco/hil_organism.hpp"

#include <thread>

#include "symb/io/fd_stream.hpp"

namespace symb::sim::mujoco {

namespace {

void connector_values(const MujocoRunner& runner, const MujocoWorld& world, std::size_t module, std::size_t connectors,
                      std::vector<float>& out) {
  for (std::size_t c = 0; c < connectors; ++c) {
    const auto r = runner.connector(module, c)->reading(world);
    out.insert(out.end(), r.begin(), r.end());
  }
}

}  // namespace

std::string describe(const HilOrganismStats& s) {
  return "sent " + std::to_string(s.frames_sent) + " (" + std::to_string(s.corrupted) + " corrupted, " +
         std::to_string(s.write_errors) + " not taken, " + std::to_string(s.unsent) + " unsent), received " +
         std::to_string(s.received) + " good, " + std::to_string(s.bad_frames()) + " bad; applied " +
         std::to_string(s.applied) + ", " + std::to_string(s.late) + " late, " + std::to_string(s.stale) + " stale, " +
         std::to_string(s.superseded) + " superseded, " + std::to_string(s.missing) + " ticks without; silent " +
         std::to_string(s.silences) + " time(s); docking " + std::to_string(s.dock_commands) + " (" +
         std::to_string(s.dock_refused) + " refused)";
}

kernel::Status HilOrganism::check(const Scenario& sc, std::size_t module) {
  if (module >= sc.robots.size())
    return kernel::Error{sc.file + ": no module " + std::to_string(module) + " for the board"};
  const RobotSpec& spec = sc.robots[module];
  if (!spec.remote_hooks.empty())
    return kernel::Error{spec.remote_hooks.front().where.str() + ": module " + spec.name +
                         " runs on the board: its hooks cannot ride the organism bus"};
  for (const RobotSpec& r : sc.robots)
    for (const RemoteHookSpec& h : r.remote_hooks)
      if (h.to_index == module)
        return kernel::Error{h.where.str() + ": module " + spec.name +
                             " runs on the board: hooks to it cannot ride the organism bus"};
  // A sensor frame is 'N' and a float per value; the board's decoder takes payloads of 1024 bytes.
  const std::size_t values = 1 + 4 + 2 + kConnectorChannels * spec.module_kind.connectors.size();
  if (1 + 4 * values > 1024)
    return kernel::Error{spec.module_where.str() + ": module " + spec.name + " has " +
                         std::to_string(spec.module_kind.connectors.size()) +
                         " connectors, more than a frame to the board carries (" +
                         std::to_string(((1024 - 1) / 4 - 7) / kConnectorChannels) + ")"};
  for (const EventSpec& e : sc.events)
    if (e.robot == module)
      return kernel::Error{e.where.str() + ": module " + spec.name +
                           " runs on the board: its events belong to the board's shell"};
  return {};
}

kernel::Result<std::unique_ptr<HilOrganism>> HilOrganism::create(OrganismSession& session,
                                                                 kernel::VirtualTimeExecutor& executor,
                                                                 std::size_t module, std::shared_ptr<io::IOStream> port,
                                                                 HilOrganismOptions options) {
  if (auto st = check(session.scenario(), module); !st) return kernel::Error{st.error()};
  const Scenario& sc = session.scenario();
  if (!(options.corrupt >= 0 && options.corrupt <= 1))
    return kernel::Error{"the corruption fraction must be in [0, 1]"};
  if (options.answer_wait < kernel::Duration{0}) return kernel::Error{"the answer wait must not be negative"};
  std::unique_ptr<HilOrganism> h(new HilOrganism(session, executor, module, std::move(port), std::move(options)));
  if (!h->port_->is_open())
    if (auto st = h->port_->open(); !st) return kernel::Error{"cannot open the serial line: " + st.error()};
  if (auto* fd = dynamic_cast<io::FdStream*>(h->port_.get())) {
    fd->set_write_timeout(sc.control_period / 4);
  }
  // The module's node is the board's now: nothing of it runs here, its devices are the link's.
  session.robot(module).node().clear();
  MujocoRunner& runner = session.runner();
  (void)runner.hinge(module)->open();
  if (auto w = runner.wheels(module)) (void)w->open();
  return h;
}

HilOrganism::HilOrganism(OrganismSession& session, kernel::VirtualTimeExecutor& executor, std::size_t module,
                         std::shared_ptr<io::IOStream> port, HilOrganismOptions options)
    : session_(session),
      executor_(executor),
      module_(module),
      port_(std::move(port)),
      options_(std::move(options)),
      layout_(HilModuleLayout::of(session.scenario().robots[module].module_kind)),
      corruptor_(options_.corrupt, options_.seed, 0x4849'4c33),  // "HIL3": its own stream
      buf_(4096),
      backoff_(options_.reopen_first, options_.reopen_most) {}

namespace {

kernel::Time steady_now() {
  return std::chrono::duration_cast<kernel::Time>(std::chrono::steady_clock::now().time_since_epoch());
}

}  // namespace

void HilOrganism::watch_line() {
  const kernel::Time t = steady_now();
  std::string note;
  if (!port_->is_open()) {
    if (!backoff_.down()) {
      backoff_.lost(t);
      const auto* fd = dynamic_cast<const io::FdStream*>(port_.get());
      const std::string why = fd != nullptr ? fd->failure() : std::string();
      event("serial line '" + port_->name() + "' down" + (why.empty() ? "" : " (" + why + ")") +
            ": reopening it with backoff");
    }
    if (backoff_.due(t)) {
      if (auto st = port_->open(); st) {
        (void)port_->ioctl("flush");
        decoder_.reset();
        if (auto* fd = dynamic_cast<io::FdStream*>(port_.get()))
          fd->set_write_timeout(session_.scenario().control_period / 4);
        note = "serial line '" + port_->name() + "' open again after " +
               std::to_string(kernel::to_milliseconds(backoff_.reopened(t))) + " ms";
      } else {
        const kernel::Duration wait = backoff_.failed(t);
        event("reopen attempt " + std::to_string(backoff_.attempts()) + " failed: " + st.error() + "; next in " +
              std::to_string(kernel::to_milliseconds(wait)) + " ms");
      }
    }
  }
  {
    std::lock_guard lock(stats_mu_);
    stats_.line_losses = backoff_.losses();
    stats_.line_reopens = backoff_.reopens();
    stats_.line_down = backoff_.down_for(t);
    stats_.line_open = !backoff_.down();
  }
  if (!note.empty()) event(note);
}

HilOrganism::~HilOrganism() = default;

void HilOrganism::event(const std::string& text) {
  if (options_.on_event) options_.on_event(session_.scenario().robots[module_].name + ": " + text);
}

void HilOrganism::send_sensors(std::uint32_t seq) {
  HilModuleSensors f;
  f.seq = seq;
  f.values = readings_;
  frame_.clear();
  io::encode_frame(encode_module_sensors(f), frame_);
  if (!port_->is_open()) {
    std::lock_guard lock(stats_mu_);
    ++stats_.unsent;  // never into a line that is down
    return;
  }
  const bool corrupt = corruptor_.roll() && corrupt_frame(frame_, corruptor_.random());
  corruptor_.count(corrupt);
  const bool ok = static_cast<bool>(port_->write_all(frame_));
  std::lock_guard lock(stats_mu_);
  if (ok) {
    ++stats_.frames_sent;
    stats_.corrupted += corrupt ? 1 : 0;
  } else {
    ++stats_.write_errors;
  }
}

bool HilOrganism::read_board(kernel::Duration wait, std::uint32_t want) {
  const auto deadline = std::chrono::steady_clock::now() + wait;
  bool got = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<kernel::Duration>(deadline - std::chrono::steady_clock::now());
    auto n = port_->read_some(buf_, got ? kernel::Duration{0} : std::max(left, kernel::Duration{0}));
    if (!n) {
      // The line is gone: nothing comes before the deadline.
      std::this_thread::sleep_until(deadline);
      return got;
    }
    if (*n == 0) {
      if (got || std::chrono::steady_clock::now() >= deadline) return got;
      continue;
    }
    std::lock_guard lock(stats_mu_);
    decoder_.feed(std::span<const std::byte>(buf_.data(), *n), [&](std::span<const std::byte> payload) {
      auto f = decode_board_frame(layout_, payload);
      if (!f) {
        ++stats_.malformed;
        return;
      }
      if (f->dock) {
        docks_.push_back(f->dock_command);
        return;
      }
      ++stats_.received;
      const HilModuleCommand& c = f->command;
      if (c.seq == 0) {
        stats_.answered = true;
        if (want == 0) got = true;
        return;
      }
      // Older than one applied, or newer than any frame sent (written for an earlier run; as in 2D).
      if (c.seq < stats_.last_applied || c.seq > seq_) {
        ++stats_.stale;
        return;
      }
      if (best_) ++stats_.superseded;  // the one of the two not kept
      if (!best_ || c.seq >= best_->seq) best_ = c;
      if (want > 0 && c.seq >= want) got = true;
    });
    stats_.decoder = decoder_.stats();
  }
}

void HilOrganism::apply() {
  MujocoRunner& runner = session_.runner();
  for (const HilDockCommand& d : docks_) {
    auto connector = runner.connector(module_, static_cast<std::size_t>(d.connector));
    kernel::Status st;
    switch (d.op) {
      case HilDockOp::kLatch: st = connector->latch(); break;
      case HilDockOp::kUnlatch: st = connector->unlatch(); break;
      case HilDockOp::kOpen: st = connector->set_open(true); break;
      case HilDockOp::kClose: st = connector->set_open(false); break;
    }
    {
      std::lock_guard lock(stats_mu_);
      ++stats_.dock_commands;
      stats_.dock_refused += st ? 0 : 1;
    }
    event("board: connector_" + layout_.connectors[d.connector] + " " + std::string(dock_op_name(d.op)) +
          (st ? std::string(": done") : ": refused: " + st.error()));
  }
  docks_.clear();
  auto wheels = runner.wheels(module_);
  if (best_) {
    (void)runner.hinge(module_)->set(std::span<const float>(&best_->hinge, 1));
    if (wheels) {
      const float w[2] = {best_->left, best_->right};
      (void)wheels->set(w);
    }
    if (silent_) event("board answers again");
    silent_ = false;
    quiet_ticks_ = 0;
    std::lock_guard lock(stats_mu_);
    ++stats_.applied;
    stats_.late += best_->seq < seq_ ? 1 : 0;
    stats_.last_applied = best_->seq;
    best_.reset();
    return;
  }
  if (seq_ == 0) return;  // before the first tick: nothing to keep
  {
    std::lock_guard lock(stats_mu_);
    ++stats_.missing;
  }
  ++quiet_ticks_;
  if (!silent_ && session_.scenario().control_period * static_cast<std::int64_t>(quiet_ticks_) >= options_.hold) {
    silent_ = true;
    float angle = 0;
    runner.with_world([&](MujocoWorld& w) { angle = static_cast<float>(w.hinge_angle(module_)); });
    (void)runner.hinge(module_)->set(std::span<const float>(&angle, 1));
    if (wheels) {
      const float zero[2] = {0, 0};
      (void)wheels->set(zero);
    }
    {
      std::lock_guard lock(stats_mu_);
      ++stats_.silences;
    }
    event("board silent: the module stops");
  }
}

kernel::Status HilOrganism::wait_for_board(kernel::Duration timeout) {
  MujocoRunner& runner = session_.runner();
  readings_.assign(layout_.sensor_values() - 1, 0.0f);
  runner.with_world([&](MujocoWorld& w) {
    readings_[kHilSensorHinge - 1] = static_cast<float>(w.hinge_angle(module_));
    readings_[kHilSensorHinge] = static_cast<float>(w.hinge_speed(module_));
    std::vector<float> c;
    connector_values(runner, w, module_, layout_.connectors.size(), c);
    std::copy(c.begin(), c.end(), readings_.begin() + (kHilSensorConnector - 1));
  });
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  // Sent again each period, or each answer_wait when that is longer (a lockstep run, which waits
  // that long for every answer): a board kept off its core for more than a period would otherwise
  // answer two handshakes, and the books count one.
  const kernel::Duration wait = std::max(session_.scenario().control_period, options_.answer_wait);
  while (std::chrono::steady_clock::now() < deadline) {
    watch_line();
    send_sensors(0);
    if (read_board(wait, 0)) return {};
  }
  return kernel::Error{"the board did not answer the handshake within " +
                       std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count()) + " ms"};
}

kernel::Result<std::uint64_t> HilOrganism::run_ticks(std::uint64_t ticks) {
  MujocoRunner& runner = session_.runner();
  const kernel::Duration period = session_.scenario().control_period;
  if (!started_) {
    // Shared: the runner keeps its observers, and may outlive this.
    auto readings = std::make_shared<std::vector<float>>();
    const std::size_t module = module_, connectors = layout_.connectors.size();
    MujocoRunner* r = &runner;
    runner.add_observer([readings, module, connectors, r](const MujocoStepRecord& rec) {
      const ModuleStep& m = rec.modules[module];
      std::vector<float>& v = *readings;
      v.assign(m.ir.begin(), m.ir.end());
      v.push_back(static_cast<float>(m.hinge_angle));
      v.push_back(static_cast<float>(m.hinge_speed));
      r->with_world([&](MujocoWorld& w) { connector_values(*r, w, module, connectors, v); });
    });
    observed_ = readings;
    session_.start();
    started_ = true;
    wall_start_ = std::chrono::steady_clock::now();
  }
  std::uint64_t done = 0;
  for (; done < ticks; ++done) {
    if (seq_ >= kHilMaxSequence) return kernel::Error{"the run is out of sequence numbers (2^24 ticks)"};
    watch_line();
    apply();
    const std::uint32_t k = seq_ + 1;
    executor_.run_until(period * static_cast<std::int64_t>(k));
    if (auto e = session_.error(); !e.empty()) return kernel::Error{e};
    seq_ = k;
    readings_ = *observed_;
    send_sensors(k);
    read_board(options_.answer_wait, k);
    if (options_.paced) {
      const auto due = wall_start_ + period * static_cast<std::int64_t>(k);
      const auto left = std::chrono::duration_cast<kernel::Duration>(due - std::chrono::steady_clock::now());
      if (left > kernel::Duration{0}) read_board(left, kHilMaxSequence + 1);
    }
  }
  return done;
}

HilOrganismStats HilOrganism::stats() const {
  std::lock_guard lock(stats_mu_);
  return stats_;
}

}  // namespace symb::sim::mujoco
