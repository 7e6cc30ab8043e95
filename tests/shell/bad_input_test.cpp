// Bad input never hurts a node: 10,000 random and malformed lines (seeded, so a failure replays)
// each give an error with a message, the node's tasks keep running, and its tasks and hooks are
// exactly as they were.
#include <algorithm>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/shell.hpp"
#include "symb/shell/shell_task.hpp"

#include "shell_test_support.hpp"

namespace symb::shell {
namespace {

using namespace std::chrono_literals;

struct Snapshot {
  std::vector<std::tuple<std::string, os::TaskState, int, std::int64_t, std::size_t, std::string>> tasks;
  std::vector<
      std::tuple<std::uint32_t, std::string, std::string, int, int, std::int32_t, std::int64_t, bool, std::int64_t>>
      hooks;
  std::vector<std::pair<std::string, std::string>> params;
  bool operator==(const Snapshot&) const = default;
};

Snapshot snapshot(const os::Node& node) {
  Snapshot s;
  for (const auto& t : node.tasks()) {
    s.tasks.emplace_back(t.name, t.state, t.priority, t.period.count(), t.queue_capacity, t.type);
    if (auto p = node.parameters(t.id))
      for (const auto& [n, v] : p->values()) s.params.emplace_back(t.name + "." + n, os::format_param_value(v));
  }
  for (const auto& h : node.hooks())
    s.hooks.emplace_back(h.id.serial, h.sender_name, h.receiver_name, h.options.priority,
                         static_cast<int>(h.options.policy), h.options.port, h.options.suppress_window.count(),
                         h.options.enabled, h.inhibited_until.count());
  return s;
}

class LineMaker {
 public:
  explicit LineMaker(std::uint64_t seed) : rng_(seed, 42) {}

  std::string next() {
    switch (rng_.below(14)) {
      case 0: return random_bytes();
      case 1: return overlong();
      case 2: return unknown_command();
      case 3: return pick(kWrongArity);
      case 4: return pick(kBadNumbers);
      case 5: return pick(kBadDurations);
      case 6: return pick(kUnknownNames);
      case 7: return binary_garbage();
      case 8: return unterminated();
      case 9: return valid_with_bad_option();
      case 10: return pick(kBadCreates);
      case 11: return with_control_char();
      case 12: return invalid_utf8();
      default: return pick(kMisc);
    }
  }

