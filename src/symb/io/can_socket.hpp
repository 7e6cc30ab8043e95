// CanSocket: a CAN bus through Linux SocketCAN (a raw CAN socket bound to an interface such as
// can0, or vcan0 for a virtual bus), the paper's CANIOStream. CAN moves frames of up to 8 bytes,
// each with an identifier that also sets its bus priority; read_frame()/write_frame() give that
// directly. As an IOStream it carries a byte stream the way a serial line does, so a shell or
// the frame codec runs over CAN unchanged: write_all() cuts the bytes into frames sent with the
// "tx_id" identifier, and read_some() returns the bytes of received frames whose identifier is
// "rx_id" (or of every frame, when rx_id is -1). Frames arrive in order on one bus; other
// identifiers, remote frames and error frames are skipped by the byte stream.
//
// ioctls: "tx_id" (int, 0..0x1FFFFFFF; above 0x7FF the frame uses the 29-bit extended format),
// "rx_id" (int, -1..0x1FFFFFFF), "info".
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <string>

#include "symb/io/fd_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::io {

struct CanFrame {
  static constexpr std::uint32_t kMaxStandardId = 0x7FF;
  static constexpr std::uint32_t kMaxExtendedId = 0x1FFFFFFF;

  std::uint32_t id = 0;
  bool extended = false;  // 29-bit identifier
  bool remote = false;    // a remote transmission request (carries no data)
  std::uint8_t size = 0;  // 0..8
  std::array<std::byte, 8> data{};

  std::span<const std::byte> bytes() const { return {data.data(), size}; }
};

// Whether a raw CAN socket can be bound to `iface` here: ok, or why not (no SocketCAN in this
// kernel or network namespace, no such interface, not a CAN interface, interface down).
kernel::Status can_available(const std::string& iface);

class CanSocket final : public FdStream {
 public:
  static constexpr std::int64_t kAnyId = -1;

  // A socket on `iface` (not yet open: open() binds it).
  explicit CanSocket(std::string iface, std::uint32_t tx_id = 0x100, std::int64_t rx_id = kAnyId);

  kernel::Status open() override;
  const std::string& interface() const { return iface_; }

  // Sends one frame. Errors: identifier or size out of range, a closed socket, a bus that takes
  // nothing for write_timeout().
  kernel::Status write_frame(const CanFrame& frame);
  // Waits up to `timeout` for a frame (any identifier): the frame, or nothing on timeout.
  kernel::Result<std::optional<CanFrame>> read_frame(kernel::Duration timeout);

  // The byte-stream mapping (see above).
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override;
  kernel::Status write_all(std::span<const std::byte> data) override;

 private:
  void add_ioctls();

  std::string iface_;
  mutable std::mutex ids_mu_;  // tx_id_ and rx_id_ (ioctls come from the shell's thread)
  std::uint32_t tx_id_;
  std::int64_t rx_id_;
  // Bytes of a received frame that did not fit the caller's buffer (reader side only).
  std::array<std::byte, 8> pending_{};
  std::size_t pending_at_ = 0;
  std::size_t pending_size_ = 0;
};

}  // namespace symb::io
