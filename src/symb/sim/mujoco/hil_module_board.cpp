#include "symb/sim/mujoco/hil_module_board.hpp"

#include <stdexcept>

#include "symb/sim/mujoco/mujoco_devices.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
#include "symb/sim/periodic_runner.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim::mujoco {

namespace {

// An actuator whose hardware is the serial line: set() keeps the output (Actuator::output()),
// which the board sends with its answer.
class LinkActuator final : public robot::Actuator {
 public:
  using robot::Actuator::Actuator;

 protected:
  kernel::Status apply(std::span<const float>) override { return {}; }
};

}  // namespace

struct HilModuleBoard::Shared {
  std::mutex mu;  // pending, have_pending, outbox, readings
  std::uint32_t pending_seq = 0;
  bool have_pending = false;
  std::vector<float> pending;              // the newest sensor frame's values
  std::vector<HilDockCommand> outbox;      // docking commands not sent yet
  std::vector<ConnectorReading> readings;  // per connector, the newest
  std::shared_ptr<robot::Sensor> ir, hinge_state;
  std::vector<std::shared_ptr<robot::Sensor>> connectors;
  std::shared_ptr<robot::Actuator> hinge, wheels;  // wheels null without
};

namespace {

// connector_<name>: a sensor fed from the line whose docking ioctls are forwarded to the world.
class LinkConnector final : public robot::Sensor {
 public:
  LinkConnector(std::string name, std::weak_ptr<HilModuleBoard::Shared> shared, std::uint8_t index)
      : robot::Sensor(std::move(name), MujocoConnector::channel_specs()), shared_(std::move(shared)), index_(index) {
    forward("open", HilDockOp::kOpen, "opens the connector (forwarded to the simulator)");
    forward("close", HilDockOp::kClose, "closes the connector (forwarded to the simulator)");
    forward("latch", HilDockOp::kLatch, "docks to the connector facing this one (forwarded to the simulator)");
    forward("unlatch", HilDockOp::kUnlatch, "undocks (forwarded to the simulator)");
    add_ioctl({"state", std::nullopt, "the newest reading from the simulator: state, open, peer"},
              [this](const os::ParamValue*) -> kernel::Result<std::string> {
                auto s = shared_.lock();
                if (!s) return kernel::Error{"the link is gone"};
                std::lock_guard lock(s->mu);
                const auto& r = s->readings.at(index_);
                static constexpr const char* kStates[] = {"free", "aligned", "docked"};
                const int st = static_cast<int>(r[0]);
                std::string text = (st >= 0 && st <= 2) ? kStates[st] : "?";
                if (st == 2) text += " to module " + std::to_string(static_cast<int>(r[2]));
                return text + (r[1] > 0.5f ? ", open" : ", closed");
              });
  }

 private:
  void forward(const char* name, HilDockOp op, const char* doc) {
    add_ioctl({name, std::nullopt, doc}, [this, op](const os::ParamValue*) -> kernel::Result<std::string> {
      auto s = shared_.lock();
      if (!s) return kernel::Error{"the link is gone"};
      std::lock_guard lock(s->mu);
      s->outbox.push_back({0, index_, op});
      return std::string("sent to the simulator");
    });
  }

  std::weak_ptr<HilModuleBoard::Shared> shared_;
  std::uint8_t index_;
};

}  // namespace

// Where the MujocoRunner stands in process: the same priority and period; tick k publishes sensor
// frame k when it came.
class HilModuleBoard::Clock final : public PeriodicRunner {
 public:
  Clock(kernel::Executor& executor, std::shared_ptr<Shared> shared, PeriodicRunner::Options options)
      : PeriodicRunner(executor, options), shared_(std::move(shared)) {}
  ~Clock() override { halt(); }

 private:
  kernel::Status step_once(kernel::Time now) override {
    ++tick_;
    std::vector<float> v;
    {
      std::lock_guard lock(shared_->mu);
      if (!shared_->have_pending || shared_->pending_seq != tick_) return {};
      v = shared_->pending;
      shared_->have_pending = false;
    }
    shared_->ir->publish(std::span<const float>(v.data() + (kHilSensorIr - 1), 4), now);
    shared_->hinge_state->publish(std::span<const float>(v.data() + (kHilSensorHinge - 1), 2), now);
    for (std::size_t c = 0; c < shared_->connectors.size(); ++c)
      shared_->connectors[c]->publish(
          std::span<const float>(v.data() + (kHilSensorConnector - 1) + kConnectorChannels * c, kConnectorChannels),
          now);
    return {};
  }

