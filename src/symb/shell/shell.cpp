#include "symb/shell/shell.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"
#include "symb/shell/json_writer.hpp"
#include "symb/shell/table.hpp"

namespace symb::shell {

using kernel::Error;
using kernel::Result;

namespace {

using namespace std::chrono_literals;

constexpr std::int64_t kMaxPriority = 1000;
constexpr kernel::Duration kMinPeriod = 1ms;  // shorter periods would flood a node with ticks
constexpr kernel::Duration kMaxWindow = std::chrono::hours(24);
constexpr std::int64_t kMaxQueue = 65536;
constexpr std::size_t kDefaultLogLines = 20;

Reply ok(std::string text) {
  if (text.empty() || text.back() != '\n') text += '\n';
  return {true, std::move(text)};
}

Reply fail(std::string_view message) { return {false, "error: " + std::string(message) + "\n"}; }

std::string duration_text(kernel::Duration d) { return os::format_param_value(os::ParamValue{d}); }

std::string id_text(os::TaskId id) { return "#" + std::to_string(id.index) + "." + std::to_string(id.generation); }

std::string bound_text(const std::optional<double>& b, const char* none) {
  if (!b) return none;
  // Whole bounds print as integers (1000000, not 1e+06): that is how people write them.
  if (std::fabs(*b) < 1e15 && *b == std::floor(*b)) return std::to_string(static_cast<long long>(*b));
  return os::format_param_value(os::ParamValue{*b});
}

std::string range_text(const os::ParamSpec& p) {
  if (!p.min && !p.max) return "";
  return bound_text(p.min, "-inf") + ".." + bound_text(p.max, "inf");
}

void range_json(JsonWriter& j, const os::ParamSpec& p) {
  j.key("min");
  if (p.min)
    j.value(*p.min);
  else
    j.null();
  j.key("max");
  if (p.max)
    j.value(*p.max);
  else
    j.null();
}

// A message's error with the column of `t` in front, unless it already has a column.
std::string located(const Token& t, const std::string& message) {
  return message.starts_with("column ") ? message : at_column(t.column, message);
}

std::string read_regular_file(const std::string& path, std::string& error) {
#ifdef SYMB_BOARD
  // A board has no file system; leaving out <fstream> keeps the locale machinery (140 KB) out of
  // its flash.
  (void)path;
  error = "the board has no files";
  return {};
#else
  // A FIFO or a device would block or never end: only regular files are scripts.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    error = std::strerror(errno);
    return {};
  }
  if (!S_ISREG(st.st_mode)) {
    error = "not a regular file";
    return {};
  }
  if (static_cast<std::size_t>(st.st_size) > Shell::kMaxScriptBytes) {
    error = "larger than " + std::to_string(Shell::kMaxScriptBytes) + " bytes";
    return {};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = std::strerror(errno);
    return {};
  }
  std::string text;
  char buf[4096];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > Shell::kMaxScriptBytes) {
      error = "larger than " + std::to_string(Shell::kMaxScriptBytes) + " bytes";
      return {};
    }
  }
  return text;
#endif
}

constexpr OptionSpec kJson[] = {{"--json", ""}};
constexpr OptionSpec kCreateOptions[] = {
    {"--priority", "N"}, {"--period", "DURATION"}, {"--queue", "N"}, {"--suspended", ""}};
constexpr OptionSpec kHookOptions[] = {
    {"--priority", "N"}, {"--policy", "POLICY"}, {"--port", "P"}, {"--suppress", "DURATION"}, {"--disabled", ""}};
constexpr OptionSpec kPostOptions[] = {{"--port", "P"}};
constexpr OptionSpec kLogOptions[] = {{"--level", "LEVEL"}, {"--json", ""}};
constexpr std::string_view kLevels[] = {"debug", "info", "warn", "error"};
constexpr std::string_view kPolicies[] = {"keep-newest", "refuse"};

}  // namespace

struct Shell::Call {
  const Command& command;
  const Token& word;  // the command's own token
  Args args;
  const std::vector<Token>& pos() const { return args.positional(); }
  bool json() const { return args.has("--json"); }
};

struct Shell::Command {
  CommandHelp help;
  Reply (Shell::*run)(const Call&);
  std::size_t min_args;
  std::size_t max_args;
  std::span<const OptionSpec> options;
};

