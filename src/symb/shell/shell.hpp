// Shell: the command engine behind the paper's CommandShellTask. It executes one line of text
// against a node (create, suspend, resume, delete, hook and unhook tasks at runtime; inspect
// tasks, hooks, types, parameters, the log and devices) and returns a Reply; where the line came
// from and where the reply goes (a serial line, TCP, a test) is someone else's business.
//
// It runs on the node's executor context (it is called from a task's handler) and never blocks:
// every command is a few node calls. Bad input of any kind gives ok == false and a message that
// points at the argument (its column), and changes nothing: each command checks all of its
// arguments before it touches the node. List commands print an aligned, header-first table (see
// Table) or, with --json, a JSON array.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/syslog.hpp"
#include "symb/shell/command_line.hpp"

namespace symb::os {
class Node;
}

namespace symb::shell {

// The devices a shell may list and send ioctls to, by name.
using DeviceTable = std::map<std::string, std::shared_ptr<io::Device>, std::less<>>;

struct Reply {
  bool ok = true;
  // Ends with '\n'; an error's is one line starting with "error: ". Empty only for a line with
  // nothing to do (blank, a comment, `exit` inside a script).
  std::string text;
};

// One command, for `help` and the documentation.
struct CommandHelp {
  std::string_view name;
  std::string_view usage;
  std::string_view summary;
  std::string_view details;
};

class Shell {
 public:
  struct Options {
    // Devices for `devices`, `ioctls` and `ioctl`; may be null (then there are none).
    std::shared_ptr<const DeviceTable> devices;
    // How `run FILE` reads a script. When empty, regular files of up to kMaxScriptBytes are read
    // from the file system; a test or a fuzzer may serve scripts from memory instead.
    std::function<kernel::Result<std::string>(const std::string& path)> read_file;
    // How deeply `run` may nest.
    int max_script_depth = 8;
    // How many script lines one top-level `run` may execute in all: a script that runs itself
    // twice would otherwise do 2^8 times the work.
    std::size_t max_script_lines = 100000;
    // Hooks to tasks on other nodes, for whoever owns a bus between them (the organism bus,
    // sim/mujoco/organism_bus.hpp): `hook SENDER MODULE/TASK` calls remote_hook("<this
    // node>/SENDER", "MODULE/TASK", options), which answers the line to print or why not; `hooks`
    // (text form) appends remote_hooks()'s table. Unset: a RECEIVER with '/' is a local name.
    std::function<kernel::Result<std::string>(const std::string& sender, const std::string& receiver,
                                              const os::HookOptions& options)>
        remote_hook;
    std::function<std::string()> remote_hooks;
    // `load PATH`: adds a task-type plugin's types (os/plugin.hpp) to the node's registry; whoever
    // owns the registry sets it (symb run: the robot's own). Unset: `load` says it cannot.
    std::function<kernel::Status(const std::string& path)> load_plugin;
  };
  static constexpr std::size_t kMaxScriptBytes = 1 << 20;

  // `node` must outlive the shell.
  explicit Shell(os::Node& node) : Shell(node, Options{}) {}
  Shell(os::Node& node, Options options);

  // Executes one line (without its line ending).
  Reply execute(std::string_view line);

  // Tasks that `suspend` and `delete` refuse to touch: the shell's own task and its stream, so
  // that a user cannot cut the branch the session sits on (`exit` ends a session).
  void protect(os::TaskId id);

  // `exit` or `quit` was executed (outside a script).
  bool exit_requested() const { return exit_requested_; }
  void clear_exit_request() { exit_requested_ = false; }

  // `log follow` is in force: the caller should call follow_output() now and then.
  bool following() const { return following_; }
  // Log entries written since the last call, one formatted line each, at most `max` (the rest
  // come next time); says so when the log's ring dropped entries before they could be shown.
  std::string follow_output(std::size_t max = 64);
  void stop_following() { following_ = false; }

  // Every command, in the order `help` lists them.
  static std::span<const CommandHelp> commands();

 private:
  struct Call;
  struct Command;
  static std::span<const Command> table();

  Reply run_line(std::string_view line, int depth);

  Reply cmd_help(const Call& c);
  Reply cmd_tasks(const Call& c);
  Reply cmd_types(const Call& c);
  Reply cmd_load(const Call& c);
  Reply cmd_create(const Call& c);
  Reply cmd_suspend(const Call& c);
  Reply cmd_resume(const Call& c);
  Reply cmd_delete(const Call& c);
  Reply cmd_priority(const Call& c);
  Reply cmd_period(const Call& c);
  Reply cmd_set(const Call& c);
  Reply cmd_params(const Call& c);
  Reply cmd_hook(const Call& c);
  Reply cmd_unhook(const Call& c);
  Reply cmd_hooks(const Call& c);
  Reply cmd_enable(const Call& c);
  Reply cmd_disable(const Call& c);
  Reply cmd_suppress(const Call& c);
  Reply cmd_inhibit(const Call& c);
  Reply cmd_post(const Call& c);
  Reply cmd_log(const Call& c);
  Reply cmd_devices(const Call& c);
  Reply cmd_ioctls(const Call& c);
  Reply cmd_ioctl(const Call& c);
  Reply cmd_run(const Call& c);
  Reply cmd_time(const Call& c);
  Reply cmd_exit(const Call& c);

  Reply set_hook_enabled(const Call& c, bool enabled);
  kernel::Result<os::TaskId> task_named(const Token& t) const;
  kernel::Result<os::HookId> hook_numbered(const Token& t) const;
  kernel::Result<std::shared_ptr<io::Device>> device_named(const Token& t) const;
  bool is_protected(os::TaskId id) const;

  os::Node& node_;
  Options options_;
  std::vector<os::TaskId> protected_;
  int depth_ = 0;  // of the `run` being executed
  bool exit_requested_ = false;
  bool script_exit_ = false;      // `exit` inside a script: ends that script only
  std::size_t script_lines_ = 0;  // lines run under the current top-level `run`
  bool following_ = false;
  std::uint64_t follow_seq_ = 0;
  os::LogLevel follow_level_ = os::LogLevel::kDebug;
};

}  // namespace symb::shell