 private:
  static constexpr const char* kWrongArity[] = {"suspend",
                                                "suspend e1 s1",
                                                "resume",
                                                "delete",
                                                "delete e1 e1",
                                                "priority e1",
                                                "priority",
                                                "priority e1 1 2",
                                                "period e1",
                                                "set e1 value",
                                                "set e1",
                                                "params",
                                                "hook e1",
                                                "hook",
                                                "hook e1 s1 s1",
                                                "unhook",
                                                "unhook 1 2 3",
                                                "enable",
                                                "disable 1 2",
                                                "suppress s1 1",
                                                "inhibit e1 s1",
                                                "post",
                                                "ioctl uart1",
                                                "ioctls",
                                                "run",
                                                "run a b",
                                                "time now",
                                                "tasks all",
                                                "types x",
                                                "hooks 1",
                                                "devices x",
                                                "exit now",
                                                "quit 1",
                                                "help a b",
                                                "log 1 2",
                                                "create",
                                                "create emitter",
                                                "ioctl uart1 baud 1 2"};
  static constexpr const char* kBadNumbers[] = {"priority e1 abc",
                                                "priority e1 1e9",
                                                "priority e1 9999999999999999999999",
                                                "priority e1 1.5",
                                                "priority e1 +3",
                                                "post s1 1 x",
                                                "post s1 nan",
                                                "post s1 inf",
                                                "post s1 1e39",
                                                "post s1 --port -1",
                                                "post s1 --port 65536",
                                                "suppress s1 x 10ms",
                                                "suppress s1 1001 10ms",
                                                "log -5",
                                                "log 0",
                                                "log 1000001",
                                                "log x5",
                                                "hook e1 s1 --port 70000",
                                                "hook e1 s1 --priority many",
                                                "create emitter z --queue 0",
                                                "create emitter z --queue 100000",
                                                "create emitter z --priority 1e3x",
                                                "unhook 0",
                                                "unhook -1",
                                                "unhook 1.5",
                                                "enable 99999999999",
                                                "disable x",
                                                "ioctl uart1 baud abc",
                                                "ioctl uart1 baud 1",
                                                "ioctl uart1 baud 1e12",
                                                "create emitter z value=1e7",
                                                "create emitter z value=0x10",
                                                "create sink z gain=-1",
                                                "create sink z gain=1.5"};
  static constexpr const char* kBadDurations[] = {"period e1 10",
                                                  "period e1 -5ms",
                                                  "period e1 10 parsecs",
                                                  "period e1 1ns",
                                                  "period e1 999us",
                                                  "period e1 ms",
                                                  "period e1 50h",
                                                  "period e1 2000min",
                                                  "period e1 5 h",
                                                  "period e1 1d",
                                                  "inhibit e1 s1 forever",
                                                  "inhibit e1 s1 -1s",
                                                  "suppress s1 1 1e30s",
                                                  "hook e1 s1 --suppress 5xs",
                                                  "hook e1 s1 --suppress",
                                                  "create emitter z --period fast",
                                                  "create emitter z --period 10",
                                                  "inhibit e1 * 48h",
                                                  "suppress s1 0 10 ms"};
  static constexpr const char* kUnknownNames[] = {"suspend nosuch",
                                                  "resume e2",
                                                  "delete s2",
                                                  "priority x 1",
                                                  "period x 1s",
                                                  "set e1 nosuch 1",
                                                  "set e1 value abc",
                                                  "set s1 value 1",
                                                  "set nosuch value 1",
                                                  "params nosuch",
                                                  "ioctl nodev x",
                                                  "ioctl uart1 nosuch",
                                                  "ioctls nodev",
                                                  "unhook 999",
                                                  "enable 999",
                                                  "disable 2",
                                                  "unhook e1 nosuch",
                                                  "unhook s1 e1",
                                                  "inhibit s1 e1 1s",
                                                  "inhibit s1 * 1s",
                                                  "hook e1 nosuch",
                                                  "hook nosuch s1",
                                                  "suppress nosuch 1 1s",
                                                  "post nosuch 1",
                                                  "run nosuch",
                                                  "help nosuch",
                                                  "create nosuch z",
                                                  "create emiter z",
                                                  "set e1 label 012345678901234567890123456789012",
                                                  "set e1 loud maybe",
                                                  "resume e1",
                                                  "suspend s1x"};
  static constexpr const char* kBadCreates[] = {
      "create emitter e1",
      "create emitter s1",
      "create emitter 9z",
      "create emitter z!",
      "create emitter z value",
      "create emitter z =1",
      "create emitter z value=abc",
      "create emitter z value=1 value=2",
      "create emitter z nosuch=1",
      "create emitter z loud=perhaps",
      "create emitter z \"value\"",
      "create emitter z --suspended=yes",
      "create emitter z --bogus",
      "create emitter z --period",
      "create emitter nnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnn",
      "create sink z gain=101"};
  static constexpr const char* kMisc[] = {"log follow --json",
                                          "log stop --json",
                                          "tasks --json --json",
                                          "hooks --jsn",
                                          "tasks -- x",
                                          "help --json x y",
                                          "types --json=1",
                                          "devices --verbose",
                                          "-- tasks",
                                          "--json",
                                          "'tasks' x",
                                          "\"\"",
                                          "'' x",
                                          "log --level loud",
                                          "log follow --level",
                                          "hook e1 s1 --policy newest",
                                          "hook e1 s1 --policy",
                                          "hook e1 s1 --disabled --disabled",
                                          "run /",
                                          "run /nonexistent/dir/x.symb",
                                          "ioctl uart1 info extra",
                                          "ioctl uart1 baud",
                                          "ioctl uart1 flush 1"};