std::span<const Shell::Command> Shell::table() {
  constexpr std::size_t kMany = 64;
  static const Command commands[] = {
      {{"help", "help [COMMAND] [--json]", "list the commands, or describe one",
        "Without COMMAND, one line per command; with it, its usage and what it does."},
       &Shell::cmd_help,
       0,
       1,
       kJson},
      {{"tasks", "tasks [--json]", "list the node's tasks",
        "Columns: NAME STATE PRIO PERIOD QUEUE (depth/capacity) IN (handled) OUT (sent) DROPPED TYPE.\n"
        "JSON adds the id and every traffic counter."},
       &Shell::cmd_tasks,
       0,
       0,
       kJson},
      {{"types", "types [--json]", "list the registered task types and their parameters",
        "One row per type (PARAM '-', DOC the type's description), then one per parameter:\n"
        "TYPE PARAM KIND DEFAULT RANGE DOC."},
       &Shell::cmd_types,
       0,
       0,
       kJson},
      {{"create", "create TYPE NAME [PARAM=VALUE ...] [--priority N] [--period DURATION] [--queue N] [--suspended]",
        "create a task of a registered type",
        "Parameters not given keep the type's defaults; values with spaces go in quotes (speed=\"1 2\").\n"
        "Priority, period and queue size default to the type's. --period 0 means no ticks.\n"
        "--suspended creates it without starting it (state 'created'); 'resume' starts it."},
       &Shell::cmd_create,
       2,
       kMany,
       kCreateOptions},
      {{"suspend", "suspend NAME", "suspend a running task",
        "A suspended task gets no handler calls; its queue fills."},
       &Shell::cmd_suspend,
       1,
       1,
       {}},
      {{"resume", "resume NAME", "resume a suspended task, or start a created one", ""}, &Shell::cmd_resume, 1, 1, {}},
      {{"delete", "delete NAME", "delete a task",
        "It is unhooked from everything at once, then stopped; messages still queued are discarded."},
       &Shell::cmd_delete,
       1,
       1,
       {}},
      {{"priority", "priority NAME N", "change a task's priority (-1000..1000)", ""}, &Shell::cmd_priority, 2, 2, {}},
      {{"period", "period NAME DURATION", "change a task's tick period (0: no ticks; else at least 1ms)", ""},
       &Shell::cmd_period,
       2,
       2,
       {}},
      {{"set", "set NAME PARAM VALUE", "change a task's parameter at runtime",
        "The value is checked against the type's schema now; the task applies it on its own context\n"
        "and may refuse it (the refusal is logged)."},
       &Shell::cmd_set,
       3,
       3,
       {}},
      {{"params", "params NAME [--json]", "show a task's parameters", "Columns: PARAM KIND VALUE DEFAULT RANGE DOC."},
       &Shell::cmd_params,
       1,
       1,
       kJson},
      {{"hook",
        "hook SENDER RECEIVER [--priority N] [--policy keep-newest|refuse] [--port P] [--suppress DURATION] "
        "[--disabled]",
        "send SENDER's output to RECEIVER's queue too",
        "--policy: what a full queue does (keep-newest overwrites the oldest, refuse drops the new one).\n"
        "--port: only messages on that port. --suppress: each delivery blocks lower-priority hooks into\n"
        "RECEIVER for that long. Prints the hook's number. A RECEIVER of the form MODULE/TASK is a task on\n"
        "another node, hooked over the bus that joins them (where the shell's owner gave it one)."},
       &Shell::cmd_hook,
       2,
       2,
       kHookOptions},
      {{"unhook", "unhook HOOK | unhook SENDER RECEIVER", "remove a hook, or every hook from SENDER to RECEIVER",
        "HOOK is the number 'hooks' shows."},
       &Shell::cmd_unhook,
       1,
       2,
       {}},
      {{"hooks", "hooks [--json]", "list the hooks",
        "Columns: HOOK SENDER RECEIVER PRIO POLICY PORT SUPPRESS STATE INHIBITED (until, node time)."},
       &Shell::cmd_hooks,
       0,
       0,
       kJson},
      {{"enable", "enable HOOK", "enable a hook", ""}, &Shell::cmd_enable, 1, 1, {}},
      {{"disable", "disable HOOK", "disable a hook (nothing travels through it)", ""}, &Shell::cmd_disable, 1, 1, {}},
      {{"suppress", "suppress RECEIVER LEVEL DURATION", "block delivery into RECEIVER through hooks below LEVEL",
        "For DURATION from now (subsumption)."},
       &Shell::cmd_suppress,
       3,
       3,
       {}},
      {{"inhibit", "inhibit SENDER RECEIVER|* DURATION", "block SENDER's output to RECEIVER (or to all: *)",
        "For DURATION from now (subsumption)."},
       &Shell::cmd_inhibit,
       3,
       3,
       {}},
      {{"post", "post NAME [V ...] [--port P]", "put a message of numbers into a task's queue",
        "Up to 32 numbers, as if from outside any task. A full queue refuses it (counted as refused)."},
       &Shell::cmd_post,
       1,
       1 + 32,
       kPostOptions},
      {{"log", "log [N] [--level LEVEL] [--json] | log follow [--level LEVEL] | log stop",
        "show the newest log entries, or stream new ones",
        "N entries (default 20) at or above LEVEL (debug, info, warn, error).\n"
        "Columns: SEQ TIME LEVEL SOURCE TEXT. 'log follow' streams new entries until 'log stop'."},
       &Shell::cmd_log,
       0,
       1,
       kLogOptions},
      {{"devices", "devices [--json]", "list the devices", "Columns: NAME OPEN IOCTLS."},
       &Shell::cmd_devices,
       0,
       0,
       kJson},
      {{"ioctls", "ioctls DEVICE [--json]", "list a device's control commands",
        "Columns: COMMAND ARG RANGE DOC (ARG is the argument's type, '-' for none)."},
       &Shell::cmd_ioctls,
       1,
       1,
       kJson},
      {{"ioctl", "ioctl DEVICE COMMAND [ARG]", "send a control command to a device", "Prints the device's answer."},
       &Shell::cmd_ioctl,
       2,
       3,
       {}},
      {{"run", "run FILE", "execute a script of shell lines",
        "Stops at the first error and reports it as FILE:LINE. Scripts may run scripts, 8 deep;\n"
        "'exit' ends the script."},
       &Shell::cmd_run,
       1,
       1,
       {}},
      {{"load", "load PATH", "load a task-type plugin (a shared library) into the node's registry",
        "Its types are then created like any other (create TYPE NAME ...). A plugin of another ABI\n"
        "version, or whose registration fails, is refused and changes nothing (docs/plugins.md)."},
       &Shell::cmd_load,
       1,
       1,
       {}},
      {{"time", "time [--json]", "show the node's clock", "Columns: NODE TIME (seconds) NS."},
       &Shell::cmd_time,
       0,
       0,
       kJson},
      {{"exit", "exit", "end the session", ""}, &Shell::cmd_exit, 0, 0, {}},
      {{"quit", "quit", "end the session", ""}, &Shell::cmd_exit, 0, 0, {}},
  };
  return commands;
}

