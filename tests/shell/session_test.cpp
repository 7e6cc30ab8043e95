// Scripted shell sessions over real I/O: a pseudo-terminal (the shell on the slave end through a
// StreamTask, the test typing at the master as a person would) and TCP (TcpShellServer with a
// token). Each command's effect is checked on the node itself. The thread executor runs these
// (real time, real threads); every wait has a deadline and none is a fixed sleep.
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/loopback_stream.hpp"
#include "symb/io/pty_pair.hpp"
#include "symb/io/stdio_stream.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/io/tcp_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/shell_task.hpp"
#include "symb/shell/tcp_shell.hpp"

#include "shell_test_support.hpp"
#include "support/eventually.hpp"

namespace symb::shell {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;
using testing::Json;
using testing::JsonParser;

constexpr auto kDeadline = 10s;

// The far end of a session: what a person or a script sees and types.
class Peer {
 public:
  // `pump` runs between reads (a virtual-time executor must be driven; real time needs nothing).
  Peer(std::shared_ptr<io::IOStream> stream, bool terminal, std::function<void()> pump = {})
      : stream_(std::move(stream)), terminal_(terminal), pump_(std::move(pump)) {}

  void type(std::string_view text) { ASSERT_TRUE(stream_->write_all(io::as_bytes(text))); }

  // Reads until `needle` shows up; returns everything up to and including it (and keeps the
  // rest), or nothing at the deadline or the end of the stream.
  std::optional<std::string> until(std::string_view needle) {
    const auto end = std::chrono::steady_clock::now() + kDeadline;
    for (;;) {
      if (auto at = seen_.find(needle); at != std::string::npos) {
        std::string out = seen_.substr(0, at + needle.size());
        seen_.erase(0, at + needle.size());
        return out;
      }
      if (std::chrono::steady_clock::now() > end || !read_more()) return std::nullopt;
    }
  }

  // Sends a command line and returns its reply: in terminal mode the text between the echoed line
  // and the next prompt (with "\r\n" back to "\n"); in plain mode one line.
  std::string command(const std::string& line) {
    type(line + (terminal_ ? "\r" : "\n"));
    if (!terminal_) return until("\n").value_or("<no reply>");
    auto echoed = until(line + "\r\n");
    if (!echoed) return "<no echo>";
    auto reply = until("symb> ");
    if (!reply) return "<no prompt>";
    std::string text = reply->substr(0, reply->size() - 6);
    std::string out;
    for (char c : text)
      if (c != '\r') out += c;
    return out;
  }

  // True once the other end closed the stream (within the deadline).
  bool closed() {
    const auto end = std::chrono::steady_clock::now() + kDeadline;
    while (std::chrono::steady_clock::now() < end)
      if (!read_more()) return true;
    return false;
  }

 private:
  bool read_more() {
    if (pump_) pump_();
    std::byte buf[4096];
    auto n = stream_->read_some(buf, pump_ ? 1ms : 20ms);
    if (!n) return false;
    seen_.append(reinterpret_cast<const char*>(buf), *n);
    return true;
  }

