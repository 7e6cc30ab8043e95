// Every shell command against a node under virtual time: its effect on the node (read through the
// node's own API, not only the text), its table and its --json output read back.
#include "symb/shell/shell.hpp"

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/shell_task.hpp"

#include "shell_test_support.hpp"

namespace symb::shell {
namespace {

using namespace std::chrono_literals;
using testing::Json;
using testing::JsonParser;
using testing::split_table;

class ShellTest : public ::testing::Test {
 protected:
  ShellTest() {
    testing::add_test_types(types_);
    EXPECT_TRUE(register_shell_types(types_));
    node_ = std::make_unique<os::Node>(ex_, os::NodeConfig{"board", 7, 256, &types_});
    device_ = std::make_shared<testing::TestDevice>("uart1");
    auto devices = std::make_shared<DeviceTable>();
    (*devices)["uart1"] = device_;
    Shell::Options o;
    o.devices = devices;
    o.max_script_lines = 1000;
    o.read_file = [this](const std::string& path) -> kernel::Result<std::string> {
      auto it = scripts_.find(path);
      if (it == scripts_.end()) return kernel::Error{"no such file"};
      return it->second;
    };
    shell_.emplace(*node_, o);
  }

  Reply run(std::string_view line) { return shell_->execute(line); }
  std::string ok(std::string_view line) {
    Reply r = run(line);
    EXPECT_TRUE(r.ok) << line << " -> " << r.text;
    EXPECT_TRUE(r.text.ends_with('\n')) << line;
    return r.text;
  }
  std::string error(std::string_view line) {
    Reply r = run(line);
    EXPECT_FALSE(r.ok) << line << " -> " << r.text;
    EXPECT_TRUE(r.text.starts_with("error: ")) << r.text;
    EXPECT_TRUE(r.text.ends_with('\n')) << r.text;
    return r.text;
  }
  Json json(std::string_view line) {
    const std::string text = ok(line);
    auto j = JsonParser::parse(text);
    EXPECT_TRUE(j) << "not JSON: " << text;
    return j.value_or(Json{});
  }
  os::TaskInfo info(std::string_view name) {
    auto id = node_->find(name);
    EXPECT_TRUE(id) << name;
    return node_->info(*id).value();
  }
  const Json* task_json(const Json& tasks, std::string_view name) {
    for (const auto& t : tasks.array())
      if (t["name"].string() == name) return &t;
    return nullptr;
  }

  kernel::VirtualTimeExecutor ex_;
  os::TaskTypeRegistry types_;
  std::unique_ptr<os::Node> node_;
  std::shared_ptr<testing::TestDevice> device_;
  std::map<std::string, std::string> scripts_;
  std::optional<Shell> shell_;
};

TEST_F(ShellTest, HelpListsAndDescribesEveryCommand) {
  const auto rows = split_table(ok("help"));
  ASSERT_GE(rows.size(), Shell::commands().size() + 1);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"COMMAND", "SUMMARY"}));
  for (const auto& c : Shell::commands()) {
    const std::string text = ok("help " + std::string(c.name));
    EXPECT_TRUE(text.starts_with("usage: " + std::string(c.usage))) << text;
  }
  const Json all = json("help --json");
  EXPECT_EQ(all.array().size(), Shell::commands().size());
  EXPECT_EQ(json("help hook --json")["name"].string(), "hook");
  EXPECT_EQ(error("help hokk"), "error: column 6: no command 'hokk' (did you mean 'hook'?)\n");
  EXPECT_EQ(error("tsks"),
            "error: column 1: unknown command 'tsks' (did you mean 'tasks'?); 'help' lists the commands\n");
  EXPECT_EQ(run("").text, "");
  EXPECT_TRUE(run("   # nothing").ok);
}