std::span<const CommandHelp> Shell::commands() {
  static const std::vector<CommandHelp> help = [] {
    std::vector<CommandHelp> h;
    for (const auto& c : table()) h.push_back(c.help);
    return h;
  }();
  return help;
}

Shell::Shell(os::Node& node, Options options) : node_(node), options_(std::move(options)) {}

void Shell::protect(os::TaskId id) { protected_.push_back(id); }

bool Shell::is_protected(os::TaskId id) const {
  return std::find(protected_.begin(), protected_.end(), id) != protected_.end();
}

Reply Shell::execute(std::string_view line) { return run_line(line, 0); }

Reply Shell::run_line(std::string_view line, int depth) {
  auto tokens = tokenize(line);
  if (!tokens) return fail(tokens.error());
  if (tokens->empty()) return {true, ""};
  const Token& word = tokens->front();
  const Command* command = nullptr;
  for (const auto& c : table())
    if (c.help.name == word.text) command = &c;
  if (command == nullptr && depth > 0) {
    // A line of a file given to `run`: the file may be anything readable (a binary, a password
    // file), so its bytes are never quoted back; the position and the kind of problem say enough.
    return fail(at_column(word.column,
                          "not a shell command (the line's first word is not one; its text is not "
                          "shown, as the file may not be a shell script)"));
  }
  if (command == nullptr) {
    std::vector<std::string_view> names;
    for (const auto& c : table()) names.push_back(c.help.name);
    std::string msg = "unknown command '" + shorten(word.text) + "'";
    if (auto hint = os::closest_name(word.text, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
    return fail(at_column(word.column, msg + "; 'help' lists the commands"));
  }
  auto args = Args::parse(std::span<const Token>(*tokens).subspan(1), command->options);
  if (!args) return fail(args.error());
  const auto& pos = args->positional();
  const std::string usage = " (usage: " + std::string(command->help.usage) + ")";
  if (pos.size() < command->min_args) {
    const std::size_t col = pos.empty() ? word.column : pos.back().column;
    return fail(at_column(col, "'" + word.text + "' needs more arguments" + usage));
  }
  if (pos.size() > command->max_args) {
    const Token& extra = pos[command->max_args];
    return fail(at_column(extra.column, "unexpected argument '" + shorten(extra.text) + "'" + usage));
  }
  const int saved = depth_;
  depth_ = depth;
  Reply r = (this->*command->run)(Call{*command, word, std::move(args).value()});
  depth_ = saved;
  return r;
}

// --- lookups -------------------------------------------------------------------------------------

Result<os::TaskId> Shell::task_named(const Token& t) const {
  if (auto id = node_.find(t.text)) return *id;
  std::vector<std::string> names;
  for (const auto& i : node_.tasks()) names.push_back(i.name);
  std::vector<std::string_view> views(names.begin(), names.end());
  std::string msg = "node '" + node_.name() + "' has no task '" + shorten(t.text) + "'";
  if (auto hint = os::closest_name(t.text, views); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
  return Error{at_column(t.column, msg)};
}

Result<os::HookId> Shell::hook_numbered(const Token& t) const {
  auto n = parse_integer(t, "hook number", 1, std::numeric_limits<std::uint32_t>::max());
  if (!n) return Error{n.error()};
  for (const auto& h : node_.hooks())
    if (h.id.serial == static_cast<std::uint32_t>(*n)) return h.id;
  return Error{at_column(t.column, "no hook " + std::to_string(*n) + " ('hooks' lists them)")};
}

Result<std::shared_ptr<io::Device>> Shell::device_named(const Token& t) const {
  if (options_.devices) {
    auto it = options_.devices->find(t.text);
    if (it != options_.devices->end() && it->second) return it->second;
  }
  std::vector<std::string_view> names;
  if (options_.devices)
    for (const auto& [n, d] : *options_.devices) names.push_back(n);
  std::string msg = "no device '" + shorten(t.text) + "'";
  if (auto hint = os::closest_name(t.text, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
  if (names.empty()) msg += " (this shell has no devices)";
  return Error{at_column(t.column, msg)};
}

// --- commands ------------------------------------------------------------------------------------

Reply Shell::cmd_help(const Call& c) {
  if (!c.pos().empty()) {
    const Token& t = c.pos()[0];
    for (const auto& h : commands())
      if (h.name == t.text) {
        if (c.json()) {
          JsonWriter j;
          j.begin_object().field("name", h.name).field("usage", h.usage).field("summary", h.summary);
          j.field("details", h.details).end_object();
          return ok(j.str());
        }
        std::string text = "usage: " + std::string(h.usage) + "\n  " + std::string(h.summary) + "\n";
        if (!h.details.empty()) {
          std::string details(h.details);
          std::size_t at = 0;
          while (at < details.size()) {
            const std::size_t nl = details.find('\n', at);
            text += "  " + details.substr(at, nl == std::string::npos ? std::string::npos : nl - at) + "\n";
            at = nl == std::string::npos ? details.size() : nl + 1;
          }
        }
        return ok(text);
      }
    std::vector<std::string_view> names;
    for (const auto& h : commands()) names.push_back(h.name);
    std::string msg = "no command '" + shorten(t.text) + "'";
    if (auto hint = os::closest_name(t.text, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
    return fail(at_column(t.column, msg));
  }
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& h : commands())
      j.begin_object().field("name", h.name).field("usage", h.usage).field("summary", h.summary).end_object();
    j.end_array();
    return ok(j.str());
  }
  Table t({"COMMAND", "SUMMARY"});
  for (const auto& h : commands()) t.add({std::string(h.name), std::string(h.summary)});
  return ok(t.str() + "'help COMMAND' describes one; durations take a unit: 30ms, 2s, 1min.\n");
}

Reply Shell::cmd_tasks(const Call& c) {
  const auto tasks = node_.tasks();
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& i : tasks) {
      const auto& t = i.traffic;
      j.begin_object()
          .field("name", i.name)
          .field("id", id_text(i.id))
          .field("type", i.type)
          .field("state", os::to_string(i.state))
          .field("priority", i.priority)
          .field("period_ns", static_cast<std::int64_t>(i.period.count()))
          .field("queue_depth", static_cast<std::uint64_t>(i.queue_depth))
          .field("queue_capacity", static_cast<std::uint64_t>(i.queue_capacity))
          .field("in", t.delivered)
          .field("out", i.sent)
          .field("dropped", t.dropped())
          .field("attempted", t.attempted)
          .field("overwritten", t.overwritten)
          .field("refused", t.refused)
          .field("suppressed", t.suppressed)
          .field("inhibited", t.inhibited)
          .end_object();
    }
    j.end_array();
    return ok(j.str());
  }
  Table t({"NAME", "STATE", "PRIO", "PERIOD", "QUEUE", "IN", "OUT", "DROPPED", "TYPE"});
  for (const auto& i : tasks)
    t.add({i.name, os::to_string(i.state), std::to_string(i.priority),
           i.period.count() > 0 ? duration_text(i.period) : "-",
           std::to_string(i.queue_depth) + "/" + std::to_string(i.queue_capacity), std::to_string(i.traffic.delivered),
           std::to_string(i.sent), std::to_string(i.traffic.dropped()), i.type});
  return ok(t.str());
}

Reply Shell::cmd_types(const Call& c) {
  std::vector<const os::TaskType*> types;
  if (node_.types() != nullptr) types = node_.types()->list();
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto* type : types) {
      j.begin_object().field("name", type->name).field("doc", type->doc);
      j.field("priority", type->defaults.priority)
          .field("period_ns", static_cast<std::int64_t>(type->defaults.period.count()))
          .field("queue", static_cast<std::uint64_t>(type->defaults.queue_capacity));
      j.key("params").begin_array();
      for (const auto& p : type->params) {
        j.begin_object()
            .field("name", p.name)
            .field("type", os::to_string(p.type))
            .field("default", os::format_param_value(p.default_value));
        range_json(j, p);
        j.field("doc", p.doc).end_object();
      }
      j.end_array().end_object();
    }
    j.end_array();
    return ok(j.str());
  }
  Table t({"TYPE", "PARAM", "KIND", "DEFAULT", "RANGE", "DOC"});
  for (const auto* type : types) {
    t.add({type->name, "-", "-", "-", "-", type->doc});
    for (const auto& p : type->params)
      t.add({type->name, p.name, os::to_string(p.type), os::format_param_value(p.default_value), range_text(p), p.doc});
  }
  return ok(t.str());
}

Reply Shell::cmd_create(const Call& c) {
  const Token& type_tok = c.pos()[0];
  const Token& name_tok = c.pos()[1];
  const os::TaskTypeRegistry* registry = node_.types();
  if (registry == nullptr) return fail(at_column(type_tok.column, "node '" + node_.name() + "' has no task types"));
  const os::TaskType* type = registry->find(type_tok.text);
  if (type == nullptr) return fail(at_column(type_tok.column, registry->unknown_type_error(type_tok.text)));
  if (!os::is_valid_name(name_tok.text))
    return fail(at_column(name_tok.column, "invalid task name '" + shorten(name_tok.text) +
                                               "': use 1 to 63 letters, digits, '_', '.' or '-', starting with a "
                                               "letter or '_'"));
  if (node_.find(name_tok.text))
    return fail(
        at_column(name_tok.column, "node '" + node_.name() + "' already has a task named '" + name_tok.text + "'"));
  // name=value tokens become assignments that keep their column in the line, so the registry's
  // errors point at the right place.
  std::vector<os::ParamAssignment> params;
  for (std::size_t k = 2; k < c.pos().size(); ++k) {
    const Token& t = c.pos()[k];
    const std::size_t eq = t.text.find('=');
    if (eq == std::string::npos || !os::is_valid_name(std::string_view(t.text).substr(0, eq)))
      return fail(at_column(t.column, "expected PARAM=VALUE, got '" + shorten(t.text) + "'"));
    params.push_back({t.text.substr(0, eq), t.text.substr(eq + 1), t.column});
  }
  os::TaskOptions options = type->defaults;
  auto priority = c.args.integer("--priority", -kMaxPriority, kMaxPriority);
  if (!priority) return fail(priority.error());
  auto period = c.args.duration("--period", kernel::Duration{0}, kMaxWindow);
  if (!period) return fail(period.error());
  if (*period && period->value() > kernel::Duration{0} && period->value() < kMinPeriod)
    return fail(at_column(c.args.value("--period")->column, "option '--period': at least 1ms (or 0 for no ticks)"));
  auto queue = c.args.integer("--queue", 1, kMaxQueue);
  if (!queue) return fail(queue.error());
  if (*priority) options.priority = static_cast<int>(**priority);
  if (*period) options.period = **period;
  if (*queue) options.queue_capacity = static_cast<std::size_t>(**queue);
  options.autostart = !c.args.has("--suspended");
  auto id = node_.create(type->name, name_tok.text, params, options);
  if (!id) return fail(located(type_tok, id.error()));
  return ok("created '" + name_tok.text + "' (" + type->name + ", " + id_text(*id) + ")" +
            (options.autostart ? "" : ", not started: 'resume " + name_tok.text + "' starts it"));
}

Reply Shell::cmd_suspend(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  if (is_protected(*id)) return fail(at_column(t.column, "'" + t.text + "' carries this shell session: not suspended"));
  if (auto st = node_.suspend(*id); !st) return fail(at_column(t.column, st.error()));
  return ok("suspended '" + t.text + "'");
}

Reply Shell::cmd_resume(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  auto info = node_.info(*id);
  const bool created = info && info->state == os::TaskState::kCreated;
  if (auto st = created ? node_.start(*id) : node_.resume(*id); !st) return fail(at_column(t.column, st.error()));
  return ok((created ? "started '" : "resumed '") + t.text + "'");
}

Reply Shell::cmd_delete(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  if (is_protected(*id))
    return fail(at_column(t.column, "'" + t.text + "' carries this shell session: use 'exit' to end it"));
  if (auto st = node_.remove(*id); !st) return fail(at_column(t.column, st.error()));
  return ok("deleted '" + t.text + "'");
}

Reply Shell::cmd_priority(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  auto p = parse_integer(c.pos()[1], "priority", -kMaxPriority, kMaxPriority);
  if (!p) return fail(p.error());
  if (auto st = node_.set_priority(*id, static_cast<int>(*p)); !st) return fail(at_column(t.column, st.error()));
  return ok("priority of '" + t.text + "' is " + std::to_string(*p));
}

Reply Shell::cmd_period(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  auto d = parse_duration(c.pos()[1], "period", kernel::Duration{0}, kMaxWindow);
  if (!d) return fail(d.error());
  if (d->count() > 0 && *d < kMinPeriod) return fail(at_column(c.pos()[1].column, "period: at least 1ms (or 0)"));
  if (auto st = node_.set_period(*id, *d); !st) return fail(at_column(t.column, st.error()));
  return ok(d->count() > 0 ? "period of '" + t.text + "' is " + duration_text(*d)
                           : "'" + t.text + "' is no more ticked");
}

Reply Shell::cmd_set(const Call& c) {
  const Token& t = c.pos()[0];
  const Token& param = c.pos()[1];
  const Token& value = c.pos()[2];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  auto info = node_.info(*id);
  const os::TaskType* type =
      info && node_.types() != nullptr ? node_.types()->find(info->type) : static_cast<const os::TaskType*>(nullptr);
  // Errors about the parameter's name point at it, errors about its value at the value.
  const Token& culprit = type != nullptr && type->param(param.text) != nullptr ? value : param;
  if (auto st = node_.set_parameter(*id, param.text, value.text); !st)
    return fail(at_column(type == nullptr ? t.column : culprit.column, st.error()));
  return ok("'" + t.text + "' " + param.text + " = " + quote_word(value.text) + " (the task applies it)");
}

Reply Shell::cmd_params(const Call& c) {
  const Token& t = c.pos()[0];
  auto id = task_named(t);
  if (!id) return fail(id.error());
  auto values = node_.parameters(*id);
  if (!values) return fail(at_column(t.column, values.error()));
  auto info = node_.info(*id);
  const os::TaskType* type =
      info && node_.types() != nullptr ? node_.types()->find(info->type) : static_cast<const os::TaskType*>(nullptr);
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& [name, v] : values->values()) {
      j.begin_object().field("name", name).field("type", os::to_string(os::type_of(v)));
      j.field("value", os::format_param_value(v));
      if (const os::ParamSpec* spec = type != nullptr ? type->param(name) : nullptr) {
        j.field("default", os::format_param_value(spec->default_value));
        range_json(j, *spec);
        j.field("doc", spec->doc);
      }
      j.end_object();
    }
    j.end_array();
    return ok(j.str());
  }
  Table table({"PARAM", "KIND", "VALUE", "DEFAULT", "RANGE", "DOC"});
  for (const auto& [name, v] : values->values()) {
    const os::ParamSpec* spec = type != nullptr ? type->param(name) : nullptr;
    table.add({name, os::to_string(os::type_of(v)), os::format_param_value(v),
               spec != nullptr ? os::format_param_value(spec->default_value) : "",
               spec != nullptr ? range_text(*spec) : "", spec != nullptr ? spec->doc : ""});
  }
  return ok(table.str());
}

