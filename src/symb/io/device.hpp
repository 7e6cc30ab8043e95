// Device: anything the robot talks to through a driver (the paper's Device class): it can be
// opened, closed and sent control commands (ioctl), like a Linux device. Where Linux passes an
// untyped request number and pointer, a Device here declares each command it understands by name
// with a typed, documented argument (an os::ParamSpec), so the shell can list them, check them and
// call them, and a wrong or unknown command is an error, never undefined behaviour.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/os/param.hpp"

namespace symb::io {

struct IoctlSpec {
  std::string name;
  std::optional<os::ParamSpec> arg;  // nullopt: the command takes no argument
  std::string doc;
};

class Device {
 public:
  explicit Device(std::string name) : name_(std::move(name)) {}
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const std::string& name() const { return name_; }
  virtual kernel::Status open() = 0;
  virtual void close() = 0;
  virtual bool is_open() const = 0;

  // Runs control command `command`; `arg` is text checked against the command's argument spec.
  // Returns the command's answer as text (e.g. the current baud rate) or an error naming the
  // device and the command, with a "did you mean" hint for a misspelt one.
  kernel::Result<std::string> ioctl(std::string_view command, std::string_view arg = {});
  // The same with an already typed argument (for C++ callers).
  kernel::Result<std::string> ioctl_value(std::string_view command, const os::ParamValue& arg);
  // Every command this device understands, in the order they were added.
  std::vector<IoctlSpec> ioctls() const;

 protected:
  using IoctlHandler = std::function<kernel::Result<std::string>(const os::ParamValue* arg)>;
  // Subclasses declare their commands (usually in their constructor).
  void add_ioctl(IoctlSpec spec, IoctlHandler handler);

 private:
  struct Command {
    IoctlSpec spec;
    IoctlHandler handler;
  };
  const Command* find(std::string_view command, std::string& error) const;

  std::string name_;
  std::vector<Command> commands_;
};

}  // namespace symb::io
