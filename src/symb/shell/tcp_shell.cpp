#include "symb/shell/tcp_shell.hpp"

#include <cstdio>
#include <fstream>

#include "symb/os/node.hpp"

namespace symb::shell {

namespace {
using namespace std::chrono_literals;
constexpr kernel::Duration kAcceptWait = 50ms;  // how often the loop looks at its sessions
}  // namespace

// One connection. The server's thread and the node's executor both touch it: the flags are
// atomics, and the task ids are written before `attached` is set.
struct TcpShellServer::Session {
  std::shared_ptr<io::IOStream> stream;
  std::string name;
  os::TaskId io;
  os::TaskId shell;
  std::atomic<bool> attached{false};
  std::atomic<bool> failed{false};
  std::atomic<bool> ended{false};      // the shell task stopped
  std::atomic<bool> cancelled{false};  // the server is going: do not attach any more
  std::mutex attach_mu;                // an attach and a cancellation do not interleave
  bool removal_requested = false;      // server thread only
};

kernel::Result<std::string> random_token(std::size_t hex_chars) {
  std::ifstream in("/dev/urandom", std::ios::binary);
  std::string raw((hex_chars + 1) / 2, '\0');
  if (!in || !in.read(raw.data(), static_cast<std::streamsize>(raw.size())))
    return kernel::Error{"cannot read /dev/urandom for a shell token"};
  std::string hex;
  char buf[4];
  for (char c : raw) {
    std::snprintf(buf, sizeof buf, "%02x", static_cast<unsigned char>(c));
    hex += buf;
  }
  hex.resize(hex_chars);
  return hex;
}

kernel::Result<std::unique_ptr<TcpShellServer>> TcpShellServer::start(os::Node& node, TcpShellOptions options) {
  if (!os::is_valid_name(options.prefix) || options.prefix.size() > 40)
    return kernel::Error{"invalid shell session prefix '" + options.prefix.substr(0, 63) + "'"};
  std::string token;
  if (options.require_token) {
    if (!options.token.empty()) {
      token = options.token;
    } else {
      auto t = random_token();
      if (!t) return kernel::Error{t.error()};
      token = *t;
    }
  }
  auto listener = io::TcpListener::bind(options.host, options.port);
  if (!listener) return kernel::Error{"shell server: " + listener.error()};
  auto server = std::unique_ptr<TcpShellServer>(
      new TcpShellServer(node, std::move(options), std::move(listener).value(), std::move(token)));
  server->thread_ = std::thread([s = server.get()] { s->loop(); });
  return server;
}

TcpShellServer::TcpShellServer(os::Node& node, TcpShellOptions options, std::unique_ptr<io::TcpListener> listener,
                               std::string token)
    : node_(node), options_(std::move(options)), listener_(std::move(listener)), token_(std::move(token)) {}

TcpShellServer::~TcpShellServer() {
  stop_ = true;
  listener_->close();
  if (thread_.joinable()) thread_.join();
  std::vector<std::shared_ptr<Session>> sessions;
  {
    std::lock_guard lock(mu_);
    sessions.swap(sessions_);
  }
  os::Node* node = &node_;
  for (auto& s : sessions) {
    {
      std::lock_guard lock(s->attach_mu);
      s->cancelled = true;
    }
    // Closing the connection first: the stream task's reader sees the end and nothing more is
    // written to a client that is gone.
    s->stream->close();
    if (s->attached.load())
      node->inject([node, io = s->io, shell = s->shell] {
        (void)node->remove(shell);
        (void)node->remove(io);
      });
  }
}

std::size_t TcpShellServer::session_count() const {
  std::lock_guard lock(mu_);
  return sessions_.size();
}

void TcpShellServer::loop() {
  bool failing = false;
  while (!stop_.load()) {
    reap();
    auto connection = listener_->accept(kAcceptWait);
    if (!connection) {
      if (stop_.load() || !listener_->is_open()) break;
      // Out of descriptors, say: logged once, retried without spinning, until it works again.
      if (!failing) node_.log().warn("shell-server", connection.error());
      failing = true;
      std::this_thread::sleep_for(kAcceptWait);
      continue;
    }
    failing = false;
    if (*connection) open_session(std::move(connection).value());
  }
}

void TcpShellServer::open_session(std::unique_ptr<io::TcpStream> connection) {
  const std::string peer = connection->peer();
  {
    std::lock_guard lock(mu_);
    if (sessions_.size() >= options_.max_sessions) {
      (void)connection->write_all(io::as_bytes("error: too many shell sessions\n"));
      connection->close();
      node_.log().warn("shell-server", "refused a shell session from " + peer + ": too many sessions");
      return;
    }
  }
  auto session = std::make_shared<Session>();
  session->stream = std::shared_ptr<io::IOStream>(std::move(connection));
  session->name = options_.prefix + std::to_string(opened_.fetch_add(1) + 1);
  ShellOptions o = options_.session;
  o.token = token_;
  o.close_on_exit = true;
  o.peer = {};
  std::weak_ptr<Session> weak = session;
  o.on_close = [weak] {
    if (auto s = weak.lock()) s->ended = true;
  };
  {
    std::lock_guard lock(mu_);
    sessions_.push_back(session);
  }
  node_.log().info("shell-server", "shell session " + session->name + " from " + peer);
  os::Node* node = &node_;
  node_.inject([node, session, o = std::move(o)]() mutable {
    std::lock_guard lock(session->attach_mu);
    if (session->cancelled.load()) return;
    // A task someone created by hand may already have the name: take the next free one.
    const std::string base = session->name;
    for (int k = 2; k < 100 && (node->find(session->name) || node->find(session->name + ".io")); ++k)
      session->name = base + "-" + std::to_string(k);
    auto r = attach_shell(*node, session->stream, std::move(o), session->name);
    if (!r) {
      node->log().warn("shell-server", "cannot open shell session " + session->name + ": " + r.error());
      session->failed = true;
      return;
    }
    session->io = r->io;
    session->shell = r->shell;
    session->attached = true;
  });
}

void TcpShellServer::reap() {
  std::vector<std::shared_ptr<Session>> done;
  {
    std::lock_guard lock(mu_);
    std::erase_if(sessions_, [&](const std::shared_ptr<Session>& s) {
      if (s->ended.load() || s->failed.load()) {
        done.push_back(s);
        return true;
      }
      return false;
    });
  }
  os::Node* node = &node_;
  for (auto& s : done) {
    // The shell ended the session (or never began): its stream task may still be there.
    if (s->failed.load()) (void)s->stream->write_all(io::as_bytes("error: no shell session could be opened\n"));
    s->stream->close();
    if (s->attached.load()) node->inject([node, io = s->io] { (void)node->remove(io); });
  }
  std::vector<std::shared_ptr<Session>> live;
  {
    std::lock_guard lock(mu_);
    live = sessions_;
  }
  for (auto& s : live) {
    // The client went away: the session's tasks go too (the shell's on_stop then ends it).
    if (s->attached.load() && !s->removal_requested && !s->stream->is_open()) {
      s->removal_requested = true;
      node->inject([node, io = s->io, shell = s->shell] {
        (void)node->remove(shell);
        (void)node->remove(io);
      });
    }
  }
}

}  // namespace symb::shell