  std::shared_ptr<io::IOStream> stream_;
  bool terminal_;
  std::function<void()> pump_;
  std::string seen_;
};

double json_in(Peer& peer, const std::string& task) {
  const std::string text = peer.command("tasks --json");
  auto j = JsonParser::parse(text);
  EXPECT_TRUE(j) << "not JSON: " << text;
  if (!j) return -1;
  for (const auto& t : j->array())
    if (t["name"].string() == task) return t["in"].number();
  return -1;
}

double json_out(Peer& peer, const std::string& task) {
  auto j = JsonParser::parse(peer.command("tasks --json"));
  if (!j) return -1;
  for (const auto& t : j->array())
    if (t["name"].string() == task) return t["out"].number();
  return -1;
}

// The session every transport runs: two tasks from registered types, hooked; messages flow;
// suspend, resume, delete; each step checked on the node.
void run_scenario(os::Node& node, Peer& peer) {
  EXPECT_NE(peer.command("create emitter src --period 5ms").find("created 'src'"), std::string::npos);
  EXPECT_NE(peer.command("create sink dst").find("created 'dst'"), std::string::npos);
  const auto src = node.find("src");
  const auto dst = node.find("dst");
  ASSERT_TRUE(src && dst);
  EXPECT_EQ(node.info(*src)->type, "emitter");
  EXPECT_EQ(node.info(*src)->period, 5ms);

  EXPECT_NE(peer.command("hook src dst").find(": src -> dst"), std::string::npos);
  bool hooked = false;
  for (const auto& h : node.hooks()) hooked = hooked || (h.sender == *src && h.receiver == *dst);
  EXPECT_TRUE(hooked);

  // Messages flow: the receiver's in-count, as the shell reports it, grows.
  double in = 0;
  EXPECT_TRUE(eventually([&] { return (in = json_in(peer, "dst")) >= 5; })) << in;
  EXPECT_GE(static_cast<double>(node.info(*dst)->traffic.delivered), in);

  EXPECT_EQ(peer.command("suspend src"), "suspended 'src'\n");
  EXPECT_EQ(node.info(*src)->state, os::TaskState::kSuspended);
  const double sent = json_out(peer, "src");
  EXPECT_EQ(json_out(peer, "src"), sent);  // a suspended task sends nothing more

  EXPECT_EQ(peer.command("resume src"), "resumed 'src'\n");
  EXPECT_EQ(node.info(*src)->state, os::TaskState::kRunning);
  const double in_before = json_in(peer, "dst");
  EXPECT_TRUE(eventually([&] { return json_in(peer, "dst") > in_before; }));

  EXPECT_EQ(peer.command("delete src"), "deleted 'src'\n");
  EXPECT_FALSE(node.find("src"));
  for (const auto& h : node.hooks()) EXPECT_NE(h.sender_name, "src");
  EXPECT_NE(peer.command("suspend src").find("error: column 9: node 'board' has no task 'src'"), std::string::npos);
}

struct Board {
  Board() {
    testing::add_test_types(types);
    node = std::make_unique<os::Node>(ex, os::NodeConfig{"board", 5, 256, &types});
  }
  ~Board() { node.reset(); }
  kernel::ThreadExecutor ex;
  os::TaskTypeRegistry types;
  std::unique_ptr<os::Node> node;
};

// A script piped in (a file, `printf ... |`): the input ends right after the last line, which has
// no newline. Every line runs, the replies still go out, then the session ends by itself.
TEST(ShellSession, InputThatEndsRunsEveryLineThenEndsTheSession) {
  Board b;
  int in[2], out[2];
  ASSERT_EQ(::pipe2(in, O_CLOEXEC), 0);
  ASSERT_EQ(::pipe2(out, O_CLOEXEC), 0);
  const std::string script = "create sink piped1\ncreate sink piped2\ntime";
  ASSERT_EQ(::write(in[1], script.data(), script.size()), static_cast<ssize_t>(script.size()));
  ::close(in[1]);
  auto stream = std::make_shared<io::StdioStream>("pipe", in[0], out[1]);
  auto session = attach_shell(*b.node, stream, ShellOptions{}, "script");
  ASSERT_TRUE(session) << session.error();
  EXPECT_TRUE(eventually([&] { return !b.node->find("script") && !b.node->find("script.io"); }));
  EXPECT_TRUE(b.node->find("piped1") && b.node->find("piped2"));
  std::string replies;
  char buf[4096];
  for (ssize_t n; (n = ::read(out[0], buf, sizeof buf)) > 0;) {
    replies.append(buf, static_cast<std::size_t>(n));
    if (replies.find("NODE") != std::string::npos && replies.ends_with("\n") &&
        replies.find("board ") != std::string::npos)
      break;
  }
  EXPECT_NE(replies.find("created 'piped1'"), std::string::npos) << replies;
  EXPECT_NE(replies.find("created 'piped2'"), std::string::npos) << replies;
  EXPECT_NE(replies.find("NODE"), std::string::npos) << replies;  // `time`, the line without a newline
  bool said = false;
  for (const auto& e : b.node->log().since(0))
    said = said || e.text.find("end of input: the session ends") != std::string::npos;
  EXPECT_TRUE(said);
  for (int fd : {in[0], out[0], out[1]}) ::close(fd);
}

TEST(ShellSession, OverAPseudoTerminal) {
  Board b;
  auto pty = io::PtyPair::open("pty");
  ASSERT_TRUE(pty) << pty.error();
  ShellOptions o;
  o.terminal = true;
  o.close_on_exit = false;  // a serial console stays
  auto session = attach_shell(*b.node, pty->slave, o, "console");
  ASSERT_TRUE(session) << session.error();
  Peer user(pty->master, true);
  auto hello = user.until("symb> ");
  ASSERT_TRUE(hello);
  EXPECT_NE(hello->find("Symbricator shell on node 'board'"), std::string::npos);

  run_scenario(*b.node, user);

  // Line editing as a person types: a typo fixed with backspace and arrows, then history.
  user.type("tasjs\x7f\x7fks --jsn\x1b[Do\r");
  ASSERT_TRUE(user.until("\r\n"));  // the redraws before Enter show the prompt too
  auto fixed = user.until("symb> ");
  ASSERT_TRUE(fixed);
  EXPECT_NE(fixed->find("\"name\":\"dst\""), std::string::npos) << ::testing::PrintToString(*fixed);
  user.type("\x1b[A\r");  // up: the same command again
  ASSERT_TRUE(user.until("\r\n"));
  auto again = user.until("symb> ");
  ASSERT_TRUE(again);
  EXPECT_NE(again->find("\"name\":\"dst\""), std::string::npos);

  // The session cannot saw off its own branch.
  EXPECT_NE(user.command("delete console.io").find("carries this shell session"), std::string::npos);
  EXPECT_TRUE(b.node->find("console.io"));
  // exit on a console keeps the console (no token: a new prompt comes).
  EXPECT_EQ(user.command("exit"), "bye\n");
  EXPECT_TRUE(b.node->find("console"));
  EXPECT_EQ(user.command("time").substr(0, 4), "NODE");
}

TEST(ShellSession, OverTcpWithAToken) {
  Board b;
  TcpShellOptions so;
  so.token = "open-sesame";
  auto server = TcpShellServer::start(*b.node, so);
  ASSERT_TRUE(server) << server.error();
  ASSERT_NE((*server)->port(), 0);
  EXPECT_EQ((*server)->token(), "open-sesame");

  auto conn = io::TcpStream::connect("127.0.0.1", (*server)->port());
  ASSERT_TRUE(conn) << conn.error();
  Peer script(std::shared_ptr<io::IOStream>(std::move(conn).value()), false);
  script.type("open-sesame\n");
  // The session's tasks exist before their hooks are made (attach_shell creates, hooks, then
  // starts them): wait for the hooks themselves, not for the tasks.
  const auto hooked_both_ways = [&] {
    const auto shell = b.node->find("shell1");
    const auto io = b.node->find("shell1.io");
    if (!shell || !io) return false;
    std::size_t both_ways = 0;
    for (const auto& h : b.node->hooks())
      both_ways += (h.sender == *shell && h.receiver == *io) || (h.sender == *io && h.receiver == *shell);
    return both_ways == 2;
  };
  ASSERT_TRUE(eventually(hooked_both_ways));

  run_scenario(*b.node, script);

  // A second client with the wrong token gets nothing done and is closed after three tries.
  auto bad_conn = io::TcpStream::connect("127.0.0.1", (*server)->port());
  ASSERT_TRUE(bad_conn);
  Peer intruder(std::shared_ptr<io::IOStream>(std::move(bad_conn).value()), false);
  EXPECT_EQ(intruder.command("guess"), "error: access denied\n");
  EXPECT_EQ(intruder.command("create sink hacked"), "error: access denied\n");
  EXPECT_EQ((*server)->session_count(), 2u);
  EXPECT_EQ(intruder.command("tasks"), "error: access denied; closing\n");
  EXPECT_TRUE(intruder.closed());
  EXPECT_FALSE(b.node->find("hacked"));
  EXPECT_TRUE(eventually([&] { return !b.node->find("shell2") && !b.node->find("shell2.io"); }));
  EXPECT_TRUE(eventually([&] { return (*server)->session_count() == 1; }));

  // The first session still works; exit ends it and closes the connection.
  EXPECT_EQ(script.command("time").substr(0, 4), "NODE");  // a table: its header line,
  EXPECT_EQ(script.until("\n")->substr(0, 6), "board ");   // then its row
  EXPECT_EQ(script.command("exit"), "bye\n");
  EXPECT_TRUE(script.closed());
  EXPECT_TRUE(eventually([&] { return !b.node->find("shell1") && !b.node->find("shell1.io"); }));
  EXPECT_TRUE(eventually([&] { return (*server)->session_count() == 0; }));
}

TEST(ShellSession, TcpSessionsAtOnceAndClientsThatLeave) {
  Board b;
  TcpShellOptions so;  // a random token
  auto server = TcpShellServer::start(*b.node, so);
  ASSERT_TRUE(server) << server.error();
  const std::string token = (*server)->token();
  ASSERT_EQ(token.size(), 16u);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos);