  template <std::size_t N>
  std::string pick(const char* const (&list)[N]) {
    return list[rng_.below(N)];
  }
  std::string random_bytes() {
    std::string s(1 + rng_.below(200), '\0');
    for (char& c : s) c = static_cast<char>(rng_.below(256));
    // Made certainly invalid: a control byte somewhere.
    s[rng_.below(s.size())] = static_cast<char>(1 + rng_.below(8));
    return s;
  }
  std::string overlong() {
    std::string s = "tasks ";
    const std::size_t n = kMaxLineBytes + 1 + rng_.below(6000);
    while (s.size() < n) s.push_back(static_cast<char>('a' + rng_.below(26)));
    return s;
  }
  std::string unknown_command() {
    std::string w;
    for (;;) {
      w.clear();
      const std::size_t n = 1 + rng_.below(10);
      for (std::size_t i = 0; i < n; ++i) w.push_back(static_cast<char>('a' + rng_.below(26)));
      bool known = false;
      for (const auto& c : Shell::commands()) known = known || c.name == w;
      if (!known) break;
    }
    return w + " e1 s1 " + std::to_string(rng_.below(100));
  }
  std::string binary_garbage() {
    std::string s = pick(kMisc);
    s.insert(rng_.below(s.size() + 1), std::string("\0\xff\x80\x1b", 4));
    return s;
  }
  std::string unterminated() {
    static constexpr const char* kOpen[] = {
        "create emitter \"abc",       "post s1 'x", "set e1 label \"a\\\"", "\"", "'", "tasks \"--json",
        "hook e1 s1 --policy 'refuse"};
    return pick(kOpen);
  }
  std::string valid_with_bad_option() {
    static constexpr const char* kValid[] = {"tasks", "hooks",      "types",     "devices",     "time",
                                             "log 3", "help tasks", "params e1", "ioctls uart1"};
    return pick(kValid) + std::string(" --bogus") + std::to_string(rng_.below(1000));
  }
  std::string with_control_char() {
    static constexpr const char* kValid[] = {"create sink zz", "suspend e1", "delete s1", "unhook 1", "priority e1 5"};
    std::string s = pick(kValid);
    static constexpr char kControl[] = {'\x01', '\x07', '\x08', '\n', '\r', '\x1b', '\x7f', '\0'};
    s.insert(rng_.below(s.size() + 1), 1, kControl[rng_.below(sizeof kControl)]);
    return s;
  }
  std::string invalid_utf8() {
    static constexpr const char* kBad[] = {"\xc0\xaf", "\xed\xa0\x80", "\xf8\x88\x80\x80\x80", "\xc3", "\x80", "\xfe"};
    static constexpr const char* kValid[] = {"create sink zz", "suspend e1", "delete s1", "post s1 1 2"};
    std::string s = pick(kValid);
    s.insert(rng_.below(s.size() + 1), pick(kBad));
    return s;
  }

  kernel::RandomStream rng_;
};

TEST(ShellBadInput, TenThousandBadLinesChangeNothing) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  testing::add_test_types(types);
  os::Node node(ex, {"board", 3, 256, &types});
  auto devices = std::make_shared<DeviceTable>();
  (*devices)["uart1"] = std::make_shared<testing::TestDevice>("uart1");
  Shell::Options options;
  options.devices = devices;
  Shell shell(node, options);

  ASSERT_TRUE(shell.execute("create emitter e1 value=3 --period 10ms").ok);
  ASSERT_TRUE(shell.execute("create sink s1").ok);
  ASSERT_TRUE(shell.execute("create sink quiet --suspended").ok);
  ASSERT_TRUE(shell.execute("hook e1 s1 --priority 1").ok);
  ex.run_for(50ms);
  const Snapshot before = snapshot(node);
  const auto in_before = node.info(*node.find("s1"))->traffic.delivered;
  ASSERT_GT(in_before, 0u);

