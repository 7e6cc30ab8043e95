#include "symb/apps/view/organism_view.hpp"

#include <memory>

namespace symb::apps::view {

namespace mj = sim::mujoco;

ViewTarget organism_view_target(mj::MujocoRunner& runner, std::vector<std::string> robots,
                                std::vector<os::Node*> nodes) {
  ViewTarget t;
  t.robots = std::move(robots);
  t.nodes = std::move(nodes);
  runner.with_world([&](mj::MujocoWorld& w) {
    for (std::size_t m = 0; m < w.module_count(); ++m) {
      const mj::ModuleSpec& spec = w.module(m);
      ModuleShape shape;
      shape.name = spec.name;
      shape.size = spec.kind.body.size;
      shape.hinge_axis = spec.kind.hinge.axis;
      shape.wheels = spec.kind.has_wheels;
      for (const mj::ConnectorSpec& c : spec.kind.connectors) shape.connectors.emplace_back(c.name, c.position);
      t.organism.push_back(std::move(shape));
    }
  });
  // Reused frame to frame: only the run's thread makes poses frames.
  struct Scratch {
    std::vector<ModulePose> poses;
    std::vector<DockedPair> docked;
  };
  auto scratch = std::make_shared<Scratch>();
  t.poses = [&runner, scratch] {
    std::uint64_t step = 0;
    double seconds = 0;
    runner.with_world([&](mj::MujocoWorld& w) {
      const std::size_t n = w.module_count();
      scratch->poses.resize(n);
      scratch->docked.clear();
      for (std::size_t m = 0; m < n; ++m) {
        const mj::Pose3 p = w.pose(m);
        scratch->poses[m] = {p.position, p.quaternion, w.hinge_angle(m)};
        for (std::size_t c = 0; c < w.module(m).kind.connectors.size(); ++c)
          if (const auto other = w.docked_to(m, c); other && std::pair(m, c) < *other)  // each pair once
            scratch->docked.push_back({m, c, other->first, other->second});
      }
      step = w.steps();
      seconds = w.time();
    });
    return organism_json(step, seconds, scratch->poses, scratch->docked);
  };
  t.seconds = [&runner] {
    double s = 0;
    runner.with_world([&](mj::MujocoWorld& w) { s = w.time(); });
    return s;
  };
  return t;
}

}  // namespace symb::apps::view
