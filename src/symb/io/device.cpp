#include "symb/io/device.hpp"

namespace symb::io {

using kernel::Error;

void Device::add_ioctl(IoctlSpec spec, IoctlHandler handler) {
  commands_.push_back({std::move(spec), std::move(handler)});
}

std::vector<IoctlSpec> Device::ioctls() const {
  std::vector<IoctlSpec> out;
  out.reserve(commands_.size());
  for (const auto& c : commands_) out.push_back(c.spec);
  return out;
}

const Device::Command* Device::find(std::string_view command, std::string& error) const {
  for (const auto& c : commands_)
    if (c.spec.name == command) return &c;
  std::vector<std::string_view> names;
  for (const auto& c : commands_) names.push_back(c.spec.name);
  error = "device '" + name_ + "' has no ioctl '" + std::string(command.substr(0, 63)) + "'";
  if (auto hint = os::closest_name(command, names); !hint.empty()) error += " (did you mean '" + hint + "'?)";
  return nullptr;
}

kernel::Result<std::string> Device::ioctl(std::string_view command, std::string_view arg) {
  std::string error;
  const Command* c = find(command, error);
  if (c == nullptr) return Error{error};
  if (!c->spec.arg) {
    if (!arg.empty()) return Error{"ioctl '" + c->spec.name + "' of device '" + name_ + "' takes no argument"};
    return c->handler(nullptr);
  }
  if (arg.empty())
    return Error{"ioctl '" + c->spec.name + "' of device '" + name_ + "' needs a " + os::to_string(c->spec.arg->type) +
                 " argument"};
  auto v = os::parse_param_value(*c->spec.arg, arg);
  if (!v) return Error{"ioctl '" + c->spec.name + "' of device '" + name_ + "': " + v.error()};
  return c->handler(&*v);
}

kernel::Result<std::string> Device::ioctl_value(std::string_view command, const os::ParamValue& arg) {
  std::string error;
  const Command* c = find(command, error);
  if (c == nullptr) return Error{error};
  if (!c->spec.arg) return Error{"ioctl '" + c->spec.name + "' of device '" + name_ + "' takes no argument"};
  if (auto st = os::check_param_value(*c->spec.arg, arg); !st)
    return Error{"ioctl '" + c->spec.name + "' of device '" + name_ + "': " + st.error()};
  return c->handler(&arg);
}

}  // namespace symb::io
