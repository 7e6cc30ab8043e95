// WsTestClient: the smallest WebSocket client that can check the web view's server from a test
// or a benchmark: a blocking POSIX socket, the HTTP upgrade, unmasked text frames in (the server
// does not mask) and masked text frames out (a client must). It can also stall on purpose: a
// client that never calls read_frame() is a browser that stopped reading.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace symb::testing {

class WsTestClient {
 public:
  WsTestClient() = default;
  ~WsTestClient() { close(); }
  WsTestClient(const WsTestClient&) = delete;
  WsTestClient& operator=(const WsTestClient&) = delete;

  // Connects to 127.0.0.1:port and asks for `path` as a WebSocket. Returns the HTTP status line
  // of the answer ("HTTP/1.1 101 Switching Protocols"), or empty when there was none.
  std::string open(std::uint16_t port, const std::string& path, int receive_buffer = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd_ < 0) return {};
    if (receive_buffer > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return {};
    const std::string request = "GET " + path +
                                " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
                                "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n";
    if (!write_all(request)) return {};
    std::string head;
    while (head.find("\r\n\r\n") == std::string::npos) {
      char c;
      if (!read_exact(&c, 1, std::chrono::seconds(5))) break;
      head += c;
    }
    status_ = head.substr(0, head.find("\r\n"));
    return status_;
  }
  bool upgraded() const { return status_.find(" 101 ") != std::string::npos; }

  // The next text frame's payload, waiting up to `timeout`; nothing on timeout or a closed socket.
  std::optional<std::string> read_frame(std::chrono::milliseconds timeout = std::chrono::milliseconds(2000)) {
    unsigned char h[2];
    if (!read_exact(h, 2, timeout)) return std::nullopt;
    std::uint64_t len = h[1] & 0x7f;
    if (len == 126) {
      unsigned char e[2];
      if (!read_exact(e, 2, timeout)) return std::nullopt;
      len = (std::uint64_t{e[0]} << 8) | e[1];
    } else if (len == 127) {
      unsigned char e[8];
      if (!read_exact(e, 8, timeout)) return std::nullopt;
      len = 0;
      for (unsigned char b : e) len = (len << 8) | b;
    }
    if (len > (64u << 20)) return std::nullopt;
    std::string payload(len, '\0');
    if (len && !read_exact(payload.data(), len, timeout)) return std::nullopt;
    if ((h[0] & 0x0f) == 0x8) {
      told_goodbye_ = true;
      return std::nullopt;
    }
    return payload;
  }
  // Whether read_frame() met the server's close frame (rather than a timeout or a dropped socket).
  bool told_goodbye() const { return told_goodbye_; }

  // Sends one masked text frame.
  bool send_text(const std::string& text) {
    std::string f;
    f += static_cast<char>(0x81);
    if (text.size() < 126) {
      f += static_cast<char>(0x80 | text.size());
    } else {
      f += static_cast<char>(0x80 | 126);
      f += static_cast<char>((text.size() >> 8) & 0xff);
      f += static_cast<char>(text.size() & 0xff);
    }
    const char mask[4] = {0x12, 0x34, 0x56, 0x78};
    f.append(mask, 4);
    for (std::size_t i = 0; i < text.size(); ++i) f += static_cast<char>(text[i] ^ mask[i % 4]);
    return write_all(f);
  }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  bool write_all(const std::string& s) {
    for (std::size_t done = 0; done < s.size();) {
      const ssize_t n = ::send(fd_, s.data() + done, s.size() - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }
  bool read_exact(void* buf, std::size_t n, std::chrono::milliseconds timeout) {
    auto* p = static_cast<char*>(buf);
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (n > 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
      pollfd pfd{fd_, POLLIN, 0};
      if (left.count() <= 0 || ::poll(&pfd, 1, static_cast<int>(left.count())) <= 0) return false;
      const ssize_t r = ::recv(fd_, p, n, 0);
      if (r <= 0) return false;
      p += r;
      n -= static_cast<std::size_t>(r);
    }
    return true;
  }

  int fd_ = -1;
  std::string status_;
  bool told_goodbye_ = false;
};

}  // namespace symb::testing
