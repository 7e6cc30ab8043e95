#include "symb/sim/world_factory.hpp"

#include <algorithm>

#include "symb/sim/box2d/box2d_world.hpp"
#include "symb/sim/enki_world.hpp"

namespace symb::sim {

std::unique_ptr<World> make_world(const WorldSpec& spec, std::uint64_t seed, std::size_t robots) {
  switch (spec.engine) {
    case Engine2d::kBox2d: return std::make_unique<Box2DWorld>(spec, seed);
    case Engine2d::kEnki: break;
  }
  EnkiWorld::Options options;
  options.max_robots = std::max<std::size_t>(robots, 1);
  return std::make_unique<EnkiWorld>(spec, seed, options);
}

const char* engine_name(Engine2d engine) { return engine == Engine2d::kBox2d ? "box2d" : "enki"; }

}  // namespace symb::sim
