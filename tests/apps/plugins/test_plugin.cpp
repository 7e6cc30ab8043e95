// The plugins apps_tests loads (plugin_test.cpp), one file built four ways (tests/apps/CMakeLists.txt):
//   TEST_PLUGIN_GOOD      registers `test_drive`: on every IR reading, [speed, speed] to the wheels
//   TEST_PLUGIN_BAD_ABI   an entry point as SYMB_PLUGIN makes it, for ABI version 999
//   TEST_PLUGIN_THROWS    registers a type, then throws
//   TEST_PLUGIN_NO_ENTRY  a shared library without the entry point
#include <memory>
#include <stdexcept>

#include "symb/os/plugin.hpp"
#include "symb/os/task.hpp"

namespace test_plugin {

using namespace symb;

struct DriveOptions {
  double speed = 300;
};

class Drive : public os::Task {
 public:
  explicit Drive(const DriveOptions& o) : options_(o) { bind_parameters(options_); }

 protected:
  void on_message(const os::Message& m) override {
    if (m.numbers().size() >= 7) send(0, {static_cast<float>(options_.speed), static_cast<float>(options_.speed)});
  }

 private:
  DriveOptions options_;
};

os::TaskType drive_type() {
  os::ParamTable<DriveOptions> p;
  p.add("speed", &DriveOptions::speed).range(-500.0, 500.0).doc("both wheels (motor units)").live();
  return os::declare_task_type("test_drive", "drives straight on every IR reading", std::move(p),
                               [](const DriveOptions& o) { return std::make_unique<Drive>(o); });
}

[[maybe_unused]] kernel::Status register_types(os::TaskTypeRegistry& registry) {
#if defined(TEST_PLUGIN_THROWS)
  if (auto st = registry.add(drive_type()); !st) return st;
  throw std::runtime_error("test plugin: no types today");
#else
  return registry.add(drive_type());
#endif
}

}  // namespace test_plugin

#if defined(TEST_PLUGIN_BAD_ABI)
extern "C" __attribute__((visibility("default"))) int symb_plugin_entry(symb::os::PluginHost* host) {
  host->plugin_abi_version = 999;
  return host->abi_version == 999 ? symb::os::kPluginOk : symb::os::kPluginAbiMismatch;
}
#elif !defined(TEST_PLUGIN_NO_ENTRY)
SYMB_PLUGIN(test_plugin::register_types)
#endif
