// TcpShellServer: the command shell over TCP, several sessions at once. It listens (on 127.0.0.1
// unless told otherwise; port 0 picks a free port) and opens a shell session for each connection:
// a StreamTask "shell<N>.io" and a CommandShellTask "shell<N>" on the node, hooked both ways
// (attach_shell()). A session ends when the client disconnects (its tasks are deleted) or when the
// shell ends it (exit, too many wrong tokens: the connection is closed).
//
// Unless told otherwise (require_token = false), sessions need a token: the one given, or 16 hex
// characters read from /dev/urandom at start, which the caller prints where the operator sees it.
//
// The server's own thread accepts and watches connections; everything it does to the node goes
// through Node::inject, so it works under the thread and the virtual-time executor alike (under
// virtual time, sessions appear when the executor runs injected work). The node must outlive the
// server.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "symb/io/tcp_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/shell/shell_task.hpp"

namespace symb::os {
class Node;
}

namespace symb::shell {

struct TcpShellOptions {
  std::string host = "127.0.0.1";
  std::uint16_t port = 0;     // 0: a free port, see port()
  bool require_token = true;  // false: anyone who can connect gets a shell (--no-token)
  std::string token;          // empty with require_token: a random one
  std::size_t max_sessions = 8;
  std::string prefix = "shell";  // sessions are <prefix><N>
  // Per-session options (terminal, prompt, devices, read_file); token, peer, close_on_exit and
  // on_close are set by the server.
  ShellOptions session;
};

// `hex_chars` random hexadecimal characters from /dev/urandom.
kernel::Result<std::string> random_token(std::size_t hex_chars = 16);

class TcpShellServer {
 public:
  static kernel::Result<std::unique_ptr<TcpShellServer>> start(os::Node& node, TcpShellOptions options);
  // Stops listening, closes every connection and deletes the sessions' tasks.
  ~TcpShellServer();
  TcpShellServer(const TcpShellServer&) = delete;
  TcpShellServer& operator=(const TcpShellServer&) = delete;

  std::uint16_t port() const { return listener_->port(); }
  const std::string& host() const { return listener_->host(); }
  // The token sessions must give first; empty when none is required.
  const std::string& token() const { return token_; }
  // Connections being served.
  std::size_t session_count() const;
  // Connections accepted so far.
  std::uint64_t sessions_opened() const { return opened_.load(); }

 private:
  struct Session;
  TcpShellServer(os::Node& node, TcpShellOptions options, std::unique_ptr<io::TcpListener> listener, std::string token);
  void loop();
  void open_session(std::unique_ptr<io::TcpStream> connection);
  void reap();

  os::Node& node_;
  TcpShellOptions options_;
  std::unique_ptr<io::TcpListener> listener_;
  std::string token_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> opened_{0};
  mutable std::mutex mu_;  // sessions_
  std::vector<std::shared_ptr<Session>> sessions_;
  std::thread thread_;
};

}  // namespace symb::shell
