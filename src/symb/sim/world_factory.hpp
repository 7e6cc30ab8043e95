// make_world: the 2D World a WorldSpec names in its `engine` (EnkiWorld or Box2DWorld), so the
// code that runs a scenario (sessions, the HIL simulator, evolution) does not choose a backend.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "symb/sim/world.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim {

// `robots`: how many robots will be added (Enki reserves their address space up front; at least
// 1). Throws std::invalid_argument on a spec the backend refuses (see its check_spec).
std::unique_ptr<World> make_world(const WorldSpec& spec, std::uint64_t seed, std::size_t robots);

// "enki" or "box2d": the word scenario files use.
const char* engine_name(Engine2d engine);

}  // namespace symb::sim
