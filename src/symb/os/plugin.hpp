// Plugins: a shared library of the user's own that adds task types (controllers, fitness tasks,
// anything a Task can be) to a TaskTypeRegistry the host hands it. Nothing global: the plugin
// registers into the registry it is given, as often as the host asks (the session's shared types,
// a robot's own registry, the registry a scenario is checked against), and keeps no state of its
// own between calls.
//
// A plugin is one C++ file built against the installed package (docs/plugins.md):
//
//   #include "symb/os/plugin.hpp"
//   kernel::Status register_types(os::TaskTypeRegistry& registry) {
//     return registry.add(os::declare_task_type("my_controller", "...", std::move(table), make));
//   }
//   SYMB_PLUGIN(register_types)
//
// SYMB_PLUGIN defines the one exported C entry point, `symb_plugin_entry`. The host (the loader in
// io/plugin_library.hpp) calls it with a PluginHost whose first two fields never move: the host's
// ABI version, and where the plugin writes its own. The entry point compares them before it
// touches anything else, so a plugin built against another version is refused without running a
// line of its registration; the rest of PluginHost and everything the registration uses (C++
// classes, std::string, the registry) are only valid between a host and a plugin of one ABI.
// kPluginAbiVersion changes whenever a public class a plugin uses changes its layout or virtual
// functions (Task, TaskType, TaskTypeRegistry, Message, ParamTable...).
//
// What may go wrong, and what the host makes of it (each an error naming the file): the library
// does not load (dlopen's message), has no entry point, was built for another ABI version (both
// numbers), or its registration returns an error or throws (the message). Registration goes to a
// scratch registry first and reaches the real one only when all of it succeeded, so a failed
// plugin leaves no half of its types behind.
#pragma once

#include <cstdint>
#include <exception>
#include <string>

#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::os {

inline constexpr std::uint32_t kPluginAbiVersion = 1;

// The entry point's exported name.
inline constexpr const char* kPluginEntryName = "symb_plugin_entry";

// What the entry point returns.
enum PluginStatus : int { kPluginOk = 0, kPluginAbiMismatch = 1, kPluginFailed = 2 };

// What the host passes to the entry point. The first two fields keep their place in every version.
struct PluginHost {
  std::uint32_t abi_version = kPluginAbiVersion;  // the host's
  std::uint32_t plugin_abi_version = 0;           // written by the plugin
  // Only for a plugin of the host's ABI version:
  TaskTypeRegistry* registry = nullptr;  // where the types go
  std::string error;                     // why the registration failed (kPluginFailed)
};

using PluginEntry = int (*)(PluginHost*);

namespace detail {

// The body of every plugin's entry point, compiled into the plugin (so kPluginAbiVersion is the
// plugin's): checks the version, then registers, turning an error or an exception into text.
template <class Register>
int plugin_entry(PluginHost* host, Register register_types) noexcept {
  if (host == nullptr) return kPluginFailed;
  host->plugin_abi_version = kPluginAbiVersion;
  if (host->abi_version != kPluginAbiVersion) return kPluginAbiMismatch;
  try {
    if (host->registry == nullptr) {
      host->error = "no registry given";
      return kPluginFailed;
    }
    kernel::Status st = register_types(*host->registry);
    if (!st) {
      host->error = st.error();
      return kPluginFailed;
    }
    return kPluginOk;
  } catch (const std::exception& e) {
    host->error = std::string("registration threw: ") + e.what();
  } catch (...) {
    host->error = "registration threw an exception that is not a std::exception";
  }
  return kPluginFailed;
}

}  // namespace detail
}  // namespace symb::os

// Defines the plugin's entry point over `register_fn`, a function (or function object) taking an
// os::TaskTypeRegistry& and returning a kernel::Status. Use it once, at namespace scope.
#define SYMB_PLUGIN(register_fn)                                                                          \
  extern "C" __attribute__((visibility("default"))) int symb_plugin_entry(::symb::os::PluginHost* host) { \
    return ::symb::os::detail::plugin_entry(host, register_fn);                                           \
  }
