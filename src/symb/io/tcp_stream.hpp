// TcpStream and TcpListener: a byte stream over TCP, for links that cross machines or containers
// (a simulator on a workstation, a shell from a laptop) where a serial line would need a cable.
// Nagle's algorithm is off (TCP_NODELAY): robot traffic is small frames that must leave at once,
// not wait to be merged with the next one.
//
// A listener binds to 127.0.0.1 unless told otherwise: a robot's shell must not appear on every
// network the machine is on by accident. Port 0 picks a free port (port() tells which), so tests
// and parallel runs never collide. Every accepted connection is accepted: no filtering here.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "symb/io/fd_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::io {

class TcpStream final : public FdStream {
 public:
  // Connects to host:port (a name or a numeric IPv4/IPv6 address), waiting up to `timeout`.
  // Errors name the address and the cause ("Connection refused", a timeout, an unknown host).
  static kernel::Result<std::unique_ptr<TcpStream>> connect(const std::string& host, std::uint16_t port,
                                                            kernel::Duration timeout = std::chrono::seconds(5));

  // A connection made by connect() connects again to the same address; an accepted one cannot.
  kernel::Status open() override;
  const std::string& peer() const { return peer_; }

 private:
  friend class TcpListener;
  TcpStream(const std::string& name, std::string host, std::uint16_t port, kernel::Duration timeout, std::string peer);
  static kernel::Result<int> dial(const std::string& host, std::uint16_t port, kernel::Duration timeout);
  void add_ioctls();

  std::string host_;  // empty for an accepted connection
  std::uint16_t port_;
  kernel::Duration timeout_;
  std::string peer_;
};

class TcpListener {
 public:
  // Listens on host:port; port 0 picks a free one.
  static kernel::Result<std::unique_ptr<TcpListener>> bind(const std::string& host = "127.0.0.1",
                                                           std::uint16_t port = 0, int backlog = 16);
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;

  // The port listened on (the one picked when bound with port 0).
  std::uint16_t port() const { return port_; }
  const std::string& host() const { return host_; }
  // Waits up to `timeout` for a connection: the new stream, or nullptr when none came. An error
  // when the listener is closed (also when close() is called during the wait) or accept fails.
  kernel::Result<std::unique_ptr<TcpStream>> accept(kernel::Duration timeout);
  // Stops listening; wakes a thread waiting in accept(). Safe from any thread.
  void close() { fd_.close(); }
  bool is_open() const { return fd_.attached(); }

 private:
  TcpListener(std::string host, std::uint16_t port) : host_(std::move(host)), port_(port) {}

  std::string host_;
  std::uint16_t port_;
  WakeableFd fd_;
};

}  // namespace symb::io