  std::vector<std::unique_ptr<Peer>> peers;
  std::vector<std::shared_ptr<io::IOStream>> streams;
  for (int i = 0; i < 3; ++i) {
    auto c = io::TcpStream::connect("127.0.0.1", (*server)->port());
    ASSERT_TRUE(c) << c.error();
    streams.push_back(std::shared_ptr<io::IOStream>(std::move(c).value()));
    peers.push_back(std::make_unique<Peer>(streams.back(), false));
    peers.back()->type(token + "\n");
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string name = "from" + std::to_string(i);
    const std::string reply = peers[i]->command("create sink " + name);
    EXPECT_TRUE(reply.starts_with("created '" + name + "' (sink, #")) << reply;
    EXPECT_TRUE(b.node->find(name));
  }
  EXPECT_EQ((*server)->session_count(), 3u);
  for (const char* name : {"shell1", "shell2", "shell3"}) EXPECT_TRUE(b.node->find(name)) << name;

  // A client that just goes away takes its session with it.
  streams[1]->close();
  EXPECT_TRUE(eventually([&] { return !b.node->find("shell2") && !b.node->find("shell2.io"); }));
  EXPECT_TRUE(eventually([&] { return (*server)->session_count() == 2; }));
  EXPECT_EQ(peers[0]->command("time").substr(0, 4), "NODE");
  EXPECT_TRUE(peers[0]->until("\n"));

