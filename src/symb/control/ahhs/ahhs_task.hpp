// AhhsTask: a whole AHHS hormone network in one controller task. Sensor vectors come in, every
// vector steps the network once, and the actuators go out scaled to wheel units:
//
//   ir --port 0--> AhhsTask --port 0--> wheels        [a0 * scale, a1 * scale, ...]
//
// Contract (docs/ahhs.md, "Task types"):
//  - In, port 0: at least Model::sensor_count() finite numbers; each is normalised to
//    clamp(value / sensor_range, 0, 1). Anything else (short, NaN, a blob, another port) is counted
//    and ignored with a warning at a limited rate; the network does not step on it.
//  - Out, port 0: the actuator vector (actuator index order), each in [-1, 1] times actuator_scale.
//  - Probes, once per step: "hormones/c<k>" (levels of compartment k, for the first
//    kMaxProbedCompartments compartments) and "actuators" (values in [-1, 1]).
//  - No period needed: the network steps on data, one step per sensor vector.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "symb/control/ahhs/model.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control {

inline constexpr os::Port kAhhsSensorPort = 0;
inline constexpr os::Port kAhhsActuatorPort = 0;
inline constexpr std::size_t kMaxProbedCompartments = 64;

struct AhhsTaskOptions {
  double sensor_range = 4505;   // > 0: a raw value of this reads 1
  double actuator_scale = 300;  // > 0: an actuator at 1 sends this
  kernel::Duration warn_interval = std::chrono::seconds(1);
};
kernel::Status check(const AhhsTaskOptions& o);

struct AhhsStats {
  std::uint64_t steps = 0;
  std::uint64_t ignored = 0;  // messages not used
};

class AhhsTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<AhhsTask>> create(ahhs::Network network, AhhsTaskOptions options = {});

  // Safe from any thread.
  std::vector<float> levels(std::uint32_t compartment) const;
  std::vector<float> actuators() const;
  AhhsStats stats() const;

 protected:
  void on_message(const os::Message& m) override;

 private:
  AhhsTask(ahhs::Model model, AhhsTaskOptions options);
  void ignore(const std::string& why);

  AhhsTaskOptions options_;
  std::vector<float> sensors_;
  std::vector<float> out_;
  os::WarningLimiter warning_;
  mutable std::mutex mu_;  // model_, for readers on other threads
  ahhs::Model model_;
  struct Counters {  // kernel/counter.hpp
    kernel::Counter steps, ignored;
    AhhsStats snapshot() const { return {.steps = steps.load(), .ignored = ignored.load()}; }
  } counters_;
};

// Normalises a raw sensor vector into `out` (clamp(v / range, 0, 1)); false, with `why`, when the
// vector is too short or not finite.
bool normalise_sensors(std::span<const float> raw, std::size_t needed, double range, std::vector<float>& out,
                       std::string& why);

}  // namespace symb::control
