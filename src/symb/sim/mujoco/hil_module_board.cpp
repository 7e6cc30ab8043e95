#include "symb/sim/mujoco/hil_module_board.hpp"

#include <stdexcept>

#include "symb/sim/mujoco/mujoco_devices.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
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
  std::mutex mu;                           // outbox, readings
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

std::string describe(const HilModuleBoardStats& s) {
  return describe(static_cast<const FrameClockStats&>(s), ", docking " + std::to_string(s.dock_commands));
}

HilModuleBoard::HilModuleBoard(kernel::VirtualTimeExecutor& executor, const ModuleKind& kind,
                               std::shared_ptr<io::IOStream> port, HilModuleBoardOptions options)
    : FrameClockBoard(executor, std::move(port), std::move(options), "sensor frame"),
      layout_(HilModuleLayout::of(kind)),
      shared_(std::make_shared<Shared>()) {
  if (layout_.connectors.size() > 255) throw std::invalid_argument("HilModuleBoard: more than 255 connectors");
  shared_->ir = std::make_shared<robot::Sensor>("ir", MujocoIrSensor::channel_specs());
  shared_->hinge_state = std::make_shared<robot::Sensor>("hinge_state", MujocoHingeSensor::channel_specs());
  for (std::size_t c = 0; c < layout_.connectors.size(); ++c)
    shared_->connectors.push_back(
        std::make_shared<LinkConnector>("connector_" + layout_.connectors[c], shared_, static_cast<std::uint8_t>(c)));
  shared_->readings.assign(layout_.connectors.size(), ConnectorReading{0, 0, -1, -1, 0, 0});
  shared_->hinge = std::make_shared<LinkActuator>("hinge", MujocoHinge::channel_specs(kind.hinge.range));
  if (layout_.wheels) shared_->wheels = std::make_shared<LinkActuator>("wheels", SimWheels::channel_specs());
}

HilModuleBoard::~HilModuleBoard() { stop_clock(); }

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

kernel::Result<FrameClockBoard::SensorFrame> HilModuleBoard::decode(std::span<const std::byte> payload) const {
  auto f = decode_module_sensors(layout_, payload);
  if (!f) return kernel::Error{f.error()};
  return SensorFrame{f->seq, std::move(f->values)};
}

void HilModuleBoard::publish(const std::vector<float>& v, kernel::Time now) {
  {
    std::lock_guard lock(shared_->mu);
    for (std::size_t c = 0; c < shared_->readings.size(); ++c)
      for (std::size_t k = 0; k < kConnectorChannels; ++k)
        shared_->readings[c][k] = v[(kHilSensorConnector - 1) + kConnectorChannels * c + k];
  }
  shared_->ir->publish(std::span<const float>(v.data() + (kHilSensorIr - 1), 4), now);
  shared_->hinge_state->publish(std::span<const float>(v.data() + (kHilSensorHinge - 1), 2), now);
  for (std::size_t c = 0; c < shared_->connectors.size(); ++c)
    shared_->connectors[c]->publish(
        std::span<const float>(v.data() + (kHilSensorConnector - 1) + kConnectorChannels * c, kConnectorChannels), now);
}

bool HilModuleBoard::answer(std::uint32_t seq) {
  // The docking commands the node gave while it ran go first: the world applies them before its
  // next step, as an in-process ioctl acts between two steps.
  std::vector<HilDockCommand> docks;
  {
    std::lock_guard lock(shared_->mu);
    docks.swap(shared_->outbox);
  }
  for (HilDockCommand& d : docks) {
    d.seq = seq;
    ++(send(encode_dock_command(d)) ? dock_commands_ : dock_write_errors_);
  }
  HilModuleCommand c;
  c.seq = seq;
  c.hinge = shared_->hinge->output().at(0);
  if (shared_->wheels) {
    const auto w = shared_->wheels->output();
    c.left = w.at(0);
    c.right = w.at(1);
  }
  return send(encode_module_command(layout_, c));
}

HilModuleBoardStats HilModuleBoard::stats() const {
  HilModuleBoardStats s;
  static_cast<FrameClockStats&>(s) = link_stats();
  s.dock_commands = dock_commands_.load();
  s.write_errors += dock_write_errors_.load();
  return s;
}

}  // namespace symb::sim::mujoco
