#include "symb/sim/mujoco/world_access.hpp"

#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "symb/os/node.hpp"

namespace symb::sim::mujoco {

std::string connector_device_name(std::string_view connector) { return "connector_" + std::string(connector); }

WorldAccess::WorldAccess(MujocoWorld& world)
    : world_(&world), cursor_(world.docking_log().size()), modules_(world.module_count()), nodes_(modules_, nullptr) {
  for (std::size_t m = 0; m < modules_; ++m) {
    module_names_.push_back(world.module(m).name);
    std::vector<std::string> connectors;
    for (const ConnectorSpec& c : world.module(m).kind.connectors) connectors.push_back(c.name);
    connector_names_.push_back(std::move(connectors));
  }
}

std::vector<DockEvent> WorldAccess::take_dock_events(const MujocoWorld& world) {
  const auto& log = world.docking_log();
  std::vector<DockEvent> fresh(log.begin() + static_cast<std::ptrdiff_t>(cursor_), log.end());
  cursor_ = log.size();
  return fresh;
}

void WorldAccess::close() {
  {
    std::lock_guard lock(world_mu_);
    world_ = nullptr;
  }
  std::lock_guard lock(node_mu_);
  std::fill(nodes_.begin(), nodes_.end(), nullptr);
}

void WorldAccess::set_node(std::size_t module, os::Node* node) {
  if (module >= modules_) throw std::out_of_range("world access: no module " + std::to_string(module));
  std::lock_guard lock(node_mu_);
  nodes_[module] = node;
}

void WorldAccess::log(std::size_t module, os::LogLevel level, std::string_view source, std::string_view text) {
  std::lock_guard lock(node_mu_);
  if (module < modules_ && nodes_[module] != nullptr) nodes_[module]->log().write(level, source, text);
}

void WorldAccess::log_all(os::LogLevel level, std::string_view source, std::string_view text) {
  std::lock_guard lock(node_mu_);
  for (os::Node* node : nodes_)
    if (node != nullptr) node->log().write(level, source, text);
}

namespace {

// "(4.12 mm, 0.31 deg apart, step 215)": what the world measured when it decided.
std::string mj_access_measures(const DockEvent& e) {
  char text[96];
  if (e.distance < 0)
    std::snprintf(text, sizeof text, "(step %llu)", static_cast<unsigned long long>(e.step));
  else
    std::snprintf(text, sizeof text, "(%.2f mm, %.2f deg apart, step %llu)", e.distance * 1000,
                  e.angle * 180 / std::numbers::pi, static_cast<unsigned long long>(e.step));
  return text;
}

}  // namespace

void WorldAccess::log_dock_events(const std::vector<DockEvent>& events) {
  if (events.empty()) return;
  auto label = [&](std::size_t m, std::size_t c) { return module_names_[m] + "." + connector_names_[m][c]; };
  for (const DockEvent& e : events) {
    if (e.module >= modules_ || e.connector >= connector_names_[e.module].size()) continue;
    const std::string source = connector_device_name(connector_names_[e.module][e.connector]);
    const bool partner = e.other_module < modules_ && e.other_connector < connector_names_[e.other_module].size();
    switch (e.change) {
      case DockChange::kLatched:
      case DockChange::kUnlatched: {
        const std::string verb = e.change == DockChange::kLatched ? "latched" : "unlatched";
        const std::string how = mj_access_measures(e) + ", " + e.reason;
        log(e.module, os::LogLevel::kInfo, source,
            verb + " " + connector_names_[e.module][e.connector] +
                (partner ? " to " + label(e.other_module, e.other_connector) : "") + " " + how);
        if (partner && e.other_module != e.module)
          log(e.other_module, os::LogLevel::kInfo,
              connector_device_name(connector_names_[e.other_module][e.other_connector]),
              verb + " " + connector_names_[e.other_module][e.other_connector] + " to " + label(e.module, e.connector) +
                  " (" + verb + " by " + module_names_[e.module] + ") " + how);
        break;
      }
      case DockChange::kRefused:
        log(e.module, os::LogLevel::kWarn, source,
            "refused " + connector_names_[e.module][e.connector] + ": " + e.reason + " " + mj_access_measures(e));
        break;
    }
  }
}

}  // namespace symb::sim::mujoco