TEST_F(ShellTest, CreateAndTasks) {
  ok("create emitter e1 value=2.5 label=\"two words\" --period 20ms --priority 3 --queue 8");
  ok("create sink s1 --suspended");
  const auto e1 = info("e1");
  EXPECT_EQ(e1.type, "emitter");
  EXPECT_EQ(e1.state, os::TaskState::kRunning);
  EXPECT_EQ(e1.priority, 3);
  EXPECT_EQ(e1.period, 20ms);
  EXPECT_EQ(e1.queue_capacity, 8u);
  EXPECT_EQ(info("s1").state, os::TaskState::kCreated);
  auto params = node_->parameters(*node_->find("e1"));
  EXPECT_EQ(params->real("value"), 2.5);
  EXPECT_EQ(params->string("label"), "two words");

  const auto rows = split_table(ok("tasks"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0],
            (std::vector<std::string>{"NAME", "STATE", "PRIO", "PERIOD", "QUEUE", "IN", "OUT", "DROPPED", "TYPE"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"e1", "running", "3", "20ms", "0/8", "0", "0", "0", "emitter"}));
  EXPECT_EQ(rows[2], (std::vector<std::string>{"s1", "created", "0", "-", "0/64", "0", "0", "0", "sink"}));

  const Json tasks = json("tasks --json");
  ASSERT_EQ(tasks.array().size(), 2u);
  const Json& j = *task_json(tasks, "e1");
  EXPECT_EQ(j["state"].string(), "running");
  EXPECT_EQ(j["priority"].number(), 3);
  EXPECT_EQ(j["period_ns"].number(), 20e6);
  EXPECT_EQ(j["queue_capacity"].number(), 8);
  EXPECT_EQ(j["type"].string(), "emitter");

  // Errors point at the argument, and leave nothing behind.
  EXPECT_EQ(error("create emiter e2"), "error: column 8: unknown task type 'emiter' (did you mean 'emitter'?)\n");
  EXPECT_EQ(error("create emitter e2 valeu=3"),
            "error: column 19: task type 'emitter' has no parameter 'valeu' (did you mean 'value'?)\n");
  EXPECT_EQ(error("create emitter e2 loud=true value=abc"),
            "error: column 29: parameter 'value': expected a finite real number, got 'abc'\n");
  EXPECT_EQ(error("create emitter e2 value=2e6"),
            "error: column 19: parameter 'value': value 2e+06 is outside [-1e+06, 1e+06]\n");
  EXPECT_EQ(error("create emitter e1"), "error: column 16: node 'board' already has a task named 'e1'\n");
  EXPECT_TRUE(error("create emitter 2bad").starts_with("error: column 16: invalid task name '2bad'"));
  EXPECT_EQ(error("create emitter e2 value"), "error: column 19: expected PARAM=VALUE, got 'value'\n");
  EXPECT_EQ(error("create emitter e2 --period 10"),
            "error: column 28: option '--period': '10' has no unit: write e.g. 30ms, 1.5s, 250us, 2min\n");
  EXPECT_EQ(error("create emitter e2 --period 10us"),
            "error: column 28: option '--period': at least 1ms (or 0 for no ticks)\n");
  EXPECT_EQ(error("create emitter e2 --queue 0"),
            "error: column 27: option '--queue': value 0 is outside [1, 65536]\n");
  EXPECT_EQ(error("create emitter"),
            "error: column 8: 'create' needs more arguments (usage: create TYPE NAME "
            "[PARAM=VALUE ...] [--priority N] [--period DURATION] [--queue N] "
            "[--suspended])\n");
  EXPECT_EQ(node_->task_count(), 2u);
}

// A constructor that throws, or an absurd size, is an error reply; the shell and the node go on.
TEST_F(ShellTest, CreateOfATypeWhoseConstructorFailsIsAnError) {
  testing::add_fragile_type(types_);
  EXPECT_NE(error("create fragile a kind=0").find("task type 'fragile' could not make a task: fragile by request"),
            std::string::npos);
  EXPECT_NE(error("create fragile b kind=1").find("task type 'fragile'"), std::string::npos);
  // More than a vector can hold: std::length_error. Under the sanitizers an allocation that the
  // system refuses aborts the process (their allocators report it instead of throwing
  // std::bad_alloc), so the bad_alloc case runs in the release build only.
  EXPECT_NE(error("create fragile c size=9000000000000000000").find("task type 'fragile'"), std::string::npos);
#ifndef SYMB_SANITIZER
  EXPECT_NE(error("create fragile c size=100000000000000000").find("task type 'fragile'"), std::string::npos);
#endif
  EXPECT_FALSE(node_->find("a") || node_->find("b") || node_->find("c"));
  ok("create fragile d size=16");
  ok("create emitter e value=2");
  ex_.run_for(50ms);
  EXPECT_TRUE(node_->find("e"));
}