  std::shared_ptr<Shared> shared_;
  std::uint64_t tick_ = 0;
};

std::string describe(const HilModuleBoardStats& s) {
  return "frames " + std::to_string(s.frames) + " good, " + std::to_string(s.bad_frames()) + " bad (crc " +
         std::to_string(s.decoder.crc_errors) + ", malformed " + std::to_string(s.malformed) + "), " +
         std::to_string(s.missed) + " missed, " + std::to_string(s.out_of_order) + " out of order; answers " +
         std::to_string(s.answers) + ", docking " + std::to_string(s.dock_commands) + ", not taken " +
         std::to_string(s.write_errors) + "; link lost " + std::to_string(s.link_losses) + ", back " +
         std::to_string(s.link_recoveries);
}

HilModuleBoard::HilModuleBoard(kernel::VirtualTimeExecutor& executor, const ModuleKind& kind,
                               std::shared_ptr<io::IOStream> port, HilModuleBoardOptions options)
    : executor_(executor),
      layout_(HilModuleLayout::of(kind)),
      port_(std::move(port)),
      options_(std::move(options)),
      shared_(std::make_shared<Shared>()),
      buf_(4096) {
  if (options_.control_period <= kernel::Duration{0} || options_.control_period > std::chrono::seconds(1))
    throw std::invalid_argument("HilModuleBoard: the control period must be in (0, 1 s]");
  if (layout_.connectors.size() > 255) throw std::invalid_argument("HilModuleBoard: more than 255 connectors");
  shared_->ir = std::make_shared<robot::Sensor>("ir", MujocoIrSensor::channel_specs());
  shared_->hinge_state = std::make_shared<robot::Sensor>("hinge_state", MujocoHingeSensor::channel_specs());
  for (std::size_t c = 0; c < layout_.connectors.size(); ++c)
    shared_->connectors.push_back(
        std::make_shared<LinkConnector>("connector_" + layout_.connectors[c], shared_, static_cast<std::uint8_t>(c)));
  shared_->readings.assign(layout_.connectors.size(), ConnectorReading{0, 0, -1, -1, 0, 0});
  shared_->hinge = std::make_shared<LinkActuator>("hinge", MujocoHinge::channel_specs(kind.hinge.range));
  if (layout_.wheels) shared_->wheels = std::make_shared<LinkActuator>("wheels", SimWheels::channel_specs());
  PeriodicRunner::Options co;
  co.period = options_.control_period;
  co.name = "link";
  clock_ = std::make_unique<Clock>(executor_, shared_, co);
}

HilModuleBoard::~HilModuleBoard() { clock_.reset(); }

robot::RobotDevices HilModuleBoard::device_lookups() const {
  std::vector<std::shared_ptr<robot::Sensor>> sensors{shared_->ir, shared_->hinge_state};
  sensors.insert(sensors.end(), shared_->connectors.begin(), shared_->connectors.end());
  std::vector<std::shared_ptr<robot::Actuator>> actuators{shared_->hinge};
  if (shared_->wheels) actuators.push_back(shared_->wheels);
  return device_lookups_of(std::move(sensors), std::move(actuators));
}

std::vector<std::shared_ptr<io::Device>> HilModuleBoard::devices() const {
  std::vector<std::shared_ptr<io::Device>> d{shared_->ir, shared_->hinge_state, shared_->hinge};
  if (shared_->wheels) d.push_back(shared_->wheels);
  d.insert(d.end(), shared_->connectors.begin(), shared_->connectors.end());
  return d;
}

kernel::Status HilModuleBoard::start() {
  if (started_) return kernel::Error{"the board's clock is already running"};
  if (!port_->is_open())
    if (auto st = port_->open(); !st) return kernel::Error{"cannot open the serial line: " + st.error()};
  started_ = true;
  last_frame_wall_ = std::chrono::steady_clock::now();
  return clock_->start();
}

void HilModuleBoard::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

