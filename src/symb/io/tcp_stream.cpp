#include "symb/io/tcp_stream.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace symb::io {

namespace {

std::string address_text(const sockaddr* sa, socklen_t len) {
  char host[NI_MAXHOST] = {};
  char serv[NI_MAXSERV] = {};
  if (::getnameinfo(sa, len, host, sizeof host, serv, sizeof serv, NI_NUMERICHOST | NI_NUMERICSERV) != 0) return "?";
  return sa->sa_family == AF_INET6 ? "[" + std::string(host) + "]:" + serv : std::string(host) + ":" + serv;
}

std::string endpoint(const std::string& host, std::uint16_t port) {
  return (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

void set_nodelay(int fd) {
  const int one = 1;
  (void)::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

struct AddrInfo {
  addrinfo* list = nullptr;
  ~AddrInfo() {
    if (list != nullptr) ::freeaddrinfo(list);
  }
};

kernel::Status resolve(const std::string& host, std::uint16_t port, bool passive, AddrInfo& out) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV | (passive ? AI_PASSIVE : 0);
  const std::string service = std::to_string(port);
  const int rc = ::getaddrinfo(host.empty() ? nullptr : host.c_str(), service.c_str(), &hints, &out.list);
  if (rc != 0) return kernel::Error{"tcp: cannot resolve '" + host + "': " + ::gai_strerror(rc)};
  return {};
}

// A non-blocking, close-on-exec socket for the address `a`, or -1 with the reason in `last`.
int open_socket(const addrinfo& a, std::string& last) {
  const int fd = ::socket(a.ai_family, a.ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a.ai_protocol);
  if (fd < 0) last = std::strerror(errno);
  return fd;
}

}  // namespace

// --- TcpStream -----------------------------------------------------------------------------------

TcpStream::TcpStream(const std::string& name, std::string host, std::uint16_t port, kernel::Duration timeout,
                     std::string peer)
    : Device(name), FdStream(name), host_(std::move(host)), port_(port), timeout_(timeout), peer_(std::move(peer)) {
  add_ioctls();
}

kernel::Result<int> TcpStream::dial(const std::string& host, std::uint16_t port, kernel::Duration timeout) {
  const std::string where = endpoint(host, port);
  if (port == 0) return kernel::Error{"tcp: cannot connect to " + where + ": port 0 is not a port one connects to"};
  AddrInfo ai;
  if (auto st = resolve(host, port, false, ai); !st) return kernel::Error{st.error()};
  const auto deadline = std::chrono::steady_clock::now() + std::min<kernel::Duration>(timeout, std::chrono::hours(24));
  std::string last = "no address";
  for (addrinfo* a = ai.list; a != nullptr; a = a->ai_next) {
    const int fd = open_socket(*a, last);
    if (fd < 0) continue;
    int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    int err = rc == 0 ? 0 : errno;
    if (err == EINPROGRESS) {
      // The connection completes in the background; poll says when, SO_ERROR how.
      pollfd p{fd, POLLOUT, 0};
      int n = 0;
      do {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        n = ::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, left.count())));
      } while (n < 0 && errno == EINTR);
      if (n == 0) {
        ::close(fd);
        return kernel::Error{"tcp: cannot connect to " + where + ": timed out after " +
                             std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(timeout).count()) +
                             " ms"};
      }
      socklen_t len = sizeof err;
      if (n < 0 || ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0) err = errno;
    }
    if (err == 0) {
      set_nodelay(fd);
      return fd;
    }
    last = std::strerror(err);
    ::close(fd);
  }
  return kernel::Error{"tcp: cannot connect to " + where + ": " + last};
}

kernel::Result<std::unique_ptr<TcpStream>> TcpStream::connect(const std::string& host, std::uint16_t port,
                                                              kernel::Duration timeout) {
  auto fd = dial(host, port, timeout);
  if (!fd) return kernel::Error{fd.error()};
  sockaddr_storage peer{};
  socklen_t len = sizeof peer;
  std::string peer_text = ::getpeername(*fd, reinterpret_cast<sockaddr*>(&peer), &len) == 0
                              ? address_text(reinterpret_cast<sockaddr*>(&peer), len)
                              : endpoint(host, port);
  std::unique_ptr<TcpStream> s(new TcpStream("tcp:" + endpoint(host, port), host, port, timeout, peer_text));
  if (auto st = s->attach(*fd, *fd, true); !st) {
    ::close(*fd);
    return kernel::Error{st.error()};
  }
  return s;
}