  // Terminal mode on request (telnet's IAC DO ECHO, as `symb shell` sends from a terminal).
  peers[2]->type("\xff\xfd\x01");
  auto greeting = peers[2]->until("symb> ");
  ASSERT_TRUE(greeting);
  EXPECT_NE(greeting->find("Symbricator shell on node 'board'"), std::string::npos);

  // The server's end: every session's tasks go, the clients see the connection close.
  server = kernel::Error{"stopped"};
  EXPECT_TRUE(peers[0]->closed());
  EXPECT_TRUE(eventually([&] { return !b.node->find("shell1") && !b.node->find("shell3"); }));
}

TEST(ShellSession, TcpWithoutToken) {
  Board b;
  TcpShellOptions so;
  so.require_token = false;
  auto server = TcpShellServer::start(*b.node, so);
  ASSERT_TRUE(server);
  EXPECT_EQ((*server)->token(), "");
  ASSERT_TRUE(b.node->create("sink", "shell1", std::vector<os::ParamAssignment>{}));  // the name is taken
  auto c = io::TcpStream::connect("127.0.0.1", (*server)->port());
  ASSERT_TRUE(c);
  Peer peer(std::shared_ptr<io::IOStream>(std::move(c).value()), false);
  EXPECT_EQ(peer.command("priority nosuch 1"), "error: column 10: node 'board' has no task 'nosuch'\n");
  EXPECT_TRUE(peer.command("create sink s").starts_with("created 's' (sink, #"));
  EXPECT_TRUE(b.node->find("s"));
  EXPECT_TRUE(b.node->find("shell1-2") && b.node->find("shell1-2.io"));
}

// --- the same machinery under virtual time, over an in-memory stream ---------------------------------

struct VirtualBoard {
  VirtualBoard() {
    testing::add_test_types(types);
    node = std::make_unique<os::Node>(ex, os::NodeConfig{"board", 5, 256, &types});
  }
  void pump() {
    ex.wait_injected(1ms);
    ex.run_for(20ms);
  }
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  std::unique_ptr<os::Node> node;
};

