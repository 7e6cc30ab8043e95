#include "symb/sim/mujoco/module_battery.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace symb::sim::mujoco {

BatteryDevice::BatteryDevice(ModuleBatteries& owner, std::size_t module) : robot::Sensor("battery", channel_specs()) {
  add_ioctl({"share_on", std::nullopt, "shares this battery with docked modules that share theirs"},
            [&owner, module](const os::ParamValue*) -> kernel::Result<std::string> {
              owner.set_sharing(module, true);
              return owner.describe(module);
            });
  add_ioctl({"share_off", std::nullopt, "stops sharing"}, [&owner, module](const os::ParamValue*) {
    owner.set_sharing(module, false);
    return kernel::Result<std::string>(owner.describe(module));
  });
  add_ioctl({"state", std::nullopt, "charge, energy, power and sharing"},
            [&owner, module](const os::ParamValue*) { return kernel::Result<std::string>(owner.describe(module)); });
}

std::vector<robot::ChannelSpec> BatteryDevice::channel_specs() {
  return {robot::ChannelSpec{"charge", "fraction", 0.0f, 1.0f}, robot::ChannelSpec{"energy", "J", 0.0f, 1e9f},
          robot::ChannelSpec{"power", "W", 0.0f, 1e6f}, robot::ChannelSpec{"sharing", "flag", 0.0f, 1.0f}};
}

kernel::Result<std::unique_ptr<ModuleBatteries>> ModuleBatteries::create(MujocoRunner& runner, BatteryModel model) {
  if (!(std::isfinite(model.capacity) && model.capacity > 0))
    return kernel::Error{"battery: the capacity must be a positive number of J"};
  for (const double c : {model.idle, model.wheel, model.hinge, model.share_power})
    if (!(std::isfinite(c) && c >= 0)) return kernel::Error{"battery: power coefficients must be >= 0"};
  auto b = std::unique_ptr<ModuleBatteries>(new ModuleBatteries(runner, model));
  runner.add_observer([raw = b.get()](const MujocoStepRecord& record) { raw->tick(record); });
  return b;
}

ModuleBatteries::ModuleBatteries(MujocoRunner& runner, BatteryModel model)
    : runner_(runner),
      model_(model),
      dt_(kernel::to_seconds(runner.options().period)),
      batteries_(runner.module_count()) {
  for (std::size_t m = 0; m < batteries_.size(); ++m) {
    batteries_[m].energy = model_.capacity;
    devices_.push_back(std::make_shared<BatteryDevice>(*this, m));
  }
}

double ModuleBatteries::energy(std::size_t module) const {
  std::lock_guard lock(mu_);
  return batteries_.at(module).energy;
}

void ModuleBatteries::set_energy(std::size_t module, double joules) {
  std::lock_guard lock(mu_);
  batteries_.at(module).energy = std::clamp(joules, 0.0, model_.capacity);
}

bool ModuleBatteries::sharing(std::size_t module) const {
  std::lock_guard lock(mu_);
  return batteries_.at(module).sharing;
}

void ModuleBatteries::set_sharing(std::size_t module, bool on) {
  std::lock_guard lock(mu_);
  batteries_.at(module).sharing = on;
}

std::string ModuleBatteries::describe(std::size_t module) const {
  std::lock_guard lock(mu_);
  const Battery& b = batteries_.at(module);
  char text[160];
  std::snprintf(text, sizeof text, "charge %.3f (%.1f J of %.1f), power %.3f W, sharing %s%s",
                b.energy / model_.capacity, b.energy, model_.capacity, b.power, b.sharing ? "on" : "off",
                b.empty ? ", empty: no drive" : "");
  return text;
}

void ModuleBatteries::tick(const MujocoStepRecord& record) {
  links_.clear();
  runner_.with_world([&](MujocoWorld& world) {
    for (std::size_t m = 0; m < world.module_count(); ++m)
      for (std::size_t c = 0; c < world.module(m).kind.connectors.size(); ++c)
        if (const auto other = world.docked_to(m, c); other && other->first > m) links_.emplace_back(m, other->first);
  });
  std::vector<std::pair<std::size_t, bool>> changes;
  std::vector<std::array<float, 4>> published(batteries_.size());
  {
    std::lock_guard lock(mu_);
    const std::size_t n = std::min(batteries_.size(), record.modules.size());
    for (std::size_t m = 0; m < n; ++m) {
      const ModuleStep& s = record.modules[m];
      Battery& b = batteries_[m];
      b.power = model_.idle + model_.wheel * (std::abs(s.wheels[0]) + std::abs(s.wheels[1])) +
                model_.hinge * std::abs(s.hinge_speed);
      b.energy = std::max(0.0, b.energy - b.power * dt_);
    }
    for (const auto& [a, o] : links_) {
      Battery& x = batteries_[a];
      Battery& y = batteries_[o];
      if (!x.sharing || !y.sharing || x.energy == y.energy) continue;
      Battery& fuller = x.energy > y.energy ? x : y;
      Battery& emptier = x.energy > y.energy ? y : x;
      const double moved = std::min(model_.share_power * dt_, (fuller.energy - emptier.energy) / 2);
      fuller.energy -= moved;
      emptier.energy += moved;
    }
    for (std::size_t m = 0; m < batteries_.size(); ++m) {
      Battery& b = batteries_[m];
      const bool empty = b.energy <= 0;
      if (empty != b.empty) {
        b.empty = empty;
        changes.emplace_back(m, empty);
      }
      published[m] = {static_cast<float>(b.energy / model_.capacity), static_cast<float>(b.energy),
                      static_cast<float>(b.power), b.sharing ? 1.0f : 0.0f};
    }
  }
  for (const auto& [m, empty] : changes) {
    runner_.set_powered(m, !empty);
    runner_.access()->log(m, empty ? os::LogLevel::kWarn : os::LogLevel::kInfo, "battery",
                          empty ? "battery empty: wheels and hinge get no drive" : "battery recharged: drive back");
  }
  for (std::size_t m = 0; m < devices_.size(); ++m) devices_[m]->publish_state(published[m], record.time);
}

}  // namespace symb::sim::mujoco