Reply Shell::cmd_hook(const Call& c) {
  auto sender = task_named(c.pos()[0]);
  if (!sender) return fail(sender.error());
  const bool remote = options_.remote_hook && c.pos()[1].text.find('/') != std::string::npos;
  kernel::Result<os::TaskId> receiver = os::TaskId{};
  if (!remote) receiver = task_named(c.pos()[1]);
  if (!receiver) return fail(receiver.error());
  os::HookOptions o;
  auto priority = c.args.integer("--priority", -kMaxPriority, kMaxPriority);
  if (!priority) return fail(priority.error());
  auto policy = c.args.choice("--policy", kPolicies);
  if (!policy) return fail(policy.error());
  auto port = c.args.integer("--port", 0, 65535);
  if (!port) return fail(port.error());
  auto suppress = c.args.duration("--suppress", kernel::Duration{0}, kMaxWindow);
  if (!suppress) return fail(suppress.error());
  if (*priority) o.priority = static_cast<int>(**priority);
  if (*policy) o.policy = **policy == "refuse" ? os::QueuePolicy::kRefuse : os::QueuePolicy::kKeepNewest;
  if (*port) o.port = static_cast<std::int32_t>(**port);
  if (*suppress) o.suppress_window = **suppress;
  o.enabled = !c.args.has("--disabled");
  if (remote) {
    auto made = options_.remote_hook(node_.name() + "/" + c.pos()[0].text, c.pos()[1].text, o);
    if (!made) return fail(at_column(c.pos()[1].column, made.error()));
    return ok(*made);
  }
  auto id = node_.hook(*sender, *receiver, o);
  if (!id) return fail(at_column(c.pos()[0].column, id.error()));
  return ok("hook " + std::to_string(id->serial) + ": " + c.pos()[0].text + " -> " + c.pos()[1].text);
}

