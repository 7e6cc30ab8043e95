#include "symb/robot/robot_task_types.hpp"

#include <stdexcept>
#include <string>

#include "symb/robot/actuator_task.hpp"

namespace symb::robot {

namespace {

using namespace std::chrono_literals;
using os::ParamSpec;
using os::ParamType;

// Lookups run inside TaskType::make, whose only way to explain a failure is an exception (the
// node turns it into an error naming the type).
template <class T>
std::shared_ptr<T> find_device(const std::function<std::shared_ptr<T>(std::string_view)>& lookup,
                               const std::string& name, const char* what, const char* param = "device") {
  if (name.empty()) throw std::invalid_argument(std::string("name the ") + what + " to use: " + param + "=NAME");
  if (!lookup) throw std::invalid_argument(std::string("this node has no ") + what + " devices");
  auto d = lookup(name);
  if (!d) throw std::invalid_argument(std::string("no ") + what + " named '" + name.substr(0, 63) + "'");
  return d;
}

std::vector<ChannelSpec> ranges_for(const std::vector<ChannelSpec>& channels, const std::string& text) {
  if (text.empty()) return {};
  auto r = apply_ranges(channels, text);
  if (!r) throw std::invalid_argument("ranges: " + r.error());
  return std::move(r).value();
}

ParamSpec device_param(const char* doc) { return {"device", ParamType::kString, std::string(), 0.0, 63.0, doc}; }
ParamSpec ranges_param() {
  return {"ranges",
          ParamType::kString,
          std::string(),
          0.0,
          1024.0,
          "narrower channel ranges: lo:hi for all channels or lo:hi,lo:hi,... one per channel; empty: the "
          "device's"};
}
ParamSpec warn_param() {
  return {"warn_interval",
          ParamType::kDuration,
          kernel::Duration{1s},
          0.0,
          3600.0,
          "at most one warning of a kind per interval (counts say how many it stands for)"};
}

}  // namespace

kernel::Status register_robot_task_types(os::TaskTypeRegistry& registry, RobotDevices devices) {
  auto shared = std::make_shared<const RobotDevices>(std::move(devices));

  os::TaskType sensor;
  sensor.name = "sensor";
  sensor.doc = "forwards an active sensor's samples (one number per channel) to hooked tasks";
  sensor.params = {device_param("the active sensor"), ranges_param(), warn_param()};
  sensor.defaults.priority = 1;  // data first: tasks that act on it at the same instant see it
  sensor.defaults.queue_capacity = 4;
  sensor.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto dev = find_device(shared->sensor, p.string("device"), "sensor");
    SensorTask::Options o;
    o.ranges = ranges_for(dev->channels(), p.string("ranges"));
    o.warn_interval = p.duration("warn_interval");
    return std::make_unique<SensorTask>(std::move(dev), std::move(o));
  };

