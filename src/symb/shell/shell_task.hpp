// CommandShellTask: the paper's CommandShellTask, a task that gives a person (or a script) a shell
// on a running node over any byte stream. It is hooked from a StreamTask in raw mode (it receives
// the bytes typed, as io::Bytes), turns them into lines with a LineEditor, executes each with a
// Shell, and sends the replies back to the tasks hooked to it (that StreamTask) as io::Bytes. The
// shell does not care whether the bytes come over a serial line, a pseudo-terminal or TCP: a shell
// over any stream is that stream's StreamTask and a CommandShellTask hooked both ways
// (attach_shell()).
//
// With a token, the first line must be that token: a session stays locked ("access denied")
// until it is, and after max_token_failures wrong tokens the task deletes itself and its stream
// task. `exit` ends the session the same way (or, with close_on_exit off, locks it again).
// `log follow` streams new SysLog entries at each tick.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/shell/line_editor.hpp"
#include "symb/shell/shell.hpp"

namespace symb::os {
class Node;
}

namespace symb::shell {

struct ShellOptions {
  bool terminal = false;          // a person at a terminal: echo, line editing, prompt
  std::string prompt = "symb> ";  // shown in terminal mode
  std::string token;              // when not empty, the first line must be this
  int max_token_failures = 3;     // then the session is closed
  bool close_on_exit = true;      // `exit` deletes the session's tasks; off: it locks it again
  std::shared_ptr<const DeviceTable> devices;
  // How `run FILE` reads scripts (see Shell::Options::read_file).
  std::function<kernel::Result<std::string>(const std::string& path)> read_file;
  // How `load PATH` loads a task-type plugin (see Shell::Options::load_plugin).
  std::function<kernel::Status(const std::string& path)> load_plugin;
  // The stream task the session talks through. When invalid, the first task that sends bytes.
  os::TaskId peer;
  // Called from the task's on_stop (on its own context) however the session ended: a server
  // hears here that it may close the connection.
  std::function<void()> on_close;
  // attach_shell's queues, each slot a message: raw chunks typed or pasted in, and replies
  // waiting to be written. A microcontroller (the board: 32 KiB of RAM) gives smaller ones.
  std::size_t input_queue = 256;  // raw chunks of a fast paste must not be dropped
  std::size_t output_queue = 64;
};

class CommandShellTask : public os::Task {
 public:
  // How often the task looks for new log entries (log follow) and for the end of its session.
  static constexpr kernel::Duration kTick = std::chrono::milliseconds(100);
  // How long a closing session waits for its farewell to be written before it goes anyway.
  static constexpr kernel::Duration kDrainLimit = std::chrono::seconds(2);

  explicit CommandShellTask(ShellOptions options);

  // Whether the session still waits for its token (readable from any thread).
  bool locked() const { return locked_.load(); }

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;
  void on_stop() override;

 private:
  // Runs the lines in `data` and sends the replies.
  void feed(std::span<const std::byte> data);
  // The stream task said no more input will come: the last line runs, then the session closes.
  void end_of_input();
  // What to send for one editor event.
  std::string handle(const EditorEvent& e);
  std::string unlock(const std::string& line);
  std::string greeting() const;
  // Reply text as the other end wants it: "\r\n" line ends on a terminal.
  std::string terminal_text(std::string_view text) const;
  void say(const std::string& text);
  void close_session();
  void finish();

  ShellOptions options_;
  bool terminal_;  // options_.terminal, or switched on by the client
  LineEditor editor_;
  std::optional<Shell> shell_;
  os::TaskId peer_;
  std::atomic<bool> locked_;
  int failures_ = 0;
  bool closing_ = false;
  kernel::Time closing_since_{0};
  std::vector<EditorEvent> events_;
};

// Whether a token given equals the expected one. Compares without stopping at the first
// difference, so the time taken says nothing about how much of a guessed token was right (the
// shell's sessions and the web view check their tokens with it).
bool same_token(std::string_view given, std::string_view expected);

// The two tasks of one shell session on a node.
struct ShellSession {
  os::TaskId io;     // the StreamTask, named "<name>.io"
  os::TaskId shell;  // the CommandShellTask, named "<name>"
};

// Opens a shell on `node` over `stream`: creates a raw StreamTask "<name>.io" and a
// CommandShellTask "<name>", hooks them both ways and starts them. Call it where node calls may
// be made (on the executor's context: inside Node::inject from another thread). On failure
// nothing is left behind.
kernel::Result<ShellSession> attach_shell(os::Node& node, std::shared_ptr<io::IOStream> stream, ShellOptions options,
                                          std::string name = "shell");

// Registers the task type "shell": a CommandShellTask with parameters terminal, prompt and token,
// to be hooked to a stream task by hand (`create shell sh2` then `hook uart1 sh2` and
// `hook sh2 uart1`). Its sessions use `devices` for ioctl.
kernel::Status register_shell_types(os::TaskTypeRegistry& registry,
                                    std::shared_ptr<const DeviceTable> devices = nullptr);

}  // namespace symb::shell
