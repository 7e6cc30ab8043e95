// A task-type plugin, built against the installed Symbricator (docs/plugins.md): `my_braitenberg`,
// a Braitenberg vehicle (type 3b, "explorer") for a Thymio's 7 horizontal IR sensors. Each wheel
// runs at `speed` and is slowed by the readings on its own side and sped up by the other side's,
// so the robot turns away from what it sees. In on port 0: 7 IR readings; out on port 0: the
// wheel command [left, right] in motor units. One parameter is live: `set NAME gain 2` from a shell.
#include <algorithm>
#include <array>
#include <memory>

#include "symb/os/plugin.hpp"
#include "symb/os/task.hpp"
#include "symb/robot/ports.hpp"

namespace my_controller {

using namespace symb;

struct BraitenbergOptions {
  double speed = 200;   // motor units, both wheels, when nothing is seen
  double gain = 1.0;    // how hard a reading turns the robot
  double range = 4505;  // the IR reading that counts as touching
};

class Braitenberg : public os::Task {
 public:
  explicit Braitenberg(const BraitenbergOptions& o) : options_(o) { bind_parameters(options_); }

 protected:
  void on_message(const os::Message& m) override {
    const auto ir = m.numbers();
    if (m.port != 0 || ir.size() < 7) return;
    // Sensors 0..4 face front, left to right; 5 and 6 face back.
    static constexpr std::array<double, 5> kLeft{1.0, 0.8, 0.4, -0.8, -1.0};
    double turn = 0;
    for (std::size_t i = 0; i < kLeft.size(); ++i) turn += kLeft[i] * std::clamp(ir[i] / options_.range, 0.0, 1.0);
    const double forward = options_.speed * (1.0 - std::clamp(ir[2] / options_.range, 0.0, 1.0));
    const double steer = options_.gain * options_.speed * turn;
    send(0, {static_cast<float>(forward + steer), static_cast<float>(forward - steer)});
    probe("turn", {static_cast<float>(turn)});
  }

 private:
  BraitenbergOptions options_;
};

kernel::Status register_types(os::TaskTypeRegistry& registry) {
  using O = BraitenbergOptions;
  os::ParamTable<O> p;
  p.add("speed", &O::speed).range(0.0, 500.0).doc("wheel speed with nothing in sight (motor units)").live();
  p.add("gain", &O::gain).range(0.0, 10.0).doc("how hard the IR readings turn the robot").live();
  p.add("range", &O::range).range(1.0, 10000.0).doc("the IR reading that counts as touching");
  auto t = os::declare_task_type("my_braitenberg", "Braitenberg explorer: 7 IR readings in, [left, right] out",
                                 std::move(p), [](const O& o) { return std::make_unique<Braitenberg>(o); });
  t.inputs = {{0, "ir", robot::layout::kSensorVector}};
  t.outputs = {{0, "wheels", robot::layout::kWheelCommand}};
  return registry.add(std::move(t));
}

}  // namespace my_controller

SYMB_PLUGIN(my_controller::register_types)