  os::TaskType polling;
  polling.name = "polling_sensor";
  polling.doc = "polls a passive sensor at its period and sends each fresh sample to hooked tasks";
  polling.params = {device_param("the polled sensor"), ranges_param(), warn_param()};
  polling.defaults.period = 30ms;  // the paper's IR rate, 33.33 Hz
  polling.defaults.priority = 1;
  polling.defaults.queue_capacity = 4;
  polling.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto dev = find_device(shared->polling_sensor, p.string("device"), "polling sensor");
    PollingSensorTask::Options o;
    o.ranges = ranges_for(dev->channels(), p.string("ranges"));
    o.warn_interval = p.duration("warn_interval");
    return std::make_unique<PollingSensorTask>(std::move(dev), std::move(o));
  };

  os::TaskType sink;
  sink.name = "actuator_sink";
  sink.doc = "applies every message it receives (one number per channel) to an actuator at once";
  sink.params = {device_param("the actuator"),
                 ranges_param(),
                 warn_param(),
                 {"timeout", ParamType::kDuration, kernel::Duration{0}, 0.0, 3600.0,
                  "watchdog: apply the safe output (closest to 0) when no command came for this long; 0: off"}};
  sink.defaults.queue_capacity = 8;
  // No period by default: a sink with a watchdog gives itself one (ActuatorSinkTask::arm_watchdog).
  sink.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto dev = find_device(shared->actuator, p.string("device"), "actuator");
    ActuatorSinkTask::Options o;
    o.ranges = ranges_for(dev->channels(), p.string("ranges"));
    o.warn_interval = p.duration("warn_interval");
    o.timeout = p.duration("timeout");
    return std::make_unique<ActuatorSinkTask>(std::move(dev), std::move(o));
  };

  const ActuatorTask::Options d;
  os::TaskType drive;
  drive.name = "actuator_task";
  drive.doc = "drives a differential-drive base towards goals (drive, turn, hold speed) using hooked odometry";
  drive.params = {
      {"drive", ParamType::kString, std::string(), 0.0, 63.0, "the differential drive"},
      {"max_speed", ParamType::kReal, d.max_speed, 0.001, 100.0,
       "wheel speed limit, m/s (the drive's own applies too)"},
      {"kp_distance", ParamType::kReal, d.kp_distance, 0.0, 1000.0, "forward speed per metre to go, 1/s"},
      {"kp_turn", ParamType::kReal, d.kp_turn, 0.0, 1000.0, "turn rate per radian to turn, 1/s"},
      {"kp_heading", ParamType::kReal, d.kp_heading, 0.0, 1000.0, "turn rate per radian off heading when driving, 1/s"},
      {"distance_tolerance", ParamType::kReal, d.distance_tolerance, 1e-6, 10.0, "a drive goal is reached within, m"},
      {"angle_tolerance", ParamType::kReal, d.angle_tolerance, 1e-6, 1.0, "a turn goal is reached within, rad"},
      {"odometry_timeout", ParamType::kDuration, d.odometry_timeout, 0.001, 3600.0,
       "a goal is aborted and the wheels stopped when odometry is silent this long"},
      {"odometry", ParamType::kString, std::string("pose"), 1.0, 16.0,
       "pose: [x, y, theta]; wheels: cumulative wheel distances [left, right]"},
      {"wheel_base", ParamType::kReal, d.wheel_base, 0.001, 100.0, "distance between the wheels, m"},
      {"odometry_port", ParamType::kInt, std::int64_t{d.odometry_port}, 0.0, 65535.0, "port odometry arrives on"},
      {"command_port", ParamType::kInt, std::int64_t{d.command_port}, 0.0, 65535.0, "port goals arrive on"},
      warn_param(),
  };
  drive.defaults.period = 20ms;
  drive.defaults.priority = 0;
  drive.defaults.queue_capacity = 16;
  drive.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto dev = find_device(shared->drive, p.string("drive"), "drive", "drive");
    ActuatorTask::Options o;
    o.max_speed = p.real("max_speed");
    o.kp_distance = p.real("kp_distance");
    o.kp_turn = p.real("kp_turn");
    o.kp_heading = p.real("kp_heading");
    o.distance_tolerance = p.real("distance_tolerance");
    o.angle_tolerance = p.real("angle_tolerance");
    o.odometry_timeout = p.duration("odometry_timeout");
    const std::string& format = p.string("odometry");
    if (format == "pose")
      o.odometry = OdometryFormat::kPose;
    else if (format == "wheels")
      o.odometry = OdometryFormat::kWheelDistances;
    else
      throw std::invalid_argument("odometry must be 'pose' or 'wheels', not '" + format + "'");
    o.wheel_base = p.real("wheel_base");
    o.odometry_port = static_cast<os::Port>(p.integer("odometry_port"));
    o.command_port = static_cast<os::Port>(p.integer("command_port"));
    o.warn_interval = p.duration("warn_interval");
    return std::make_unique<ActuatorTask>(std::move(dev), o);
  };

  for (auto* t : {&sensor, &polling, &sink, &drive})
    if (auto st = registry.add(std::move(*t)); !st) return st;
  return {};
}

}  // namespace symb::robot