Reply Shell::cmd_unhook(const Call& c) {
  if (c.pos().size() == 1) {
    const Token& t = c.pos()[0];
    if (t.text.empty() || !std::isdigit(static_cast<unsigned char>(t.text[0])))
      return fail(at_column(
          t.column, "expected a hook number ('hooks' lists them) or SENDER RECEIVER, got '" + shorten(t.text) + "'"));
    auto id = hook_numbered(c.pos()[0]);
    if (!id) return fail(id.error());
    if (auto st = node_.unhook(*id); !st) return fail(at_column(c.pos()[0].column, st.error()));
    return ok("removed hook " + std::to_string(id->serial));
  }
  auto sender = task_named(c.pos()[0]);
  if (!sender) return fail(sender.error());
  auto receiver = task_named(c.pos()[1]);
  if (!receiver) return fail(receiver.error());
  std::vector<os::HookId> ids;
  for (const auto& h : node_.hooks())
    if (h.sender == *sender && h.receiver == *receiver) ids.push_back(h.id);
  if (ids.empty())
    return fail(at_column(c.pos()[0].column, "no hook from '" + c.pos()[0].text + "' to '" + c.pos()[1].text + "'"));
  for (const auto& id : ids) (void)node_.unhook(id);
  return ok("removed " + std::to_string(ids.size()) + " hook" + (ids.size() == 1 ? "" : "s") + " from '" +
            c.pos()[0].text + "' to '" + c.pos()[1].text + "'");
}

