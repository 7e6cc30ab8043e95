// Spike pictures for `symb run` output folders: a spike raster (one dot per spike, time on x,
// neuron on y) and the grown network of a Linda controller on its developmental grid (neurons at
// their sites coloured by class, synapses as arrows, input and output channels marked), for a
// person to look at after a run. Plain SVG 1.1 in the style of probe_plot.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "symb/control/snn/development.hpp"

namespace symb::apps::run {

struct SpikeDot {
  double time_s = 0;
  std::uint32_t neuron = 0;
};

// Rasters with more dots than this keep every k-th spike (the title says so), so a long run's
// picture stays a few MB that a browser can open.
inline constexpr std::size_t kMaxRasterDots = 200'000;

// A spike raster: one <circle> per drawn spike, time (s) on x, neuron on y (neuron 0 at the
// bottom); `neurons` rows, more when a spike names a higher neuron; spikes at non-finite times
// are left out.
std::string raster_svg(std::span<const SpikeDot> spikes, std::size_t neurons, std::string_view title);

// The grown network on its width x height grid (site (0, 0) top left): one <circle> per neuron at
// its site, coloured by class (a legend); one <line> per synapse from source to target with an
// arrow head, excitatory blue, inhibitory red, width by |weight|; the neurons that input channels
// drive and output channels read marked "in C" / "out C". Neurons or synapses whose indices or
// sites are out of range are left out, never a crash.
std::string network_svg(const control::snn::GrownNetwork& net, std::string_view title);

}  // namespace symb::apps::run
