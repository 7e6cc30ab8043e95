#include "symb/shell/shell_task.hpp"

#include "symb/io/bytes.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/os/node.hpp"

namespace symb::shell {

namespace {

constexpr std::size_t kShellQueue = 256;  // raw chunks of a fast paste must not be dropped

}  // namespace

bool same_token(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const auto x = static_cast<unsigned char>(i < a.size() ? a[i] : 0);
    const auto y = static_cast<unsigned char>(i < b.size() ? b[i] : 0);
    diff = static_cast<unsigned char>(diff | (x ^ y));
  }
  return diff == 0;
}

CommandShellTask::CommandShellTask(ShellOptions options)
    : options_(std::move(options)),
      terminal_(options_.terminal),
      editor_(LineEditor::Options{terminal_, kMaxLineBytes, 100, options_.prompt}),
      peer_(options_.peer),
      locked_(!options_.token.empty()) {
  editor_.set_secret(locked_.load());
  if (locked_.load()) editor_.set_prompt("token: ");
}

std::string CommandShellTask::greeting() const {
  return "Symbricator shell on node '" + node().name() + "'. 'help' lists the commands.\n";
}

void CommandShellTask::on_start() {
  Shell::Options so;
  so.devices = options_.devices;
  so.read_file = options_.read_file;
  so.load_plugin = options_.load_plugin;
  shell_.emplace(node(), std::move(so));
  shell_->protect(id());
  if (peer_.valid()) shell_->protect(peer_);
  // Plain-mode sessions (scripts) get no greeting: their output is only the replies.
  if (terminal_) say(terminal_text(locked_.load() ? std::string() : greeting()) + editor_.redraw());
}

std::string CommandShellTask::terminal_text(std::string_view text) const {
  if (!terminal_) return std::string(text);
  std::string out;
  out.reserve(text.size() + 16);
  for (char c : text) {
    if (c == '\n') out += '\r';
    out += c;
  }
  return out;
}

void CommandShellTask::say(const std::string& text) {
  if (!text.empty()) send(io::StreamTask::kDataPort, io::text_payload(text));
}

void CommandShellTask::on_message(const os::Message& m) {
  if (closing_ || !shell_) return;
  const io::Bytes* bytes = io::bytes_of(m);
  if (bytes == nullptr && m.port == io::StreamTask::kEndPort) {
    end_of_input();
    return;
  }
  if (bytes == nullptr) return;
  if (!peer_.valid() && m.source.valid()) {
    peer_ = m.source;
    shell_->protect(peer_);
  }
  feed(bytes->data);
}

void CommandShellTask::end_of_input() {
  // A last line without its newline was typed all the same: it runs before the session ends.
  if (!editor_.buffer().empty()) {
    const char nl = '\n';
    feed(std::as_bytes(std::span<const char>(&nl, 1)));
  }
  if (closing_) return;
  if (!options_.close_on_exit) {
    // A console stays for the line's return (a replugged adapter), locked again if it has a token.
    log(os::LogLevel::kInfo, "end of input: the console waits for its line");
    if (!options_.token.empty()) {
      locked_ = true;
      editor_.set_secret(true);
      editor_.set_prompt("token: ");
    }
    return;
  }
  log(os::LogLevel::kInfo, "end of input: the session ends");
  close_session();
}

void CommandShellTask::feed(std::span<const std::byte> data) {
  events_.clear();
  const std::string echo = editor_.feed(data, events_);
  std::string out;
  std::size_t echoed = 0;
  for (const auto& e : events_) {
    out.append(echo, echoed, e.echo_at - echoed);
    echoed = e.echo_at;
    out += handle(e);
    if (closing_) break;
  }
  if (!closing_) out.append(echo, echoed);
  say(out);
}

std::string CommandShellTask::handle(const EditorEvent& e) {
  switch (e.kind) {
    case EditorEvent::Kind::kInterrupt:
      if (shell_->following()) shell_->stop_following();
      return editor_.redraw();
    case EditorEvent::Kind::kOverlong: return terminal_text("error: " + e.text + "\n") + editor_.redraw();
    case EditorEvent::Kind::kEndOfInput:
      if (locked_.load()) return {};
      break;  // Ctrl-D on an empty line: as `exit`
    case EditorEvent::Kind::kTerminal:
      terminal_ = true;
      return terminal_text(locked_.load() ? std::string() : greeting()) + editor_.redraw();
    case EditorEvent::Kind::kLine: break;
  }
  if (locked_.load()) return unlock(e.text);
  Reply r = shell_->execute(e.kind == EditorEvent::Kind::kEndOfInput ? std::string_view("exit") : e.text);
  std::string out = terminal_text(r.text);
  if (shell_->exit_requested()) {
    shell_->clear_exit_request();
    shell_->stop_following();
    if (options_.close_on_exit) {
      close_session();
      return out;
    }
    if (!options_.token.empty()) {
      // A serial console is not closed: it locks again for the next person.
      locked_ = true;
      editor_.set_secret(true);
      editor_.set_prompt("token: ");
    }
  }
  return out + editor_.redraw();
}

