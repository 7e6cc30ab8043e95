// Task types for spiking networks (docs/linda.md): the control layer's entries in a
// TaskTypeRegistry, added by register_control_task_types():
//
//   linda          a spiking network grown from a Linda genome   genome, seed, module, pulse
//   izhikevich     a built-in example network (the 2003 paper's 800/200 random network, with its
//                  thalamic noise input)                          example, excitatory, inhibitory,
//                                                                 network_seed, integration, module
//   spike_encoder  sensor values to input currents or rate-coded AER events   coding, gain, ...
//   spike_decoder  output-channel spike rates to wheel commands                gain, offset, ...
//   aer_codec      AER packets to bytes and back, for spikes crossing byte links between nodes
//
// Network tasks step in 1 ms steps, in batches of their period (default 10 ms). Genomes are a
// reference that ControlResources::read_program resolves, or the genome text itself (a value
// holding a line break or starting with "grid" or '#'): evolution writes genomes inline.
#pragma once

#include <string>
#include <string_view>

#include "symb/control/control_task_types.hpp"
#include "symb/control/snn/development.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

// Reads (inline or through resources), parses and grows a genome. Errors name the reference and
// carry the parser's LINE:COLUMN.
kernel::Result<snn::GrownNetwork> grow_genome(std::string_view genome, std::uint64_t seed,
                                              const ControlResources& resources);

kernel::Status register_snn_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources);

}  // namespace symb::control
