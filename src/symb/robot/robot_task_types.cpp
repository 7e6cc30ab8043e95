#include "symb/robot/robot_task_types.hpp"

#include <string>

#include "symb/robot/actuator_task.hpp"
#include "symb/robot/ports.hpp"

namespace symb::robot {

namespace {

using namespace std::chrono_literals;
using kernel::Error;
using kernel::Result;

template <class T>
Result<std::shared_ptr<T>> find_device(const std::function<std::shared_ptr<T>(std::string_view)>& lookup,
                                       const std::string& name, const char* what, const char* param = "device") {
  if (name.empty()) return Error{std::string("name the ") + what + " to use: " + param + "=NAME"};
  if (!lookup) return Error{std::string("this node has no ") + what + " devices"};
  auto d = lookup(name);
  if (!d) return Error{std::string("no ") + what + " named '" + name.substr(0, 63) + "'"};
  return d;
}

Result<std::vector<ChannelSpec>> ranges_for(const std::vector<ChannelSpec>& channels, const std::string& text) {
  if (text.empty()) return std::vector<ChannelSpec>{};
  auto r = apply_ranges(channels, text);
  if (!r) return Error{"ranges: " + r.error()};
  return r;
}

// What the device-backed types share: the device's name and narrower ranges as text, on top of
// the task's own options.
template <class Options>
struct DeviceParams : Options {
  std::string device;
  std::string ranges_text;
};

template <class Options>
void add_device_params(os::ParamTable<DeviceParams<Options>>& p, const char* device_doc) {
  using P = DeviceParams<Options>;
  p.add("device", &P::device).range(0, 63).doc(device_doc);
  p.add("ranges", &P::ranges_text)
      .range(0, 1024)
      .doc(
          "narrower channel ranges: lo:hi for all channels or lo:hi,lo:hi,... one per channel; empty: the "
          "device's");
  p.add("warn_interval", &P::warn_interval)
      .range(0.0, 3600.0)
      .doc("at most one warning of a kind per interval (counts say how many it stands for)")
      .live();
}

// The device and the ranges of `p` resolved into the task's options.
template <class Device, class Options>
Result<std::pair<std::shared_ptr<Device>, Options>> resolve_device(
    const std::function<std::shared_ptr<Device>(std::string_view)>& lookup, const DeviceParams<Options>& p,
    const char* what) {
  auto dev = find_device(lookup, p.device, what);
  if (!dev) return Error{dev.error()};
  Options o = p;
  auto ranges = ranges_for((*dev)->channels(), p.ranges_text);
  if (!ranges) return Error{ranges.error()};
  o.ranges = std::move(ranges).value();
  return std::pair{std::move(dev).value(), std::move(o)};
}

struct DriveParams : ActuatorTask::Options {
  std::string drive;
};

}  // namespace

kernel::Status register_robot_task_types(os::TaskTypeRegistry& registry, RobotDevices devices) {
  auto shared = std::make_shared<const RobotDevices>(std::move(devices));

  os::ParamTable<DeviceParams<SensorTask::Options>> sp;
  add_device_params(sp, "the active sensor");
  auto sensor = os::declare_task_type(
      "sensor", "forwards an active sensor's samples (one number per channel) to hooked tasks", std::move(sp),
      [shared](const DeviceParams<SensorTask::Options>& p) -> Result<std::unique_ptr<SensorTask>> {
        auto r = resolve_device(shared->sensor, p, "sensor");
        if (!r) return Error{r.error()};
        return std::make_unique<SensorTask>(std::move(r.value().first), std::move(r.value().second));
      });
  sensor.defaults.priority = 1;  // data first: tasks that act on it at the same instant see it
  sensor.defaults.queue_capacity = 4;
  sensor.outputs = {{kDataPort, "samples", os::kAnyLayout}};

  os::ParamTable<DeviceParams<PollingSensorTask::Options>> pp;
  add_device_params(pp, "the polled sensor");
  auto polling = os::declare_task_type(
      "polling_sensor", "polls a passive sensor at its period and sends each fresh sample to hooked tasks",
      std::move(pp),
      [shared](const DeviceParams<PollingSensorTask::Options>& p) -> Result<std::unique_ptr<PollingSensorTask>> {
        auto r = resolve_device(shared->polling_sensor, p, "polling sensor");
        if (!r) return Error{r.error()};
        return std::make_unique<PollingSensorTask>(std::move(r.value().first), std::move(r.value().second));
      });
  polling.defaults.period = 30ms;  // the paper's IR rate, 33.33 Hz
  polling.defaults.priority = 1;
  polling.defaults.queue_capacity = 4;
  polling.outputs = {{kDataPort, "samples", os::kAnyLayout}};

  using SinkParams = DeviceParams<ActuatorSinkTask::Options>;
  os::ParamTable<SinkParams> kp;
  add_device_params(kp, "the actuator");
  kp.add("timeout", &SinkParams::timeout)
      .range(0.0, 3600.0)
      .doc("watchdog: apply the safe output (closest to 0) when no command came for this long; 0: off")
      .live();
  auto sink = os::declare_task_type(
      "actuator_sink", "applies every message it receives (one number per channel) to an actuator at once",
      std::move(kp), [shared](const SinkParams& p) -> Result<std::unique_ptr<ActuatorSinkTask>> {
        auto r = resolve_device(shared->actuator, p, "actuator");
        if (!r) return Error{r.error()};
        return std::make_unique<ActuatorSinkTask>(std::move(r.value().first), std::move(r.value().second));
      });
  sink.defaults.queue_capacity = 8;
  // Below the controllers (0 and up): a watchdog tick due at the instant of a command comes after
  // it and hears it, and so finds the deadline a whole timeout ahead (ActuatorSinkTask::on_tick).
  // Commands themselves are taken at once, whatever the priority.
  sink.defaults.priority = -1;
  // No period by default: a sink with a watchdog gives itself one (ActuatorSinkTask::arm_watchdog).
  sink.inputs = {{kDataPort, "command", os::kAnyLayout}};

  os::ParamTable<DriveParams> dp;
  dp.add("drive", &DriveParams::drive).range(0, 63).doc("the differential drive");
  dp.add("max_speed", &DriveParams::max_speed)
      .range(0.001, 100.0)
      .doc("wheel speed limit, m/s (the drive's own applies too)")
      .live();
  dp.add("kp_distance", &DriveParams::kp_distance).range(0.0, 1000.0).doc("forward speed per metre to go, 1/s").live();
  dp.add("kp_turn", &DriveParams::kp_turn).range(0.0, 1000.0).doc("turn rate per radian to turn, 1/s").live();
  dp.add("kp_heading", &DriveParams::kp_heading)
      .range(0.0, 1000.0)
      .doc("turn rate per radian off heading when driving, 1/s")
      .live();
  dp.add("distance_tolerance", &DriveParams::distance_tolerance)
      .range(1e-6, 10.0)
      .doc("a drive goal is reached within, m")
      .live();
  dp.add("angle_tolerance", &DriveParams::angle_tolerance)
      .range(1e-6, 1.0)
      .doc("a turn goal is reached within, rad")
      .live();
  dp.add("odometry_timeout", &DriveParams::odometry_timeout)
      .range(0.001, 3600.0)
      .doc("a goal is aborted and the wheels stopped when odometry is silent this long")
      .live();
  dp.add("odometry", &DriveParams::odometry,
         os::choice<OdometryFormat>("odometry",
                                    {{"pose", OdometryFormat::kPose}, {"wheels", OdometryFormat::kWheelDistances}}))
      .range(1.0, 16.0)
      .doc("pose: [x, y, theta]; wheels: cumulative wheel distances [left, right]");
  dp.add("wheel_base", &DriveParams::wheel_base).range(0.001, 100.0).doc("distance between the wheels, m").live();
  dp.add("odometry_port", &DriveParams::odometry_port).range(0.0, 65535.0).doc("port odometry arrives on");
  dp.add("command_port", &DriveParams::command_port).range(0.0, 65535.0).doc("port goals arrive on");
  dp.add("warn_interval", &DriveParams::warn_interval)
      .range(0.0, 3600.0)
      .doc("at most one warning of a kind per interval (counts say how many it stands for)")
      .live();
  auto drive = os::declare_task_type(
      "actuator_task", "drives a differential-drive base towards goals (drive, turn, hold speed) using hooked odometry",
      std::move(dp), [shared](const DriveParams& p) -> Result<std::unique_ptr<ActuatorTask>> {
        auto dev = find_device(shared->drive, p.drive, "drive", "drive");
        if (!dev) return Error{dev.error()};
        return std::make_unique<ActuatorTask>(std::move(dev).value(), p);
      });
  drive.defaults.period = 20ms;
  drive.defaults.priority = 0;
  drive.defaults.queue_capacity = 16;

  for (auto* t : {&sensor, &polling, &sink, &drive})
    if (auto st = registry.add(std::move(*t)); !st) return st;
  return {};
}

}  // namespace symb::robot