TEST_F(ShellTest, SuspendResumeDelete) {
  ok("create emitter e1");
  ok("create sink s1 --suspended");
  EXPECT_EQ(ok("suspend e1"), "suspended 'e1'\n");
  EXPECT_EQ(info("e1").state, os::TaskState::kSuspended);
  EXPECT_TRUE(error("suspend e1").starts_with("error: column 9: task 'e1' is suspended, not running"));
  EXPECT_EQ(ok("resume e1"), "resumed 'e1'\n");
  EXPECT_EQ(info("e1").state, os::TaskState::kRunning);
  EXPECT_EQ(ok("resume s1"), "started 's1'\n");
  EXPECT_EQ(info("s1").state, os::TaskState::kRunning);
  EXPECT_EQ(error("resume e2"), "error: column 8: node 'board' has no task 'e2' (did you mean 'e1'?)\n");
  EXPECT_EQ(ok("delete e1"), "deleted 'e1'\n");
  EXPECT_FALSE(node_->find("e1"));
  EXPECT_EQ(error("delete e1"), "error: column 8: node 'board' has no task 'e1' (did you mean 's1'?)\n");
  EXPECT_EQ(error("delete s1 now"), "error: column 11: unexpected argument 'now' (usage: delete NAME)\n");
}

TEST_F(ShellTest, ProtectedTasksAreNotSuspendedOrDeleted) {
  ok("create sink s1");
  shell_->protect(*node_->find("s1"));
  EXPECT_TRUE(error("suspend s1").find("carries this shell session") != std::string::npos);
  EXPECT_TRUE(error("delete s1").find("use 'exit'") != std::string::npos);
  EXPECT_EQ(info("s1").state, os::TaskState::kRunning);
}

TEST_F(ShellTest, PriorityAndPeriod) {
  ok("create emitter e1");
  ok("priority e1 -7");
  EXPECT_EQ(info("e1").priority, -7);
  ok("period e1 250ms");
  EXPECT_EQ(info("e1").period, 250ms);
  ok("period e1 0");
  EXPECT_EQ(info("e1").period, 0ms);
  EXPECT_EQ(error("priority e1 high"), "error: column 13: priority: expected an integer, got 'high'\n");
  EXPECT_EQ(error("priority e1 5000"), "error: column 13: priority: value 5000 is outside [-1000, 1000]\n");
  EXPECT_EQ(error("period e1 1ns"), "error: column 11: period: at least 1ms (or 0)\n");
  EXPECT_EQ(info("e1").priority, -7);
}

TEST_F(ShellTest, SetAndParams) {
  ok("create emitter e1 value=1");
  ok("set e1 value 4.5");
  ex_.run_for(1ms);  // the task applies it on its own context
  EXPECT_EQ(node_->parameters(*node_->find("e1"))->real("value"), 4.5);
  const auto rows = split_table(ok("params e1"));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"PARAM", "KIND", "VALUE", "DEFAULT", "RANGE", "DOC"}));
  EXPECT_EQ((std::vector<std::string>(rows[1].begin(), rows[1].begin() + 5)),
            (std::vector<std::string>{"value", "real", "4.5", "1", "-1000000..1000000"}));
  const Json p = json("params e1 --json");
  EXPECT_EQ(p[0]["name"].string(), "value");
  EXPECT_EQ(p[0]["value"].string(), "4.5");
  EXPECT_EQ(p[1]["value"].string(), "none");
  EXPECT_EQ(p[0]["min"].number(), -1e6);
  EXPECT_EQ(error("set e1 vlue 3"),
            "error: column 8: task type 'emitter' has no parameter 'vlue' (did you mean 'value'?)\n");
  EXPECT_EQ(error("set e1 value x"), "error: column 14: parameter 'value': expected a finite real number, got 'x'\n");
  EXPECT_EQ(error("set e9 value 1"), "error: column 5: node 'board' has no task 'e9' (did you mean 'e1'?)\n");
}

