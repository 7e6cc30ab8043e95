// The web view of a 3D organism run (`symb run scenarios/caterpillar.yaml --view PORT`): a
// ViewTarget whose world is the MuJoCo world's modules. The hello frame carries each module's
// shape (box size, hinge axis, connectors, from its kind); each poses frame every module's
// position, orientation and hinge angle and the docked connector pairs, read from the world under
// the runner's lock (MujocoRunner::with_world) between two slices of the run.
#pragma once

#include <string>
#include <vector>

#include "symb/apps/view/live_view.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"

namespace symb::apps::view {

// `robots[i]` and `nodes[i]` are module i's name and node. The runner and the nodes must outlive
// the view.
ViewTarget organism_view_target(sim::mujoco::MujocoRunner& runner, std::vector<std::string> robots,
                                std::vector<os::Node*> nodes);

}  // namespace symb::apps::view