std::string CommandShellTask::unlock(const std::string& line) {
  if (same_token(line, options_.token)) {
    locked_ = false;
    failures_ = 0;
    editor_.set_secret(false);
    editor_.set_prompt(options_.prompt);
    return terminal_ ? terminal_text(greeting()) + editor_.redraw() : std::string();
  }
  ++failures_;
  log(os::LogLevel::kWarn,
      "wrong shell token (" + std::to_string(failures_) + " of " + std::to_string(options_.max_token_failures) + ")");
  if (failures_ >= options_.max_token_failures) {
    close_session();
    return terminal_text("error: access denied; closing\n");
  }
  return terminal_text("error: access denied\n") + editor_.redraw();
}

void CommandShellTask::close_session() {
  // The farewell is still queued at the stream task: its deletion would discard it, so the
  // tasks go at a later tick, once it was written (or kDrainLimit passed).
  closing_ = true;
  closing_since_ = now();
}

void CommandShellTask::finish() {
  if (peer_.valid()) (void)node().remove(peer_);
  (void)node().remove(id());
}

void CommandShellTask::on_tick() {
  if (!shell_) return;
  if (closing_) {
    const auto peer = peer_.valid() ? node().info(peer_) : std::nullopt;
    if (!peer || peer->queue_depth == 0 || now() - closing_since_ >= kDrainLimit) finish();
    return;
  }
  // A shell whose stream task was deleted has no one to talk to any more.
  if (peer_.valid() && !node().info(peer_)) {
    (void)node().remove(id());
    return;
  }
  if (shell_->following() && !locked_.load()) {
    const std::string entries = shell_->follow_output();
    if (!entries.empty()) say(editor_.clear_line() + terminal_text(entries) + editor_.redraw());
  }
}

void CommandShellTask::on_stop() {
  if (options_.on_close) options_.on_close();
}

kernel::Result<ShellSession> attach_shell(os::Node& node, std::shared_ptr<io::IOStream> stream, ShellOptions options,
                                          std::string name) {
  if (!stream) return kernel::Error{"attach_shell: no stream"};
  if (!os::is_valid_name(name) || name.size() + 3 > 63)
    return kernel::Error{"invalid shell name '" + name.substr(0, 63) + "'"};
  // Both tasks are created unstarted and hooked before they start, so that the greeting and the
  // first bytes typed cannot pass before the hooks exist.
  os::TaskOptions io_options;
  io_options.queue_capacity = options.output_queue;
  io_options.autostart = false;
  auto io_id = node.create(name + ".io", std::make_unique<io::StreamTask>(std::move(stream), io::StreamTask::Options{}),
                           io_options);
  if (!io_id) return kernel::Error{io_id.error()};
  options.peer = *io_id;
  os::TaskOptions shell_options;
  shell_options.period = CommandShellTask::kTick;
  shell_options.queue_capacity = options.input_queue;
  shell_options.autostart = false;
  auto shell_id = node.create(name, std::make_unique<CommandShellTask>(std::move(options)), shell_options);
  if (!shell_id) {
    (void)node.remove(*io_id);
    return kernel::Error{shell_id.error()};
  }
  os::HookOptions refuse;
  refuse.policy = os::QueuePolicy::kRefuse;  // typed input and replies are never overwritten
  kernel::Status st;
  if (auto h = node.hook(*io_id, *shell_id, refuse); !h) st = kernel::Error{h.error()};
  if (st)
    if (auto h = node.hook(*shell_id, *io_id, refuse); !h) st = kernel::Error{h.error()};
  if (st) st = node.start(*io_id);
  if (st) st = node.start(*shell_id);
  if (!st) {
    (void)node.remove(*shell_id);
    (void)node.remove(*io_id);
    return kernel::Error{st.error()};
  }
  return ShellSession{*io_id, *shell_id};
}

kernel::Status register_shell_types(os::TaskTypeRegistry& registry, std::shared_ptr<const DeviceTable> devices) {
  os::ParamTable<ShellOptions> p;
  p.add("terminal", &ShellOptions::terminal).doc("echo and line editing for a person");
  p.add("prompt", &ShellOptions::prompt).at_most(64.0).doc("prompt in terminal mode");
  p.add("token", &ShellOptions::token).at_most(256.0).doc("first line must be this (empty: none)");
  p.add("close_on_exit", &ShellOptions::close_on_exit)
      .default_value(false)
      .doc("exit deletes the shell and its stream task");
  auto type = os::declare_task_type("shell", "command shell; hook a raw stream task to it and it to the stream task",
                                    std::move(p), [devices](const ShellOptions& c) {
                                      ShellOptions o = c;
                                      o.devices = devices;
                                      return std::make_unique<CommandShellTask>(std::move(o));
                                    });
  type.defaults.period = CommandShellTask::kTick;
  type.defaults.queue_capacity = kShellQueue;
  return registry.add(std::move(type));
}

}  // namespace symb::shell