// The same rule as a scenario file's (scenario_parser_test: "is given twice"): one hook per
// sender, receiver and port, whatever its priority or policy.
TEST_F(ShellTest, TheSameHookTwiceIsRefused) {
  ok("create emitter src --period 10ms");
  ok("create sink dst");
  EXPECT_EQ(ok("hook src dst"), "hook 1: src -> dst\n");
  EXPECT_EQ(error("hook src dst --priority 3 --policy refuse"),
            "error: column 6: task 'src' is already hooked to 'dst' (hook 1)\n");
  EXPECT_EQ(ok("hook src dst --port 2"), "hook 2: src -> dst\n");  // another port: another hook
  EXPECT_EQ(error("hook src dst --port 2"),
            "error: column 6: task 'src' is already hooked to 'dst' on port 2 (hook 2)\n");
  EXPECT_EQ(node_->hooks().size(), 2u);
  ok("unhook 1");
  EXPECT_EQ(ok("hook src dst"), "hook 3: src -> dst\n");
}

TEST_F(ShellTest, HooksCarryMessagesAndCanBeChanged) {
  ok("create emitter src --period 10ms");
  ok("create sink dst");
  EXPECT_EQ(ok("hook src dst"), "hook 1: src -> dst\n");
  ex_.run_for(100ms);
  const auto in = info("dst").traffic.delivered;
  EXPECT_GE(in, 9u);
  EXPECT_EQ((*task_json(json("tasks --json"), "dst"))["in"].number(), static_cast<double>(in));

  auto rows = split_table(ok("hooks"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"HOOK", "SENDER", "RECEIVER", "PRIO", "POLICY", "PORT", "SUPPRESS",
                                               "STATE", "INHIBITED"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"1", "src", "dst", "0", "keep-newest", "any", "-", "enabled", "-"}));

  ok("disable 1");
  EXPECT_FALSE(node_->hooks()[0].options.enabled);
  ex_.run_for(100ms);
  EXPECT_EQ(info("dst").traffic.delivered, in);
  ok("enable 1");
  ex_.run_for(100ms);
  EXPECT_GT(info("dst").traffic.delivered, in);

  EXPECT_EQ(ok("hook src dst --priority 2 --policy refuse --port 3 --suppress 5ms --disabled"), "hook 2: src -> dst\n");
  const auto hooks = node_->hooks();
  ASSERT_EQ(hooks.size(), 2u);
  const os::HookInfo& h = hooks[0].id.serial == 2 ? hooks[0] : hooks[1];
  EXPECT_EQ(h.options.priority, 2);
  EXPECT_EQ(h.options.policy, os::QueuePolicy::kRefuse);
  EXPECT_EQ(h.options.port, 3);
  EXPECT_EQ(h.options.suppress_window, 5ms);
  EXPECT_FALSE(h.options.enabled);
  const Json j = json("hooks --json");
  ASSERT_EQ(j.array().size(), 2u);
  for (const auto& x : j.array()) {
    if (x["hook"].number() != 2) continue;
    EXPECT_EQ(x["policy"].string(), "refuse");
    EXPECT_EQ(x["port"].number(), 3);
    EXPECT_EQ(x["suppress_ns"].number(), 5e6);
    EXPECT_FALSE(x["enabled"].boolean());
  }

  EXPECT_EQ(error("unhook 7"), "error: column 8: no hook 7 ('hooks' lists them)\n");
  EXPECT_EQ(error("unhook x7"),
            "error: column 8: expected a hook number ('hooks' lists them) or SENDER RECEIVER, got 'x7'\n");
  EXPECT_EQ(error("unhook dst src"), "error: column 8: no hook from 'dst' to 'src'\n");
  EXPECT_EQ(ok("unhook 1"), "removed hook 1\n");
  EXPECT_EQ(node_->hooks().size(), 1u);
  ok("hook src dst");
  EXPECT_EQ(ok("unhook src dst"), "removed 2 hooks from 'src' to 'dst'\n");
  EXPECT_TRUE(node_->hooks().empty());
  EXPECT_EQ(error("hook src dst --policy newest"),
            "error: column 23: option '--policy': expected one of keep-newest, refuse, got 'newest'\n");
  EXPECT_EQ(error("hook src dst --port 70000"),
            "error: column 21: option '--port': value 70000 is outside [0, 65535]\n");
  EXPECT_TRUE(node_->hooks().empty());
}

