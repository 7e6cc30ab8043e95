// SpikeRecorder: what `symb run` keeps of spiking-network controllers (the linda and izhikevich
// task types), from their probes: the "spikes" channel (pairs of spike time in ms and neuron) and
// the "layout" channel (the grown network, control/snn/network_layout.hpp). After the run it
// writes into the output folder's spikes/, per robot and network task:
//   <robot>_<task>.aedat         every spike as an AEDAT 2.0 file (address = neuron, time in us)
//   <robot>_<task>_raster.svg    a spike raster of the first kRasterSeconds
//   <robot>_<task>_network.svg   the grown network on its grid (and _network_2.svg, ... for every
//                                network that replaced it while the robot drove)
// Other probe channels are not its business (takes() says which are).
//
// Thread-safe: under the thread executor the robots' tasks probe from their own threads.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "symb/apps/run/spike_plot.hpp"
#include "symb/control/snn/aer.hpp"
#include "symb/control/snn/development.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/node.hpp"

namespace symb::apps::run {

class SpikeRecorder {
 public:
  static constexpr double kRasterSeconds = 10;
  static constexpr std::size_t kMaxEvents = 4'000'000;  // per network: 32 MB of AEDAT records

  static bool takes(std::string_view channel) { return channel == "spikes" || channel == "layout"; }
  void record(const os::ProbeSample& s);

  // Writes the files above under `dir`/spikes; returns their paths. Call after the run.
  kernel::Result<std::vector<std::filesystem::path>> write(const std::filesystem::path& dir) const;
  std::uint64_t spikes() const;

 private:
  struct Network {
    std::vector<SpikeDot> raster;
    std::vector<control::snn::AerEvent> events;
    std::uint64_t spikes = 0;
    std::uint32_t max_neuron = 0;
    double last_time = 0;
    std::vector<std::pair<double, control::snn::GrownNetwork>> layouts;  // time (s), network
    std::string bad_layout;                                              // the first layout that could not be read
  };
  mutable std::mutex mu_;
  std::map<std::pair<std::string, std::string>, Network> networks_;
};

}  // namespace symb::apps::run
