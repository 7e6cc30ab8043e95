// PluginLibrary: a task-type plugin (os/plugin.hpp) loaded from its shared library. Opening it
// loads the file, finds its entry point and checks its ABI version by a first registration into a
// scratch registry, so a plugin that cannot work is refused at once, with an error naming the file:
// one that does not load, lacks the entry point, was built for another ABI, or whose registration
// fails or throws. register_into() then adds its types to any registry, all or none.
//
// A loaded library is never unloaded: the types it registered (their factories, their parameter
// tables) and every task made from them run its code, and they may live as long as the process
// (the shared types of a session, a task made from a shell). A library that failed to open is
// unloaded again.
//
// Symbols: the host's libraries are shared (SYMB_BUILD_SHARED) and the plugin links the same
// libsymb_*.so, so both see one copy of every function; the plugin is opened RTLD_LOCAL, so its
// own symbols cannot clash with another plugin's.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/os/plugin.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::io {

class PluginLibrary {
 public:
  // `path` as the user gave it (a relative path is taken from the working directory, never
  // searched for along LD_LIBRARY_PATH).
  static kernel::Result<std::shared_ptr<const PluginLibrary>> open(const std::string& path);

  // Adds the plugin's types to `registry`: all of them, or, on an error (a name the registry
  // already has, a registration that fails this time), none. The error names the file.
  kernel::Status register_into(os::TaskTypeRegistry& registry) const;

  const std::string& path() const { return path_; }
  // The names of the types it registers, sorted.
  const std::vector<std::string>& type_names() const { return type_names_; }

 private:
  PluginLibrary() = default;
  kernel::Status register_all(os::TaskTypeRegistry& scratch) const;

  std::string path_;
  os::PluginEntry entry_ = nullptr;
  std::vector<std::string> type_names_;
};

}  // namespace symb::io