TEST_F(ShellTest, SuppressAndInhibit) {
  ok("create emitter src --period 10ms");
  ok("create sink dst");
  ok("hook src dst");
  ex_.run_for(5ms);
  EXPECT_EQ(error("inhibit dst src 10ms"), "error: column 13: task 'dst' has no hook to 'src'\n");
  ok("inhibit src dst 50ms");
  EXPECT_EQ(node_->hooks()[0].inhibited_until, node_->now() + 50ms);
  EXPECT_TRUE(json("hooks --json")[0]["inhibited"].boolean());
  ex_.run_for(45ms);
  EXPECT_GE(info("dst").traffic.inhibited, 4u);
  ok("inhibit src * 0");
  ok("suppress dst 5 30ms");
  const auto before = info("dst").traffic.suppressed;
  ex_.run_for(30ms);
  EXPECT_GE(info("dst").traffic.suppressed, before + 2);
  EXPECT_EQ(error("suppress dst high 1s"), "error: column 14: level: expected an integer, got 'high'\n");
  EXPECT_EQ(error("inhibit src dst forever"),
            "error: column 17: duration: 'forever' has no unit: write e.g. 30ms, 1.5s, 250us, 2min\n");
}

TEST_F(ShellTest, PostPutsNumbersInAQueue) {
  ok("create sink dst --suspended");
  EXPECT_EQ(ok("post dst 1 -2.5 3e2 --port 4"), "posted 3 values to 'dst'\n");
  EXPECT_EQ(info("dst").queue_depth, 1u);
  EXPECT_EQ(error("post dst 1 x"), "error: column 12: value: expected a finite real number, got 'x'\n");
  EXPECT_EQ(error("post dst 1e39"), "error: column 10: value: too large for a message (float)\n");
  std::string many = "post dst";
  for (int i = 0; i < 33; ++i) many += " 1";
  EXPECT_TRUE(error(many).starts_with("error: column 74: unexpected argument '1'"));
  EXPECT_EQ(info("dst").queue_depth, 1u);
  ok("resume dst");
  ex_.run_for(1ms);
  EXPECT_EQ(info("dst").traffic.delivered, 1u);
}

TEST_F(ShellTest, LogShowsFiltersAndFollows) {
  node_->log().info("a", "first");
  node_->log().warn("b", "second \"quoted\"");
  node_->log().error("c", "third");
  auto rows = split_table(ok("log"));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"SEQ", "TIME", "LEVEL", "SOURCE", "TEXT"}));
  EXPECT_EQ(rows[3][3], "c");
  EXPECT_EQ(split_table(ok("log 1")).size(), 2u);
  rows = split_table(ok("log --level warn"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1][2], "WARN");
  const Json j = json("log --json");
  ASSERT_EQ(j.array().size(), 3u);
  EXPECT_EQ(j[1]["text"].string(), "second \"quoted\"");
  EXPECT_EQ(error("log --level loud"),
            "error: column 13: option '--level': expected one of debug, info, warn, error, got 'loud'\n");
  EXPECT_EQ(error("log 0"), "error: column 5: count: value 0 is outside [1, 100000]\n");
  EXPECT_EQ(error("log follow --json"), "error: column 5: 'log follow' prints no JSON\n");

  EXPECT_FALSE(shell_->following());
  ok("log follow --level warn");
  EXPECT_TRUE(shell_->following());
  EXPECT_EQ(shell_->follow_output(), "");
  node_->log().info("x", "not shown");
  node_->log().warn("y", "shown");
  const std::string out = shell_->follow_output();
  EXPECT_EQ(out.find("not shown"), std::string::npos);
  EXPECT_NE(out.find("WARN  y: shown"), std::string::npos) << out;
  EXPECT_EQ(shell_->follow_output(), "");
  EXPECT_EQ(ok("log stop"), "stopped following the log\n");
  EXPECT_FALSE(shell_->following());
}

