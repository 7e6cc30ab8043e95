// Task-type plugins (os/plugin.hpp, io/plugin_library.hpp): a plugin's types work where built-in
// ones do (a node's registry, a scenario's `plugins:`, `symb run --plugin`, the shell's `load`),
// and every way a plugin can be wrong (not a library, no entry point, another ABI version, a
// registration that throws) is an error naming the file that leaves the registry, and a running
// node, as they were. The plugins are tests/apps/plugins/test_plugin.cpp built four ways.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/io/plugin_library.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/scenario_session.hpp"

namespace {

namespace fs = std::filesystem;
using symb::io::PluginLibrary;

#ifdef SYMB_TEST_PLUGIN_DIR
#define SKIP_WITHOUT_PLUGINS()
std::string plugin(const std::string& variant) {
  return std::string(SYMB_TEST_PLUGIN_DIR) + "/libtest_plugin_" + variant + ".so";
}
#else
#define SKIP_WITHOUT_PLUGINS() GTEST_SKIP() << "plugins need the shared libraries (SYMB_BUILD_SHARED)"
std::string plugin(const std::string&) { return {}; }
#endif

// A fresh folder under the test's temporary directory.
fs::path scratch_dir(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / ("symb_plugin_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The maze demo's world with one robot driven by `type`, naming `plugins` (YAML list text).
std::string drive_scenario(const std::string& type, const std::string& plugins) {
  return "name: plugin_drive\nseed: 1\nduration: 3s\ncontrol_period: 30ms\n" + plugins +
         "world:\n  arena: {width: 200, height: 150}\n  walls: [[50, 0, 50, 100]]\n"
         "robots:\n  - name: thymio\n    kind: thymio2\n    start: {x: 25, y: 25, heading: 90}\n"
         "    tasks:\n      - {name: controller, type: " +
         type + "}\n    hooks: [ir -> controller, controller -> wheels]\n";
}

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

TEST(PluginLibraryTest, RegistersItsTypesAndTheNodeCreatesThem) {
  SKIP_WITHOUT_PLUGINS();
  auto lib = PluginLibrary::open(plugin("good"));
  ASSERT_TRUE(lib) << lib.error();
  EXPECT_EQ((*lib)->type_names(), std::vector<std::string>{"test_drive"});
  symb::os::TaskTypeRegistry types;
  ASSERT_TRUE((*lib)->register_into(types));
  symb::kernel::VirtualTimeExecutor executor;
  symb::os::Node node(executor, symb::os::NodeConfig{"n", 1, 64, &types});
  auto id = node.create("test_drive", "drive", std::vector<symb::os::ParamAssignment>{{"speed", "120", 1}});
  ASSERT_TRUE(id) << id.error();
  EXPECT_EQ(node.parameters(*id)->real("speed"), 120.0);
  // A second registration into the same registry names the clash and adds nothing.
  const auto before = types.list().size();
  auto again = (*lib)->register_into(types);
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().find("'test_drive' is already registered"), std::string::npos) << again.error();
  EXPECT_EQ(types.list().size(), before);
}

TEST(PluginLibraryTest, RefusesEveryBadPluginNamingTheFile) {
  SKIP_WITHOUT_PLUGINS();
  const fs::path dir = scratch_dir("bad");
  const std::string not_a_library = write(dir / "notes.so", "not an ELF file\n").string();
  const struct {
    std::string path;
    std::string says;
  } cases[] = {
      {not_a_library, "cannot load"},
      {(dir / "missing.so").string(), "cannot load"},
      {plugin("no_entry"), "no entry point 'symb_plugin_entry'"},
      {plugin("bad_abi"),
       "built for plugin ABI version 999, this Symbricator has version " + std::to_string(symb::os::kPluginAbiVersion)},
      {plugin("throws"), "registration threw: test plugin: no types today"},
  };
  for (const auto& c : cases) {
    auto lib = PluginLibrary::open(c.path);
    ASSERT_FALSE(lib) << c.path;
    EXPECT_NE(lib.error().find("plugin " + c.path + ": "), std::string::npos) << lib.error();
    EXPECT_NE(lib.error().find(c.says), std::string::npos) << lib.error();
  }
}

TEST(PluginLibraryTest, AScenarioNamesItsPluginsRelativeToItsFile) {
  SKIP_WITHOUT_PLUGINS();
  const fs::path dir = scratch_dir("scenario");
  fs::copy_file(plugin("good"), dir / "drive.so");
  symb::apps::run::RunOptions o;
  o.scenario_path = write(dir / "s.yaml", drive_scenario("test_drive", "plugins: [drive.so]\n")).string();
  auto r = symb::apps::run::run_scenario(o);
  ASSERT_TRUE(r) << r.error();
  ASSERT_EQ(r->robots.size(), 1u);
  // 300 motor units for 3 s is about 30 cm (Thymio: 500 units = 20 cm/s), less the start.
  EXPECT_GT(r->robots[0].distance, 20.0);
  EXPECT_LT(r->robots[0].distance, 40.0);

  // A bad one is an error at its line in the scenario file, and nothing runs.
  o.scenario_path =
      write(dir / "bad.yaml", drive_scenario("test_drive", "plugins:\n  - " + plugin("bad_abi") + "\n")).string();
  auto bad = symb::apps::run::run_scenario(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find(o.scenario_path + ":6:5: plugin "), std::string::npos) << bad.error();
  EXPECT_NE(bad.error().find("ABI version 999"), std::string::npos) << bad.error();
}

TEST(PluginLibraryTest, RunPluginOptionGivesTheSameRunAsTheScenarioList) {
  SKIP_WITHOUT_PLUGINS();
  const fs::path dir = scratch_dir("option");
  fs::copy_file(plugin("good"), dir / "drive.so");
  symb::apps::run::RunOptions listed;
  listed.scenario_path = write(dir / "a.yaml", drive_scenario("test_drive", "plugins: [drive.so]\n")).string();
  symb::apps::run::RunOptions given;
  given.scenario_path = write(dir / "b.yaml", drive_scenario("test_drive", "")).string();
  given.plugins = {plugin("good")};
  auto a = symb::apps::run::run_scenario(listed);
  auto b = symb::apps::run::run_scenario(given);
  ASSERT_TRUE(a) << a.error();
  ASSERT_TRUE(b) << b.error();
  EXPECT_EQ(a->trajectory_hash, b->trajectory_hash);
  // Without the plugin the type is unknown: the scenario check says so.
  given.plugins.clear();
  auto none = symb::apps::run::run_scenario(given);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().find("test_drive"), std::string::npos) << none.error();
}

TEST(PluginLibraryTest, EveryRobotCreatesThePluginsTypesAtRuntime) {
  SKIP_WITHOUT_PLUGINS();
  // What a genome's development, an evolution task's controller swap and the shell do: create a
  // task by type name on a running robot's node, whose registry is over the session's shared types.
  const fs::path dir = scratch_dir("runtime");
  auto loaded = symb::sim::load_scenario(
      write(dir / "s.yaml", drive_scenario("test_drive", "plugins: [" + plugin("good") + "]\n")).string());
  ASSERT_TRUE(loaded) << loaded.error();
  symb::sim::Scenario scenario = std::move(loaded).value();
  scenario.robots.push_back(scenario.robots[0]);
  scenario.robots[1].name = "second";
  scenario.robots[1].start.y = 120;
  symb::kernel::VirtualTimeExecutor executor;
  auto session = symb::sim::ScenarioSession::create(scenario, executor);
  ASSERT_TRUE(session) << session.error();
  (*session)->start();
  executor.run_for(std::chrono::milliseconds(300));
  for (std::size_t i = 0; i < (*session)->robot_count(); ++i) {
    symb::os::Node& node = (*session)->robot(i).node();
    auto id = node.create("test_drive", "spare", std::vector<symb::os::ParamAssignment>{{"speed", "-100", 1}});
    ASSERT_TRUE(id) << id.error();
    EXPECT_EQ(node.info(*id)->type, "test_drive");
  }
  executor.run_for(std::chrono::milliseconds(300));
  (*session)->stop();
}

TEST(PluginLibraryTest, ShellLoadLeavesTheRunningNodeAloneWhenAPluginIsBad) {
  SKIP_WITHOUT_PLUGINS();
  symb::os::TaskTypeRegistry types;
  symb::kernel::VirtualTimeExecutor executor;
  symb::os::Node node(executor, symb::os::NodeConfig{"n", 1, 64, &types});
  symb::shell::Shell::Options so;
  so.load_plugin = [&types](const std::string& path) -> symb::kernel::Status {
    auto lib = PluginLibrary::open(path);
    if (!lib) return symb::kernel::Error{lib.error()};
    return (*lib)->register_into(types);
  };
  symb::shell::Shell shell(node, so);
  ASSERT_TRUE(shell.execute("load " + plugin("good")).ok);
  ASSERT_TRUE(shell.execute("create test_drive d1").ok);
  executor.run_for(std::chrono::milliseconds(100));
  const std::string not_a_library = write(scratch_dir("shell") / "notes.so", "not an ELF file\n").string();
  for (const std::string& bad : {plugin("bad_abi"), plugin("throws"), plugin("no_entry"), not_a_library}) {
    const auto reply = shell.execute("load " + bad);
    EXPECT_FALSE(reply.ok) << bad;
    EXPECT_NE(reply.text.find("error: column 6: plugin " + bad + ": "), std::string::npos) << reply.text;
  }
  executor.run_for(std::chrono::milliseconds(100));
  ASSERT_EQ(node.tasks().size(), 1u);
  EXPECT_EQ(node.tasks()[0].state, symb::os::TaskState::kRunning);
  EXPECT_EQ(types.list().size(), 1u);
  EXPECT_TRUE(shell.execute("create test_drive d2").ok);
  // A shell nobody gave a loader says so.
  symb::shell::Shell plain(node);
  EXPECT_NE(plain.execute("load x.so").text.find("this shell cannot load plugins"), std::string::npos);
}

}  // namespace
