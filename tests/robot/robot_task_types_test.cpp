#include "symb/robot/robot_task_types.hpp"

#include <map>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/actuator_task.hpp"

#include "fakes.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;
using testing::Collector;

class ConstAdc final : public PollingSensor {
 public:
  ConstAdc() : PollingSensor("adc", {{"a0", "raw", 0, 1023}, {"a1", "raw", 0, 1023}}) {}
  kernel::Status poll(kernel::Time, std::span<float> out) override {
    out[0] = 500, out[1] = 20;
    return {};
  }
};

class NullLeds final : public Actuator {
 public:
  NullLeds() : Actuator("leds", {{"r", "", 0, 1}}) {}

 protected:
  kernel::Status apply(std::span<const float>) override { return {}; }
};

// A node's devices, as a board application would hold them.
struct Devices {
  std::shared_ptr<Sensor> ir = std::make_shared<Sensor>("ir", std::vector<ChannelSpec>{{"ir0", "raw", 0, 1023}});
  std::shared_ptr<PollingSensor> adc = std::make_shared<ConstAdc>();
  std::shared_ptr<Actuator> leds = std::make_shared<NullLeds>();
  std::shared_ptr<testing::FakeDrive> wheels = std::make_shared<testing::FakeDrive>(0.5);

  RobotDevices lookups() {
    RobotDevices d;
    d.sensor = [this](std::string_view n) { return n == "ir" ? ir : nullptr; };
    d.polling_sensor = [this](std::string_view n) { return n == "adc" ? adc : nullptr; };
    d.actuator = [this](std::string_view n) { return n == "leds" ? leds : nullptr; };
    d.drive = [this](std::string_view n) -> std::shared_ptr<DifferentialDrive> {
      if (n == "wheels") return wheels;
      return nullptr;
    };
    return d;
  }
};

kernel::Result<os::TaskId> create(os::Node& node, std::string_view type, std::string name, std::string_view params,
                                  std::optional<os::TaskOptions> options = std::nullopt) {
  auto a = os::parse_param_assignments(params);
  if (!a) return kernel::Error{a.error()};
  return node.create(type, std::move(name), *a, options);
}

TEST(RobotTaskTypes, RegistersEveryTypeWithItsSchema) {
  Devices devices;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_robot_task_types(registry, devices.lookups()));
  for (const char* name : {"sensor", "polling_sensor", "actuator_sink", "actuator_task"})
    EXPECT_NE(registry.find(name), nullptr) << name;
  EXPECT_EQ(registry.find("polling_sensor")->defaults.period, kernel::Duration{30ms});
  EXPECT_NE(registry.find("actuator_task")->param("kp_turn"), nullptr);
  EXPECT_FALSE(register_robot_task_types(registry, devices.lookups()));  // names taken
}

TEST(RobotTaskTypes, CreatesWorkingTasksByNameWithParameters) {
  Devices devices;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_robot_task_types(registry, devices.lookups()));
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot", .types = &registry});
  auto adc = create(node, "polling_sensor", "adc_task", "device=adc ranges=0:100,0:10");
  ASSERT_TRUE(adc) << adc.error();
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(*adc, *node.create("c", std::move(c))));
  ex.run_for(60ms);  // the type's default period, 30 ms
  ASSERT_EQ(col->count(), 2u);
  EXPECT_EQ(col->received()[0].values, (std::vector<float>{100, 10}));
  EXPECT_EQ(col->received()[1].time, kernel::Time{60ms});

  auto ir = create(node, "sensor", "ir_task", "device=ir warn_interval=5s");
  ASSERT_TRUE(ir) << ir.error();
  auto sink = create(node, "actuator_sink", "led_task", "device=leds");
  ASSERT_TRUE(sink) << sink.error();
  auto base = create(node, "actuator_task", "base", "drive=wheels odometry=wheels kp_turn=3 odometry_timeout=0.5s",
                     os::TaskOptions{.period = 10ms});
  ASSERT_TRUE(base) << base.error();
  ex.run_for(1ms);
  EXPECT_TRUE(devices.ir->has_listener());
  EXPECT_EQ(node.info(*base)->period, kernel::Duration{10ms});
  EXPECT_EQ(node.info(*base)->type, "actuator_task");

  // Runtime parameter changes: gains yes, the odometry format (fixed at creation) no.
  ASSERT_TRUE(node.set_parameter(*base, "kp_distance", "3.5"));
  ASSERT_TRUE(node.set_parameter(*base, "odometry", "pose"));
  ex.run_for(1ms);
  auto values = node.parameters(*base);
  ASSERT_TRUE(values);
  EXPECT_EQ(values->real("kp_distance"), 3.5);
  EXPECT_EQ(values->string("odometry"), "wheels");
}

TEST(RobotTaskTypes, CreationErrorsNameTheProblem) {
  Devices devices;
  os::TaskTypeRegistry registry;
  RobotDevices partial = devices.lookups();
  partial.actuator = nullptr;
  ASSERT_TRUE(register_robot_task_types(registry, partial));
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot", .types = &registry});
  const auto error = [&](std::string_view type, std::string_view params) {
    auto r = create(node, type, "t", params);
    return r ? std::string("(created)") : r.error();
  };
  EXPECT_NE(error("sensor", "").find("name the sensor to use: device=NAME"), std::string::npos);
  EXPECT_NE(error("sensor", "device=eye").find("no sensor named 'eye'"), std::string::npos);
  EXPECT_NE(error("actuator_sink", "device=leds").find("this node has no actuator devices"), std::string::npos);
  EXPECT_NE(error("polling_sensor", "device=adc ranges=0:1,2").find("ranges: column 6: expected ':'"),
            std::string::npos);
  EXPECT_NE(error("actuator_task", "drive=wheels odometry=legs").find("odometry must be 'pose' or 'wheels'"),
            std::string::npos);
  EXPECT_NE(error("actuator_task", "drive=wheels command_port=0").find("different ports"), std::string::npos);
  EXPECT_NE(error("actuator_task", "drive=wheels kp_trun=1").find("did you mean 'kp_turn'"), std::string::npos);
  EXPECT_NE(error("actuator_task", "drive=wheels max_speed=-1").find("max_speed"), std::string::npos);
  EXPECT_EQ(node.task_count(), 0u);
}

}  // namespace
}  // namespace symb::robot