TEST_F(ShellTest, DevicesAndIoctls) {
  auto rows = split_table(ok("devices"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1], (std::vector<std::string>{"uart1", "yes", "3"}));
  EXPECT_EQ(json("devices --json")[0]["ioctls"].number(), 3);
  rows = split_table(ok("ioctls uart1"));
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ((std::vector<std::string>(rows[1].begin(), rows[1].begin() + 3)),
            (std::vector<std::string>{"baud", "int", "300..1000000"}));
  EXPECT_TRUE(json("ioctls uart1 --json")[1]["arg"].is_null());
  EXPECT_EQ(ok("ioctl uart1 baud 57600"), "baud 57600\n");
  EXPECT_EQ(device_->baud(), 57600);
  EXPECT_EQ(ok("ioctl uart1 info"), "baud=57600\n");
  EXPECT_EQ(ok("ioctl uart1 flush"), "ok\n");
  EXPECT_EQ(error("ioctl uart2 info"), "error: column 7: no device 'uart2' (did you mean 'uart1'?)\n");
  EXPECT_EQ(error("ioctl uart1 baudd 9600"),
            "error: column 13: device 'uart1' has no ioctl 'baudd' (did you mean 'baud'?)\n");
  EXPECT_EQ(error("ioctl uart1 baud fast"),
            "error: column 18: ioctl 'baud' of device 'uart1': parameter 'baud': expected an integer, got 'fast'\n");
  EXPECT_EQ(error("ioctl uart1 baud 10"),
            "error: column 18: ioctl 'baud' of device 'uart1': parameter 'baud': value 10 is outside [300, 1e+06]\n");
  EXPECT_EQ(device_->baud(), 57600);
}

TEST_F(ShellTest, RunScripts) {
  scripts_["setup.symb"] = "# two tasks and a hook\ncreate emitter src\r\ncreate sink dst\n\nhook src dst\n";
  const std::string out = ok("run setup.symb");
  EXPECT_NE(out.find("ran 5 lines of 'setup.symb'"), std::string::npos) << out;
  EXPECT_TRUE(node_->find("src") && node_->find("dst"));
  EXPECT_EQ(node_->hooks().size(), 1u);

  scripts_["bad.symb"] = "create sink a1\ncreate sink a1\ncreate sink a2\n";
  const std::string bad = error("run bad.symb");
  EXPECT_EQ(bad, "error: bad.symb:2: column 13: node 'board' already has a task named 'a1'\n");
  EXPECT_FALSE(node_->find("a2"));  // stopped at the first error

  scripts_["outer.symb"] = "run inner.symb\n";
  scripts_["inner.symb"] = "sleep 5\n";
  EXPECT_NE(error("run outer.symb").find("error: outer.symb:1: inner.symb:1: column 1: not a shell command"),
            std::string::npos);

  scripts_["loop.symb"] = "run loop.symb\n";
  EXPECT_NE(error("run loop.symb").find("scripts nest more than 8 deep"), std::string::npos);

  // Five files deep, each running the next five times: 5^5 lines without a budget.
  for (int i = 0; i < 5; ++i) {
    std::string text;
    for (int k = 0; k < 5; ++k) text += i < 4 ? "run l" + std::to_string(i + 1) + "\n" : std::string("time\n");
    scripts_["l" + std::to_string(i)] = text;
  }
  EXPECT_NE(error("run l0").find("scripts ran more than 1000 lines: stopped"), std::string::npos);

  scripts_["early.symb"] = "create sink b1\nexit\ncreate sink b2\n";
  ok("run early.symb");
  EXPECT_TRUE(node_->find("b1"));
  EXPECT_FALSE(node_->find("b2"));
  EXPECT_FALSE(shell_->exit_requested());  // exit in a script ends the script only

  EXPECT_EQ(error("run nowhere.symb"), "error: column 5: cannot read 'nowhere.symb': no such file\n");
}