Reply Shell::cmd_hooks(const Call& c) {
  const auto hooks = node_.hooks();
  const kernel::Time now = node_.now();
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& h : hooks) {
      j.begin_object()
          .field("hook", static_cast<std::uint64_t>(h.id.serial))
          .field("sender", h.sender_name)
          .field("receiver", h.receiver_name)
          .field("priority", h.options.priority)
          .field("policy", os::to_string(h.options.policy));
      j.key("port");
      if (h.options.port >= 0)
        j.value(static_cast<std::int64_t>(h.options.port));
      else
        j.null();
      j.field("suppress_ns", static_cast<std::int64_t>(h.options.suppress_window.count()))
          .field("enabled", h.options.enabled)
          .field("inhibited", h.inhibited_until > now)
          .field("inhibited_until_ns", static_cast<std::int64_t>(h.inhibited_until.count()))
          .end_object();
    }
    j.end_array();
    return ok(j.str());
  }
  Table t({"HOOK", "SENDER", "RECEIVER", "PRIO", "POLICY", "PORT", "SUPPRESS", "STATE", "INHIBITED"});
  for (const auto& h : hooks)
    t.add({std::to_string(h.id.serial), h.sender_name, h.receiver_name, std::to_string(h.options.priority),
           os::to_string(h.options.policy), h.options.port >= 0 ? std::to_string(h.options.port) : "any",
           h.options.suppress_window.count() > 0 ? duration_text(h.options.suppress_window) : "-",
           h.options.enabled ? "enabled" : "disabled",
           h.inhibited_until > now ? os::format_seconds(h.inhibited_until) : "-"});
  if (options_.remote_hooks) return ok(t.str() + "remote hooks:\n" + options_.remote_hooks());
  return ok(t.str());
}

Reply Shell::set_hook_enabled(const Call& c, bool enabled) {
  auto id = hook_numbered(c.pos()[0]);
  if (!id) return fail(id.error());
  if (auto st = node_.set_hook_enabled(*id, enabled); !st) return fail(at_column(c.pos()[0].column, st.error()));
  return ok("hook " + std::to_string(id->serial) + (enabled ? " enabled" : " disabled"));
}

Reply Shell::cmd_enable(const Call& c) { return set_hook_enabled(c, true); }
Reply Shell::cmd_disable(const Call& c) { return set_hook_enabled(c, false); }