void HilModuleBoard::send(const std::vector<std::byte>& payload, bool dock) {
  frame_.clear();
  io::encode_frame(payload, frame_);
  const bool ok = static_cast<bool>(port_->write_all(frame_));
  std::lock_guard lock(stats_mu_);
  if (!ok)
    ++stats_.write_errors;
  else if (dock)
    ++stats_.dock_commands;
  else
    ++stats_.answers;
}

void HilModuleBoard::handle(std::span<const std::byte> payload, std::size_t& handled) {
  auto f = decode_module_sensors(layout_, payload);
  if (!f) {
    std::lock_guard lock(stats_mu_);
    ++stats_.malformed;
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (!link_up_ && stats_.link_losses > recoveries_seen_) {
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now - last_frame_wall_).count();
    event("link back after " + std::to_string(ms) + " ms");
    std::lock_guard lock(stats_mu_);
    ++stats_.link_recoveries;
    recoveries_seen_ = stats_.link_recoveries;
  }
  link_up_ = true;
  last_frame_wall_ = now;
  std::uint32_t last = 0;
  {
    std::lock_guard lock(stats_mu_);
    last = stats_.last_seq;
    if (f->seq == 0) {
      if (stats_.frames > 0) {
        ++stats_.restarts;
      } else {
        ++stats_.handshakes;
      }
    } else if (f->seq <= last) {
      ++stats_.out_of_order;
      return;
    } else {
      stats_.missed += f->seq - last - 1;
      stats_.last_seq = f->seq;
    }
  }
  const auto outputs = [&](std::uint32_t seq) {
    HilModuleCommand c;
    c.seq = seq;
    c.hinge = shared_->hinge->output().at(0);
    if (shared_->wheels) {
      const auto w = shared_->wheels->output();
      c.left = w.at(0);
      c.right = w.at(1);
    }
    return encode_module_command(layout_, c);
  };
  if (f->seq == 0) {
    if (last > 0) {
      event("the simulator started anew: this board serves one run (its node's time cannot go back); start it again");
      return;
    }
    send(outputs(0), false);  // the handshake's answer, never applied
    return;
  }
  {
    std::lock_guard lock(shared_->mu);
    shared_->pending_seq = f->seq;
    shared_->pending = f->values;
    shared_->have_pending = true;
    for (std::size_t c = 0; c < shared_->readings.size(); ++c)
      for (std::size_t k = 0; k < kConnectorChannels; ++k)
        shared_->readings[c][k] = f->values[(kHilSensorConnector - 1) + kConnectorChannels * c + k];
  }
  // Everything the node does before the world's next step: up to just before tick seq + 1.
  const kernel::Time until = options_.control_period * (static_cast<std::int64_t>(f->seq) + 1) - kernel::Duration{1};
  executor_.run_until(until);
  std::vector<HilDockCommand> docks;
  {
    std::lock_guard lock(shared_->mu);
    docks.swap(shared_->outbox);
  }
  for (HilDockCommand& d : docks) {
    d.seq = f->seq;
    send(encode_dock_command(d), true);
  }
  send(outputs(f->seq), false);
  ++handled;
  std::lock_guard lock(stats_mu_);
  ++stats_.frames;
}

kernel::Result<std::size_t> HilModuleBoard::serve(kernel::Duration timeout) {
  if (!started_) return kernel::Error{"the board's clock has not started"};
  std::size_t handled = 0;
  auto got = port_->read_some(buf_, timeout);
  if (!got) return kernel::Error{"the serial line is gone: " + got.error()};
  decoder_.feed(std::span<const std::byte>(buf_.data(), *got),
                [&](std::span<const std::byte> payload) { handle(payload, handled); });
  {
    std::lock_guard lock(stats_mu_);
    stats_.decoder = decoder_.stats();
  }
  const auto silent = std::chrono::steady_clock::now() - last_frame_wall_;
  if (link_up_ && silent > options_.control_period * options_.lost_periods) {
    link_up_ = false;
    event("link lost: no frame for " +
          std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(silent).count()) + " ms");
    std::lock_guard lock(stats_mu_);
    ++stats_.link_losses;
  }
  return handled;
}

HilModuleBoardStats HilModuleBoard::stats() const {
  std::lock_guard lock(stats_mu_);
  return stats_;
}

}  // namespace symb::sim::mujoco
