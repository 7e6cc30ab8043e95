#include "symb/io/plugin_library.hpp"

#include <dlfcn.h>

#include <filesystem>

namespace symb::io {

namespace {

std::string dl_error() {
  const char* e = dlerror();
  return e != nullptr ? e : "unknown error";
}

}  // namespace

kernel::Result<std::shared_ptr<const PluginLibrary>> PluginLibrary::open(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
  const std::string where = "plugin " + path;
  if (ec) return kernel::Error{where + ": " + ec.message()};
  void* handle = dlopen(absolute.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) return kernel::Error{where + ": cannot load: " + dl_error()};
  std::shared_ptr<PluginLibrary> lib(new PluginLibrary());
  lib->path_ = path;
  lib->entry_ = reinterpret_cast<os::PluginEntry>(dlsym(handle, os::kPluginEntryName));
  if (lib->entry_ == nullptr) {
    dlclose(handle);
    return kernel::Error{where + ": no entry point '" + std::string(os::kPluginEntryName) +
                         "' (a plugin defines it with SYMB_PLUGIN; docs/plugins.md)"};
  }
  kernel::Status probed;
  {
    // Gone before any dlclose: what a registration that failed halfway did add runs the plugin's
    // code when it is destroyed.
    os::TaskTypeRegistry scratch;
    probed = lib->register_all(scratch);
    if (probed)
      for (const os::TaskType* t : scratch.list()) lib->type_names_.push_back(t->name);
  }
  if (!probed) {
    dlclose(handle);
    return kernel::Error{probed.error()};
  }
  // Pinned for the rest of the process (see the header): a second open of the same file with
  // RTLD_NODELETE makes the first one's dlclose, and every later one, a no-op.
  if (dlopen(absolute.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE) == nullptr)
    return kernel::Error{where + ": cannot pin the loaded library: " + dl_error()};
  return std::shared_ptr<const PluginLibrary>(std::move(lib));
}

kernel::Status PluginLibrary::register_all(os::TaskTypeRegistry& scratch) const {
  const std::string where = "plugin " + path_;
  os::PluginHost host;
  host.registry = &scratch;
  int status = os::kPluginFailed;
  try {
    status = entry_(&host);
  } catch (...) {
    // The entry point is noexcept when made by SYMB_PLUGIN; a hand-written one may not be.
    return kernel::Error{where + ": the entry point threw"};
  }
  switch (status) {
    case os::kPluginOk: return {};
    case os::kPluginAbiMismatch:
      return kernel::Error{where + ": built for plugin ABI version " + std::to_string(host.plugin_abi_version) +
                           ", this Symbricator has version " + std::to_string(os::kPluginAbiVersion) +
                           " (rebuild it against this installation)"};
    default:
      return kernel::Error{
          where + ": registration failed: " + (host.error.empty() ? "status " + std::to_string(status) : host.error)};
  }
}

kernel::Status PluginLibrary::register_into(os::TaskTypeRegistry& registry) const {
  os::TaskTypeRegistry scratch;
  if (auto st = register_all(scratch); !st) return st;
  const auto types = scratch.list();
  for (const os::TaskType* t : types)
    if (registry.find(t->name) != nullptr)
      return kernel::Error{"plugin " + path_ + ": task type '" + t->name + "' is already registered"};
  for (const os::TaskType* t : types)
    if (auto st = registry.add(*t); !st) return kernel::Error{"plugin " + path_ + ": " + st.error()};
  return {};
}

}  // namespace symb::io