Reply Shell::cmd_suppress(const Call& c) {
  auto receiver = task_named(c.pos()[0]);
  if (!receiver) return fail(receiver.error());
  auto level = parse_integer(c.pos()[1], "level", -kMaxPriority, kMaxPriority);
  if (!level) return fail(level.error());
  auto window = parse_duration(c.pos()[2], "duration", kernel::Duration{0}, kMaxWindow);
  if (!window) return fail(window.error());
  if (auto st = node_.suppress(*receiver, static_cast<int>(*level), *window); !st)
    return fail(at_column(c.pos()[0].column, st.error()));
  return ok("hooks below " + std::to_string(*level) + " into '" + c.pos()[0].text + "' suppressed for " +
            duration_text(*window));
}

Reply Shell::cmd_inhibit(const Call& c) {
  auto sender = task_named(c.pos()[0]);
  if (!sender) return fail(sender.error());
  os::TaskId receiver;  // invalid: every receiver
  const bool all = c.pos()[1].text == "*";
  if (!all) {
    auto r = task_named(c.pos()[1]);
    if (!r) return fail(r.error());
    receiver = *r;
  }
  auto window = parse_duration(c.pos()[2], "duration", kernel::Duration{0}, kMaxWindow);
  if (!window) return fail(window.error());
  if (auto st = node_.inhibit(*sender, receiver, *window); !st) return fail(at_column(c.pos()[1].column, st.error()));
  return ok("output of '" + c.pos()[0].text + "' to " +
            (all ? std::string("every receiver") : "'" + c.pos()[1].text + "'") + " inhibited for " +
            duration_text(*window));
}

Reply Shell::cmd_post(const Call& c) {
  auto id = task_named(c.pos()[0]);
  if (!id) return fail(id.error());
  auto port = c.args.integer("--port", 0, 65535);
  if (!port) return fail(port.error());
  std::vector<float> values;
  for (std::size_t k = 1; k < c.pos().size(); ++k) {
    auto v = parse_real(c.pos()[k], "value");
    if (!v) return fail(v.error());
    if (std::fabs(*v) > FLT_MAX) return fail(at_column(c.pos()[k].column, "value: too large for a message (float)"));
    values.push_back(static_cast<float>(*v));
  }
  os::Message m;
  m.port = static_cast<os::Port>(port->value_or(0));
  m.payload = os::Payload(values);
  if (auto st = node_.post(*id, m); !st) return fail(at_column(c.pos()[0].column, st.error()));
  return ok("posted " + std::to_string(values.size()) + " value" + (values.size() == 1 ? "" : "s") + " to '" +
            c.pos()[0].text + "'");
}

Reply Shell::cmd_log(const Call& c) {
  auto level_text = c.args.choice("--level", kLevels);
  if (!level_text) return fail(level_text.error());
  os::LogLevel level = os::LogLevel::kDebug;
  if (*level_text)
    for (std::size_t k = 0; k < std::size(kLevels); ++k)
      if (kLevels[k] == **level_text) level = static_cast<os::LogLevel>(k);
  std::size_t count = kDefaultLogLines;
  if (!c.pos().empty()) {
    const Token& t = c.pos()[0];
    if (t.text == "follow" || t.text == "stop") {
      if (c.json()) return fail(at_column(t.column, "'log " + t.text + "' prints no JSON"));
      if (t.text == "stop") {
        const bool was = following_;
        following_ = false;
        return ok(was ? "stopped following the log" : "not following the log");
      }
      if (*level_text == std::nullopt && following_) return ok("already following the log");
      following_ = true;
      follow_level_ = level;
      follow_seq_ = node_.log().last_seq();
      return ok("following the log ('log stop' ends it)");
    }
    if (t.text.empty() || !std::isdigit(static_cast<unsigned char>(t.text[0])))
      return fail(at_column(t.column, "expected a count, 'follow' or 'stop', got '" + shorten(t.text) + "'"));
    auto n = parse_integer(t, "count", 1, 100000);
    if (!n) return fail(n.error());
    count = static_cast<std::size_t>(*n);
  }
  auto entries = node_.log().since(0);
  std::erase_if(entries, [&](const os::LogEntry& e) { return e.level < level; });
  if (entries.size() > count) entries.erase(entries.begin(), entries.end() - static_cast<std::ptrdiff_t>(count));
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& e : entries)
      j.begin_object()
          .field("seq", e.seq)
          .field("time_ns", static_cast<std::int64_t>(e.time.count()))
          .field("level", os::to_string(e.level))
          .field("source", e.source)
          .field("text", e.text)
          .end_object();
    j.end_array();
    return ok(j.str());
  }
  Table t({"SEQ", "TIME", "LEVEL", "SOURCE", "TEXT"});
  for (const auto& e : entries)
    t.add({std::to_string(e.seq), os::format_seconds(e.time), os::to_string(e.level), e.source, e.text});
  return ok(t.str());
}

std::string Shell::follow_output(std::size_t max) {
  if (!following_) return {};
  std::string out;
  const auto entries = node_.log().since(follow_seq_, max);
  if (!entries.empty() && entries.front().seq > follow_seq_ + 1)
    out += "(" + std::to_string(entries.front().seq - follow_seq_ - 1) + " log entries were lost)\n";
  for (const auto& e : entries) {
    follow_seq_ = e.seq;
    if (e.level >= follow_level_) out += os::format_log_entry(e) + "\n";
  }
  return out;
}