TEST(ShellSessionVirtual, TokenExitAndLogFollow) {
  VirtualBoard b;
  auto [ours, theirs] = io::make_loopback_pair("link");
  ShellOptions o;
  o.token = "t0k3n";
  auto session = attach_shell(*b.node, std::move(ours), o, "sh");
  ASSERT_TRUE(session) << session.error();
  Peer peer(std::move(theirs), false, [&] { b.pump(); });
  EXPECT_EQ(peer.command("tasks"), "error: access denied\n");
  peer.type("t0k3n\n");
  EXPECT_EQ(peer.command("log follow"), "following the log ('log stop' ends it)\n");
  b.node->log().warn("sensor", "wheel slip");
  auto followed = peer.until("wheel slip\n");
  ASSERT_TRUE(followed);
  EXPECT_NE(followed->find("WARN  sensor: wheel slip"), std::string::npos);
  EXPECT_EQ(peer.command("log stop"), "stopped following the log\n");
  EXPECT_EQ(peer.command("create sink x"), "created 'x' (sink, #2.0)\n");
  EXPECT_EQ(peer.command("exit"), "bye\n");
  for (int i = 0; i < 20 && b.node->find("sh"); ++i) b.pump();
  EXPECT_FALSE(b.node->find("sh"));
  EXPECT_FALSE(b.node->find("sh.io"));
  EXPECT_TRUE(b.node->find("x"));
}

TEST(ShellSessionVirtual, ThreeWrongTokensCloseTheSession) {
  VirtualBoard b;
  auto [ours, theirs] = io::make_loopback_pair("link");
  ShellOptions o;
  o.token = "right";
  o.terminal = true;
  ASSERT_TRUE(attach_shell(*b.node, std::move(ours), o, "sh"));
  Peer peer(std::move(theirs), false, [&] { b.pump(); });
  ASSERT_TRUE(peer.until("token: "));
  peer.type("wrong\r");
  auto first = peer.until("token: ");
  ASSERT_TRUE(first);
  EXPECT_EQ(first->find("wrong"), std::string::npos);  // a token is not echoed
  EXPECT_NE(first->find("access denied"), std::string::npos);
  peer.type("wrong again\rstill wrong\r");
  ASSERT_TRUE(peer.until("access denied; closing"));
  for (int i = 0; i < 20 && b.node->task_count() > 0; ++i) b.pump();
  EXPECT_EQ(b.node->task_count(), 0u);
  bool logged = false;
  for (const auto& e : b.node->log().since(0))
    logged = logged || e.text.find("wrong shell token (3 of 3)") != std::string::npos;
  EXPECT_TRUE(logged);
}

TEST(ShellSessionVirtual, AConsoleLocksAgainOnExit) {
  VirtualBoard b;
  auto [ours, theirs] = io::make_loopback_pair("link");
  ShellOptions o;
  o.token = "k3y";
  o.terminal = true;
  o.close_on_exit = false;
  ASSERT_TRUE(attach_shell(*b.node, std::move(ours), o, "console"));
  Peer peer(std::move(theirs), true, [&] { b.pump(); });
  ASSERT_TRUE(peer.until("token: "));
  peer.type("k3y\r");
  ASSERT_TRUE(peer.until("symb> "));
  peer.type("\x04");  // Ctrl-D on an empty line: exit
  auto bye = peer.until("token: ");
  ASSERT_TRUE(bye);
  EXPECT_NE(bye->find("bye"), std::string::npos);
  peer.type("create sink x\r");
  auto denied = peer.until("token: ");
  ASSERT_TRUE(denied);
  EXPECT_NE(denied->find("access denied"), std::string::npos);
  EXPECT_FALSE(b.node->find("x"));
  EXPECT_TRUE(b.node->find("console"));
}

TEST(ShellSessionVirtual, AShellTypeHookedByHand) {
  VirtualBoard b;
  ASSERT_TRUE(register_shell_types(b.types));
  auto [ours, theirs] = io::make_loopback_pair("link");
  auto io_id = b.node->create("uart1", std::make_unique<io::StreamTask>(std::move(ours), io::StreamTask::Options{}));
  ASSERT_TRUE(io_id);
  std::vector<os::ParamAssignment> params = {{"prompt", "# ", 1}};
  auto sh = b.node->create("shell", "sh2", params);
  ASSERT_TRUE(sh) << sh.error();
  ASSERT_TRUE(b.node->hook(*io_id, *sh));
  ASSERT_TRUE(b.node->hook(*sh, *io_id));
  Peer peer(std::move(theirs), false, [&] { b.pump(); });
  EXPECT_EQ(peer.command("delete uart1"),
            "error: column 8: 'uart1' carries this shell session: use 'exit' to end it\n");
  EXPECT_EQ(peer.command("exit"), "bye\n");  // close_on_exit is off by default for this type
  EXPECT_EQ(peer.command("time").substr(0, 4), "NODE");
}

}  // namespace
}  // namespace symb::shell
