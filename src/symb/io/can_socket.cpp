#include "symb/io/can_socket.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <utility>

namespace symb::io {

namespace {

std::string hex(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%X", v);
  return buf;
}

// Owns a descriptor until released (error paths close it, the success path hands it on).
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

kernel::Result<int> open_bound(const std::string& iface) {
  if (iface.empty() || iface.size() >= IFNAMSIZ)
    return kernel::Error{"can: '" + iface.substr(0, 32) + "' is not a network interface name"};
  Fd fd(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (fd.get() < 0)
    return kernel::Error{"can: SocketCAN is not available in this kernel or network namespace (socket(AF_CAN): " +
                         std::string(std::strerror(errno)) + ")"};
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, iface.c_str(), iface.size() + 1);
  if (::ioctl(fd.get(), SIOCGIFINDEX, &ifr) != 0)
    return kernel::Error{"can: no network interface '" + iface + "' (" + std::strerror(errno) + ")"};
  const int index = ifr.ifr_ifindex;
  if (::ioctl(fd.get(), SIOCGIFHWADDR, &ifr) == 0 && ifr.ifr_hwaddr.sa_family != ARPHRD_CAN)
    return kernel::Error{"can: interface '" + iface + "' is not a CAN interface"};
  if (::ioctl(fd.get(), SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_UP) == 0)
    return kernel::Error{"can: interface '" + iface + "' is down (ip link set up " + iface + ")"};
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    return kernel::Error{"can: cannot bind to '" + iface + "': " + std::strerror(errno)};
  return fd.release();
}

}  // namespace

kernel::Status can_available(const std::string& iface) {
  auto fd = open_bound(iface);
  if (!fd) return kernel::Error{fd.error()};
  ::close(*fd);
  return {};
}

CanSocket::CanSocket(std::string iface, std::uint32_t tx_id, std::int64_t rx_id)
    : Device("can:" + iface), FdStream("can:" + iface), iface_(std::move(iface)), tx_id_(tx_id), rx_id_(rx_id) {
  add_ioctls();
}

kernel::Status CanSocket::open() {
  if (is_open()) return {};
  close();
  {
    std::lock_guard lock(ids_mu_);
    if (tx_id_ > CanFrame::kMaxExtendedId) return kernel::Error{"can socket '" + name() + "': tx_id out of range"};
  }
  auto fd = open_bound(iface_);
  if (!fd) return kernel::Error{fd.error()};
  if (auto st = attach(*fd, *fd, true); !st) {
    ::close(*fd);
    return st;
  }
  pending_at_ = pending_size_ = 0;
  return {};
}

kernel::Status CanSocket::write_frame(const CanFrame& frame) {
  const std::uint32_t max_id = frame.extended ? CanFrame::kMaxExtendedId : CanFrame::kMaxStandardId;
  if (frame.id > max_id)
    return kernel::Error{"can socket '" + name() + "': identifier " + hex(frame.id) + " is beyond " + hex(max_id) +
                         (frame.extended ? "" : " (set extended for 29-bit identifiers)")};
  if (frame.size > 8)
    return kernel::Error{"can socket '" + name() + "': a frame carries at most 8 bytes, not " +
                         std::to_string(frame.size)};
  can_frame raw{};
  raw.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0U) | (frame.remote ? CAN_RTR_FLAG : 0U);
  raw.can_dlc = frame.size;
  std::memcpy(raw.data, frame.data.data(), frame.size);
  return FdStream::write_all({reinterpret_cast<const std::byte*>(&raw), sizeof raw});
}

