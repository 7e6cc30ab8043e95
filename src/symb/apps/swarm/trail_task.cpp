#include "symb/apps/swarm/trail_task.hpp"

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

void TrailTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  if (v.size() < PoseLayout::kCount) return;
  log_.add(v[PoseLayout::kX], v[PoseLayout::kY], v[PoseLayout::kContact] != 0.0f);
}

}  // namespace symb::apps::swarm
