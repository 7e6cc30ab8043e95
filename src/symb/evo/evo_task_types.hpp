// Evo task types: the evo layer's entries in a TaskTypeRegistry, so scenarios, the shell and
// genomes can start on-line evolution by naming it (docs/evolution.md):
//
//   fitness       on-line fitness of one formula (fitness_task.hpp)    formula, reset, command_timeout
//                 defaults: priority 1, queue 8
//   one_plus_one  (1+1)-ONLINE evolution of the robot's controller    evaluation, recovery, genes,
//                 (one_plus_one_task.hpp)                              inputs, layers, activation,
//                                                                      sigma..., task names
//                 defaults: priority 1, period 1 s (only to retry a missing task), queue 8
//   mu_plus_one   encapsulated (mu+1)-ONLINE (mu_plus_one_task.hpp)   mu, rho, sigma, evaluation, ...
//   arbiter       forwards the best of several controller variants (arbiter_task.hpp)
//   medea         mEDEA swarm evolution over a `radio` task (medea_task.hpp)  lifetime, sigma..., names
//
// The candidate controllers are made through the node's own registry (type mlp), so a node that
// runs one_plus_one must also have the control layer's types.
#pragma once

#include "symb/control/control_task_types.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::evo {

// Adds the types above; fails when a name is already taken.
kernel::Status register_evo_task_types(os::TaskTypeRegistry& registry, const control::ControlResources& resources);

}  // namespace symb::evo