kernel::Result<std::optional<CanFrame>> CanSocket::read_frame(kernel::Duration timeout) {
  const auto deadline = std::chrono::steady_clock::now() + std::min<kernel::Duration>(timeout, std::chrono::hours(24));
  for (;;) {
    can_frame raw{};
    auto n = FdStream::read_some({reinterpret_cast<std::byte*>(&raw), sizeof raw},
                                 deadline - std::chrono::steady_clock::now());
    if (!n) return kernel::Error{n.error()};
    if (*n == 0) return std::optional<CanFrame>{};
    // A raw socket hands over whole frames; anything else (CAN FD, which is not enabled) or an
    // error frame is not for us.
    if (*n != sizeof raw || (raw.can_id & CAN_ERR_FLAG) != 0) continue;
    CanFrame f;
    f.extended = (raw.can_id & CAN_EFF_FLAG) != 0;
    f.remote = (raw.can_id & CAN_RTR_FLAG) != 0;
    f.id = raw.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    f.size = f.remote ? 0 : std::min<std::uint8_t>(raw.can_dlc, 8);
    std::memcpy(f.data.data(), raw.data, f.size);
    return std::optional<CanFrame>(f);
  }
}

kernel::Result<std::size_t> CanSocket::read_some(std::span<std::byte> buf, kernel::Duration timeout) {
  if (buf.empty()) return std::size_t{0};
  if (pending_at_ < pending_size_) {
    const std::size_t n = std::min(buf.size(), pending_size_ - pending_at_);
    std::memcpy(buf.data(), pending_.data() + pending_at_, n);
    pending_at_ += n;
    return n;
  }
  std::int64_t want = kAnyId;
  {
    std::lock_guard lock(ids_mu_);
    want = rx_id_;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::min<kernel::Duration>(timeout, std::chrono::hours(24));
  for (;;) {
    auto f = read_frame(deadline - std::chrono::steady_clock::now());
    if (!f) return kernel::Error{f.error()};
    if (!*f) return std::size_t{0};
    const CanFrame& frame = **f;
    if (frame.remote || frame.size == 0) continue;
    if (want != kAnyId && static_cast<std::int64_t>(frame.id) != want) continue;
    const std::size_t n = std::min<std::size_t>(buf.size(), frame.size);
    std::memcpy(buf.data(), frame.data.data(), n);
    pending_ = frame.data;
    pending_at_ = n;
    pending_size_ = frame.size;
    return n;
  }
}

kernel::Status CanSocket::write_all(std::span<const std::byte> data) {
  CanFrame f;
  {
    std::lock_guard lock(ids_mu_);
    f.id = tx_id_;
  }
  f.extended = f.id > CanFrame::kMaxStandardId;
  while (!data.empty()) {
    f.size = static_cast<std::uint8_t>(std::min<std::size_t>(8, data.size()));
    std::memcpy(f.data.data(), data.data(), f.size);
    if (auto st = write_frame(f); !st) return st;
    data = data.subspan(f.size);
  }
  return {};
}

void CanSocket::add_ioctls() {
  add_ioctl({"tx_id",
             os::ParamSpec{"tx_id", os::ParamType::kInt, std::int64_t{0x100}, 0.0,
                           static_cast<double>(CanFrame::kMaxExtendedId), "identifier of the frames write_all sends"},
             "identifier of the byte stream's outgoing frames (above 0x7FF: extended format)"},
            [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
              std::lock_guard lock(ids_mu_);
              tx_id_ = static_cast<std::uint32_t>(std::get<std::int64_t>(*arg));
              return hex(tx_id_);
            });
  add_ioctl({"rx_id",
             os::ParamSpec{"rx_id", os::ParamType::kInt, std::int64_t{kAnyId}, -1.0,
                           static_cast<double>(CanFrame::kMaxExtendedId), "identifier read_some accepts; -1: any"},
             "identifier of the byte stream's incoming frames; -1 takes every frame"},
            [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
              std::lock_guard lock(ids_mu_);
              rx_id_ = std::get<std::int64_t>(*arg);
              return rx_id_ == kAnyId ? std::string("any") : hex(static_cast<std::uint32_t>(rx_id_));
            });
  add_ioctl({"info", std::nullopt, "interface, identifiers and state"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              std::lock_guard lock(ids_mu_);
              std::string out = "interface=" + iface_ + " tx_id=" + hex(tx_id_) + " rx_id=" +
                                (rx_id_ == kAnyId ? std::string("any") : hex(static_cast<std::uint32_t>(rx_id_))) +
                                " open=" + (is_open() ? "true" : "false");
              if (const std::string why = failure(); !why.empty()) out += " failure=\"" + why + "\"";
              return out;
            });
}

}  // namespace symb::io