  LineMaker maker(20240611);
  std::map<std::string, int> first_words;
  for (int i = 0; i < 10000; ++i) {
    const std::string line = maker.next();
    const Reply r = shell.execute(line);
    ASSERT_FALSE(r.ok) << "line " << i << " was accepted: '" << line << "' -> " << r.text;
    ASSERT_TRUE(r.text.starts_with("error: ")) << r.text;
    ASSERT_TRUE(r.text.ends_with('\n'));
    ASSERT_GT(r.text.size(), 12u) << "no message for '" << line << "'";
    ASSERT_EQ(r.text.find('\n'), r.text.size() - 1) << "a one-line error: " << r.text;
    ASSERT_LE(r.text.size(), 1024u) << "an error does not echo a whole line back";
    if (i % 100 == 0) ex.run_for(10ms);  // the node keeps running between the lines
    ++first_words[r.text.substr(7, std::min<std::size_t>(12, r.text.size() - 8))];
  }
  ex.run_for(50ms);
  EXPECT_EQ(snapshot(node), before);
  EXPECT_GE(node.info(*node.find("s1"))->traffic.delivered, in_before + 100);  // it kept ticking
  EXPECT_EQ(node.info(*node.find("e1"))->state, os::TaskState::kRunning);
  EXPECT_FALSE(shell.exit_requested());
  EXPECT_FALSE(shell.following());
  EXPECT_GT(first_words.size(), 5u);  // the errors came from many places, not one early check
  if (::testing::Test::HasFailure())
    for (const auto& [w, n] : first_words) std::printf("%6d  %s\n", n, w.c_str());
}

TEST(ShellBadInput, BadBytesThroughTheShellTaskAreErrorsToo) {
  // The same over a session: a plain-mode shell fed 300 lines of random bytes, cut into chunks at
  // random places (so lines straddle chunks), answers each line with one error line, and its node
  // is as it was. The lines hold any byte but the line ends (CR, LF, NUL), telnet's IAC (which
  // would switch the editor to terminal mode) and '#' (a comment) at the start; each has a control
  // byte somewhere, so none is a command.
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  testing::add_test_types(types);
  os::Node node(ex, {"board", 3, 256, &types});
  auto link = io::make_loopback_pair("link");
  auto session = attach_shell(node, std::move(link.first), ShellOptions{}, "sh");
  const std::unique_ptr<io::IOStream> theirs = std::move(link.second);
  ASSERT_TRUE(session) << session.error();
  ASSERT_TRUE(node.create("sink", "s1", {}));
  ex.run_for(1ms);
  const Snapshot before = snapshot(node);

  kernel::RandomStream rng(99, 1);
  constexpr int kLines = 300;
  std::string input;
  for (int i = 0; i < kLines; ++i) {
    std::string line(1 + rng.below(600), '\0');
    for (char& c : line) {
      unsigned char b = 0;
      while (b == 0 || b == '\r' || b == '\n' || b == 0xff) b = static_cast<unsigned char>(rng.below(256));
      c = static_cast<char>(b);
    }
    if (line[0] == '#') line[0] = 'x';
    line[rng.below(line.size())] = static_cast<char>(1 + rng.below(8));  // a control byte, never a line end
    input += line + "\n";
  }

  std::string replies;
  auto read_replies = [&] {
    std::byte buf[4096];
    for (;;) {
      auto n = theirs->read_some(buf, kernel::Duration{0});
      if (!n || *n == 0) return;
      replies.append(reinterpret_cast<const char*>(buf), *n);
    }
  };
  for (std::size_t at = 0; at < input.size();) {
    const std::size_t n = std::min<std::size_t>(input.size() - at, 1 + rng.below(700));
    ASSERT_TRUE(theirs->write_all(io::as_bytes(std::string_view(input).substr(at, n))));
    at += n;
    ex.run_for(1ms);
    read_replies();
  }
  for (int i = 0; i < 100 && std::count(replies.begin(), replies.end(), '\n') < kLines; ++i) {
    ex.run_for(1ms);
    read_replies();
  }

  std::vector<std::string> lines;
  for (std::size_t at = 0; at < replies.size();) {
    const std::size_t end = replies.find('\n', at);
    ASSERT_NE(end, std::string::npos) << "a reply without its line end: " << replies.substr(at);
    lines.push_back(replies.substr(at, end - at));
    at = end + 1;
  }
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(kLines)) << "one reply per line sent";
  for (const std::string& r : lines) {
    EXPECT_TRUE(r.starts_with("error: ")) << r;
    EXPECT_GT(r.size(), 12u) << "no message: " << r;
    EXPECT_LE(r.size(), 1024u) << "an error does not echo a whole line back";
  }
  EXPECT_EQ(node.info(session->shell)->state, os::TaskState::kRunning);
  EXPECT_EQ(snapshot(node), before);
}

}  // namespace
}  // namespace symb::shell
