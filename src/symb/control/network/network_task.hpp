// NetworkTask: a neural network (network/network.hpp) as a controller task, and as one stage of an
// ANN circuit (paper section III-C: networks are tasks, coupled by hooks, replaced at runtime):
//
//   ir --port 0--> NetworkTask --port 0: [left, right] wheel units--> wheels
//                              --port 1: the raw output vector------> another NetworkTask
//
// Contract (docs/networks.md):
//  - In, port `input_port` (default 0): the input vector, exactly the network's input count of
//    finite numbers. Each is multiplied by its input scale (default 1/4505, the Thymio's IR range)
//    and the network takes one step at once; so a network steps exactly when new data arrives and
//    never sends a command computed from nothing. Anything else (wrong length, NaN, a blob, another
//    port) is counted and ignored, with a rate-limited warning.
//  - Out, after every step, by the `output` mode:
//      wheels (default): port 0: [left, right] from outputs 0 and 1, times output_scale (default
//        500); outputs in (0, 1) (sigmoid activation, ctrnn) are first centred to 2o - 1. Clamped
//        to +-speed_limit, never NaN. Needs 2 or more outputs.
//      raw: port 0: the raw output vector, for a network feeding another one (a circuit stage).
//      both: wheels on port 0 and the raw vector on port 1 (kRawOutputPort); hook the wheels with
//        port 0 then, since the wheels task would take the raw vector for a command too.
//  - Probes: "activations/<layer>" per layer (input, hidden1.., output; ctrnn: input, state) and
//    "outputs" after every step.
//  - Runtime parameters: weights (a genome: inline numbers or a reference to a weight file),
//    input_scale, output_scale, speed_limit, tau and dt (ctrnn). A new genome keeps the state
//    (Elman context, CTRNN y), except that a ctrnn's firing rates follow its new biases.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "symb/control/control_task_types.hpp"
#include "symb/control/network/network.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control {

inline constexpr os::Port kNetworkWheelPort = 0;
inline constexpr os::Port kRawOutputPort = 1;
// The Thymio's IR readings run 0..~4505: this maps them to 0..1.
inline constexpr float kIrInputScale = 1.0f / 4505.0f;

enum class NetworkOutput { kWheels, kRaw, kBoth };
kernel::Result<NetworkOutput> parse_network_output(std::string_view text);

struct NetworkTaskOptions {
  NetworkOutput output = NetworkOutput::kWheels;
  std::vector<float> input_scale{kIrInputScale};  // one factor, or one per input
  double output_scale = 500;                      // > 0
  double speed_limit = 500;                       // > 0
  os::Port input_port = 0;
  kernel::Duration warn_interval = std::chrono::seconds(1);
};

// What a running network task takes at runtime besides its options: new weights (numbers or a
// weight file reference, as read_weights reads them) and, for a ctrnn, time constants and step.
struct NetworkModelParams {
  std::string weights;
  std::string tau = "0.1";
  kernel::Duration dt = std::chrono::milliseconds(30);
};

struct NetworkStats {
  std::uint64_t steps = 0;    // network steps (each sent its outputs)
  std::uint64_t inputs = 0;   // good input vectors
  std::uint64_t ignored = 0;  // bad or foreign messages
  std::uint64_t clamped = 0;  // wheel values cut to the speed limit (or non-finite, sent as 0)
  std::uint64_t genomes = 0;  // genomes written at runtime
};

// Parses a `weights` value: inline numbers ("0.5 -0.25 ...") or, when it does not start like a
// number, a reference that `resources.read_program` turns into a weight file's text. Errors give
// LINE:COLUMN inside the numbers. Empty text gives an empty list.
kernel::Result<std::vector<float>> read_weights(std::string_view value, const ControlResources& resources);

class NetworkTask : public os::Task {
 public:
  // Checks the options against the network (input_scale count, an output vector one message can
  // carry); `resources` resolves weight references given at runtime (may be null: inline only).
  static kernel::Result<std::unique_ptr<NetworkTask>> create(network::Network net, NetworkTaskOptions options,
                                                             std::shared_ptr<const ControlResources> resources = {});

  // Safe from any thread.
  NetworkStats stats() const;
  std::vector<float> genome() const;
  std::vector<float> last_outputs() const;
  std::size_t genome_size() const { return genome_size_; }

 protected:
  void on_message(const os::Message& m) override;
  // weights, input_scale, tau and dt are checked against the network and written into it.
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  NetworkTask(network::Network net, NetworkTaskOptions options, std::shared_ptr<const ControlResources> resources);
  void ignore(const std::string& why);
  float wheel(float raw, std::uint64_t& clamped) const;

  network::Network net_;
  NetworkTaskOptions options_;
  NetworkModelParams model_params_;
  std::shared_ptr<const ControlResources> resources_;
  std::size_t genome_size_;
  bool centred_;  // outputs in (0, 1): centre them for the wheels
  std::vector<float> scaled_;
  std::vector<std::string> channels_;  // "activations/<layer>", made once
  os::WarningLimiter warning_;

  struct Counters {  // kernel/counter.hpp
    kernel::Counter steps, inputs, ignored, clamped, genomes;
    NetworkStats snapshot() const {
      return {.steps = steps.load(),
              .inputs = inputs.load(),
              .ignored = ignored.load(),
              .clamped = clamped.load(),
              .genomes = genomes.load()};
    }
  } counters_;
  mutable std::mutex mu_;  // the copies genome() and last_outputs() read
  std::vector<float> genome_copy_;
  std::vector<float> outputs_copy_;
};

}  // namespace symb::control