kernel::Status TcpStream::open() {
  if (is_open()) return {};
  if (host_.empty()) return kernel::Error{"tcp stream '" + name() + "' was accepted and cannot connect again"};
  close();
  auto fd = dial(host_, port_, timeout_);
  if (!fd) return kernel::Error{fd.error()};
  if (auto st = attach(*fd, *fd, true); !st) {
    ::close(*fd);
    return st;
  }
  return {};
}

void TcpStream::add_ioctls() {
  add_ioctl({"info", std::nullopt, "peer address and state"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              std::string out = "peer=" + peer_ + " open=" + (is_open() ? "true" : "false") + " nodelay=true";
              if (const std::string why = failure(); !why.empty()) out += " failure=\"" + why + "\"";
              return out;
            });
}

// --- TcpListener ---------------------------------------------------------------------------------

kernel::Result<std::unique_ptr<TcpListener>> TcpListener::bind(const std::string& host, std::uint16_t port,
                                                               int backlog) {
  const std::string where = endpoint(host, port);
  AddrInfo ai;
  if (auto st = resolve(host, port, true, ai); !st) return kernel::Error{st.error()};
  std::string last = "no address";
  for (addrinfo* a = ai.list; a != nullptr; a = a->ai_next) {
    const int fd = open_socket(*a, last);
    if (fd < 0) continue;
    // A board restarted right after a crash must get its port back, not wait out TIME_WAIT.
    const int one = 1;
    (void)::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, backlog) != 0) {
      last = std::strerror(errno);
      ::close(fd);
      continue;
    }
    sockaddr_storage local{};
    socklen_t len = sizeof local;
    std::uint16_t bound = port;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len) == 0) {
      if (local.ss_family == AF_INET)
        bound = ntohs(reinterpret_cast<sockaddr_in*>(&local)->sin_port);
      else if (local.ss_family == AF_INET6)
        bound = ntohs(reinterpret_cast<sockaddr_in6*>(&local)->sin6_port);
    }
    std::unique_ptr<TcpListener> l(new TcpListener(host, bound));
    if (auto st = l->fd_.attach(fd, -1, true); !st) {
      ::close(fd);
      return kernel::Error{"tcp: cannot listen on " + where + ": " + st.error()};
    }
    return l;
  }
  return kernel::Error{"tcp: cannot listen on " + where + ": " + last};
}

TcpListener::~TcpListener() { fd_.close(); }

kernel::Result<std::unique_ptr<TcpStream>> TcpListener::accept(kernel::Duration timeout) {
  auto use = fd_.use();
  if (!use) return kernel::Error{"tcp listener on " + endpoint(host_, port_) + " is closed"};
  const auto deadline = std::chrono::steady_clock::now() + std::min<kernel::Duration>(timeout, std::chrono::hours(24));
  for (;;) {
    short revents = 0;
    switch (WakeableFd::wait(*use, use->read_fd(), POLLIN, deadline - std::chrono::steady_clock::now(), revents)) {
      case WakeableFd::Wait::kClosed: return kernel::Error{"tcp listener on " + endpoint(host_, port_) + " is closed"};
      case WakeableFd::Wait::kTimeout: return std::unique_ptr<TcpStream>{};
      case WakeableFd::Wait::kFailed:
        return kernel::Error{"tcp listener on " + endpoint(host_, port_) + ": poll failed: " + std::strerror(errno)};
      case WakeableFd::Wait::kReady: break;
    }
    sockaddr_storage peer{};
    socklen_t len = sizeof peer;
    const int fd = ::accept4(use->read_fd(), reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      const int e = errno;
      // Gone before we took it, or taken by another thread: wait for the next one.
      if (e == EAGAIN || e == EWOULDBLOCK || e == EINTR || e == ECONNABORTED || e == EPROTO) continue;
      return kernel::Error{"tcp listener on " + endpoint(host_, port_) + ": accept failed: " + std::strerror(e)};
    }
    set_nodelay(fd);
    const std::string peer_text = address_text(reinterpret_cast<sockaddr*>(&peer), len);
    std::unique_ptr<TcpStream> s(new TcpStream("tcp:" + peer_text, "", 0, {}, peer_text));
    if (auto st = s->attach(fd, fd, true); !st) {
      ::close(fd);
      return kernel::Error{st.error()};
    }
    return s;
  }
}

}  // namespace symb::io