Reply Shell::cmd_devices(const Call& c) {
  std::vector<std::pair<std::string, std::shared_ptr<io::Device>>> devices;
  if (options_.devices)
    for (const auto& [n, d] : *options_.devices)
      if (d) devices.emplace_back(n, d);
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& [n, d] : devices)
      j.begin_object()
          .field("name", n)
          .field("open", d->is_open())
          .field("ioctls", static_cast<std::uint64_t>(d->ioctls().size()))
          .end_object();
    j.end_array();
    return ok(j.str());
  }
  Table t({"NAME", "OPEN", "IOCTLS"});
  for (const auto& [n, d] : devices) t.add({n, d->is_open() ? "yes" : "no", std::to_string(d->ioctls().size())});
  return ok(t.str());
}

Reply Shell::cmd_ioctls(const Call& c) {
  auto device = device_named(c.pos()[0]);
  if (!device) return fail(device.error());
  const auto specs = (*device)->ioctls();
  if (c.json()) {
    JsonWriter j;
    j.begin_array();
    for (const auto& s : specs) {
      j.begin_object().field("name", s.name);
      j.key("arg");
      if (s.arg) {
        j.begin_object().field("type", os::to_string(s.arg->type));
        range_json(j, *s.arg);
        j.field("doc", s.arg->doc).end_object();
      } else {
        j.null();
      }
      j.field("doc", s.doc).end_object();
    }
    j.end_array();
    return ok(j.str());
  }
  Table t({"COMMAND", "ARG", "RANGE", "DOC"});
  for (const auto& s : specs)
    t.add({s.name, s.arg ? os::to_string(s.arg->type) : "-", s.arg ? range_text(*s.arg) : "", s.doc});
  return ok(t.str());
}

Reply Shell::cmd_ioctl(const Call& c) {
  auto device = device_named(c.pos()[0]);
  if (!device) return fail(device.error());
  const Token& command = c.pos()[1];
  const Token* arg = c.pos().size() > 2 ? &c.pos()[2] : nullptr;
  bool known = false;
  for (const auto& s : (*device)->ioctls()) known = known || s.name == command.text;
  auto answer = (*device)->ioctl(command.text, arg != nullptr ? std::string_view(arg->text) : std::string_view());
  if (!answer) return fail(at_column(known && arg != nullptr ? arg->column : command.column, answer.error()));
  return ok(answer->empty() ? std::string("ok") : *answer);
}

Reply Shell::cmd_load(const Call& c) {
  const Token& path = c.pos()[0];
  if (!options_.load_plugin) return fail(at_column(path.column, "this shell cannot load plugins"));
  if (auto st = options_.load_plugin(path.text); !st) return fail(at_column(path.column, st.error()));
  return ok("loaded " + path.text + "\n");
}

Reply Shell::cmd_run(const Call& c) {
  const Token& file = c.pos()[0];
  if (depth_ >= options_.max_script_depth)
    return fail(
        at_column(file.column, "scripts nest more than " + std::to_string(options_.max_script_depth) + " deep"));
  std::string text;
  if (options_.read_file) {
    auto r = options_.read_file(file.text);
    if (!r) return fail(at_column(file.column, "cannot read '" + shorten(file.text, 200) + "': " + r.error()));
    text = std::move(r).value();
  } else {
    std::string error;
    text = read_regular_file(file.text, error);
    if (!error.empty()) return fail(at_column(file.column, "cannot read '" + shorten(file.text, 200) + "': " + error));
  }
  std::string out;
  std::size_t line_no = 0;
  std::size_t at = 0;
  script_exit_ = false;
  if (depth_ == 0) script_lines_ = 0;
  while (at < text.size() && !script_exit_) {
    const std::size_t nl = text.find('\n', at);
    std::string_view line = std::string_view(text).substr(at, nl == std::string::npos ? std::string::npos : nl - at);
    at = nl == std::string::npos ? text.size() : nl + 1;
    ++line_no;
    if (++script_lines_ > options_.max_script_lines)
      return fail(shorten(file.text, 200) + ":" + std::to_string(line_no) + ": scripts ran more than " +
                  std::to_string(options_.max_script_lines) + " lines: stopped");
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    Reply r = run_line(line, depth_ + 1);
    if (!r.ok) {
      // The lines before took effect (a script is not a transaction); the reply is the error.
      script_exit_ = false;
      std::string msg = r.text;
      if (msg.starts_with("error: ")) msg.erase(0, 7);
      return {false, "error: " + shorten(file.text, 200) + ":" + std::to_string(line_no) + ": " + msg};
    }
    out += r.text;
  }
  script_exit_ = false;
  return ok(out + "ran " + std::to_string(line_no) + " line" + (line_no == 1 ? "" : "s") + " of '" +
            shorten(file.text, 200) + "'");
}

Reply Shell::cmd_time(const Call& c) {
  const kernel::Time now = node_.now();
  if (c.json()) {
    JsonWriter j;
    j.begin_object()
        .field("node", node_.name())
        .field("time_s", kernel::to_seconds(now))
        .field("time_ns", static_cast<std::int64_t>(now.count()))
        .end_object();
    return ok(j.str());
  }
  Table t({"NODE", "TIME", "NS"});
  t.add({node_.name(), os::format_seconds(now), std::to_string(now.count())});
  return ok(t.str());
}

Reply Shell::cmd_exit(const Call&) {
  if (depth_ > 0) {
    script_exit_ = true;
    return {true, ""};
  }
  exit_requested_ = true;
  return ok("bye");
}

}  // namespace symb::shell