// `run` reads any file the process may read; what is not a script is described, never quoted.
TEST_F(ShellTest, RunNeverQuotesAFileItCannotRun) {
  const std::string secret = "root:$6$s3cr3tSalt$hashhashhash:19000:0:99999:7:::";
  scripts_["shadow"] = secret + "\ndaemon:*:19000:0:99999:7:::\n";
  const std::string shadow = error("run shadow");
  EXPECT_EQ(shadow.find("root"), std::string::npos) << shadow;
  EXPECT_EQ(shadow.find("s3cr3t"), std::string::npos) << shadow;
  EXPECT_NE(shadow.find("error: shadow:1: column 1: not a shell command"), std::string::npos) << shadow;

  std::string binary =
      "\x7f"
      "ELF\x02\x01\x01";
  binary += std::string(3, '\0') + "MAGICBYTES\n";
  scripts_["a.out"] = binary;
  const std::string bin = error("run a.out");
  EXPECT_EQ(bin.find("ELF"), std::string::npos) << bin;
  EXPECT_EQ(bin.find("MAGIC"), std::string::npos) << bin;
  EXPECT_NE(bin.find("error: a.out:1: column 1: control character 0x7f"), std::string::npos) << bin;

  // Second line bad, first line good: the first ran, the error names line 2 without its text.
  scripts_["half"] = "create sink h1\npassword=hunter2\n";
  const std::string half = error("run half");
  EXPECT_EQ(half.find("hunter2"), std::string::npos) << half;
  EXPECT_NE(half.find("error: half:2: column 1: not a shell command"), std::string::npos) << half;
  EXPECT_TRUE(node_->find("h1"));
  // Typed at the prompt, the unknown word is the person's own and is quoted with a hint.
  EXPECT_NE(error("tasksx").find("unknown command 'tasksx' (did you mean 'tasks'?)"), std::string::npos);
}

TEST(ShellFiles, RunReadsRegularFilesOnly) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  testing::add_test_types(types);
  os::Node node(ex, {"board", 1, 64, &types});
  Shell shell(node);
  const std::string path = ::testing::TempDir() + "shell_run_test.symb";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("create sink from-file\n", f);
    std::fclose(f);
  }
  EXPECT_TRUE(shell.execute("run " + quote_word(path)).ok);
  EXPECT_TRUE(node.find("from-file"));
  std::remove(path.c_str());
  const Reply dir = shell.execute("run /");
  EXPECT_FALSE(dir.ok);
  EXPECT_NE(dir.text.find("not a regular file"), std::string::npos);
  EXPECT_FALSE(shell.execute("run /dev/zero").ok);
}

TEST_F(ShellTest, TypesTimeAndExit) {
  const auto rows = split_table(ok("types"));
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"TYPE", "PARAM", "KIND", "DEFAULT", "RANGE", "DOC"}));
  bool saw_value = false;
  for (const auto& r : rows)
    if (r[0] == "emitter" && r[1] == "value") {
      saw_value = true;
      EXPECT_EQ(r[2], "real");
      EXPECT_EQ(r[3], "1");
    }
  EXPECT_TRUE(saw_value);
  const Json t = json("types --json");
  ASSERT_EQ(t.array().size(), 3u);  // emitter, shell, sink
  EXPECT_EQ(t[0]["name"].string(), "emitter");
  EXPECT_EQ(t[0]["params"][1]["default"].string(), "none");
  EXPECT_EQ(t[0]["period_ns"].number(), 10e6);

  ex_.run_for(1500ms);
  const auto trows = split_table(ok("time"));
  ASSERT_EQ(trows.size(), 2u);
  EXPECT_EQ(trows[1], (std::vector<std::string>{"board", "1.500000", "1500000000"}));
  EXPECT_EQ(json("time --json")["time_ns"].number(), 1.5e9);

  EXPECT_FALSE(shell_->exit_requested());
  EXPECT_EQ(ok("quit"), "bye\n");
  EXPECT_TRUE(shell_->exit_requested());
}

}  // namespace
}  // namespace symb::shell
