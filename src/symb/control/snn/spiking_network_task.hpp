// SpikingNetworkTask: an Izhikevich spiking network (snn/spiking_network.hpp) as a controller task
// (paper IV-B): the network lives in its own 1 ms time and is stepped in batches on the task's
// period, catching up with the node clock; spikes leave as AER packets (snn/aer.hpp):
//
//   spike_encoder --currents or AER events--> SpikingNetworkTask --port 0: all spikes (AER)----> raster, other modules
//                                                                --port 1: output channels (AER)--> spike_decoder -->
//                                                                wheels
//
// Contract (docs/linda.md):
//  - In (any port): a vector of numbers = one input current per input channel (channel k gets
//    value k; missing values are 0, values for channels the network lacks are ignored), held until
//    the next vector; or an AER packet whose events' neuron field is an input channel: each event
//    adds `pulse` to the channel's neurons in the 1 ms step of its timestamp (late events in the
//    next step; events more than kMaxLead ahead, or beyond kMaxQueuedEvents, are dropped and
//    counted). A channel drives the neurons the network's input map gives it. Non-finite numbers,
//    foreign blobs: counted and ignored with a rate-limited warning.
//  - Out, after each batch with spikes: port 0 (kAllSpikesPort) the batch's spikes, address
//    (module, neuron), timestamp the start of the step they fired in; port 1 (kOutputSpikesPort)
//    the spikes of output-channel neurons, address (module, channel).
//  - Probes: "spikes" (pairs: spike time in ms of node time, neuron), "rate" (population rate in
//    Hz over the batch), and "layout" (snn/network_layout.hpp) once after creation and after a
//    network is replaced.
//  - A replacement network (the `genome` or `seed` parameter, through options.grow) takes over at
//    the next step; held currents and queued events stay (they are per channel, not per neuron).
//    A genome that does not parse or grow is refused and the running network goes on.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "symb/control/snn/aer.hpp"
#include "symb/control/snn/development.hpp"
#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control {

inline constexpr os::Port kAllSpikesPort = 0;
inline constexpr os::Port kOutputSpikesPort = 1;

struct SpikingNetworkTaskOptions {
  std::uint32_t module = 0;  // the AER module bits of every address this task sends
  float pulse = 20;          // current of one input event
  // The reference network's random "thalamic" input (snn/reference_network.hpp) every step, from
  // the task's own random stream: the first `thalamic_excitatory` neurons excitatory.
  bool thalamic = false;
  std::size_t thalamic_excitatory = 0;
  // Builds a network from the `genome` and `seed` parameters when they change at runtime (the
  // linda type); empty: those parameters are refused.
  std::function<kernel::Result<snn::GrownNetwork>(const std::string& genome, std::int64_t seed)> grow;
  std::string genome;  // the current values of those parameters
  std::int64_t seed = 0;
  kernel::Duration max_catch_up = std::chrono::seconds(1);  // more lag than this is skipped, counted
  kernel::Duration warn_interval = std::chrono::seconds(1);
};

struct SpikingNetworkStats {
  std::uint64_t steps = 0;          // 1 ms network steps
  std::uint64_t spikes = 0;         // all neurons
  std::uint64_t output_spikes = 0;  // output-channel events sent
  std::uint64_t current_vectors = 0;
  std::uint64_t input_events = 0;    // accepted AER input events
  std::uint64_t late_events = 0;     // applied in the step after their own
  std::uint64_t dropped_events = 0;  // too far ahead, or the queue full
  std::uint64_t ignored = 0;         // bad messages
  std::uint64_t skipped_ms = 0;      // network time skipped (lag beyond max_catch_up)
  std::uint64_t replacements = 0;
};

class SpikingNetworkTask : public os::Task {
 public:
  static constexpr std::size_t kMaxQueuedEvents = 1u << 16;
  static constexpr kernel::Duration kMaxLead = std::chrono::seconds(1);

  // Checks the network (SpikingNetwork::create) and the options.
  static kernel::Result<std::unique_ptr<SpikingNetworkTask>> create(snn::GrownNetwork network,
                                                                    SpikingNetworkTaskOptions options);

  // Safe from any thread.
  SpikingNetworkStats stats() const;
  // How many neurons and channels the running network has.
  std::size_t neurons() const;

 protected:
  void on_start() override;
  void on_tick() override;
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  // Replaces the running network (checked first; on error the old one keeps running).
  kernel::Status replace(snn::GrownNetwork network);

  struct Running {
    snn::SpikingNetwork net;
    snn::GrownNetwork grown;
    std::vector<std::vector<std::uint32_t>> output_channels_of;  // per neuron
  };
  struct QueuedEvent {
    std::int64_t step;  // network step (ms since start)
    std::uint32_t channel;
    bool operator>(const QueuedEvent& o) const { return step != o.step ? step > o.step : channel > o.channel; }
  };

  SpikingNetworkTask(Running running, SpikingNetworkTaskOptions options);
  static kernel::Result<Running> make_running(snn::GrownNetwork network);
  void ignore(const std::string& why);
  void run_step(std::vector<snn::AerEvent>& all, std::vector<snn::AerEvent>& outputs);

  Running run_;
  SpikingNetworkTaskOptions options_;
  kernel::Time start_{0};
  bool started_ = false;
  bool layout_due_ = true;
  std::int64_t step_ = 0;           // the next network step (ms since start_)
  std::vector<float> currents_;     // per input channel, held
  std::vector<QueuedEvent> queue_;  // a min-heap by step
  std::vector<float> spike_probe_;
  os::WarningLimiter warning_;

  struct Counters {  // kernel/counter.hpp
    kernel::Counter steps, spikes, output_spikes, current_vectors, input_events, late_events, dropped_events, ignored,
        skipped_ms, replacements;
    SpikingNetworkStats snapshot() const {
      return {.steps = steps.load(),
              .spikes = spikes.load(),
              .output_spikes = output_spikes.load(),
              .current_vectors = current_vectors.load(),
              .input_events = input_events.load(),
              .late_events = late_events.load(),
              .dropped_events = dropped_events.load(),
              .ignored = ignored.load(),
              .skipped_ms = skipped_ms.load(),
              .replacements = replacements.load()};
    }
  } counters_;
  mutable std::mutex mu_;  // neurons_
  std::size_t neurons_ = 0;
};

}  // namespace symb::control
