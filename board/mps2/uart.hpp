// CmsdkUart: a CMSDK APB UART of the mps2 board as an io::IOStream, so the shared stream code (the
// shell's StreamTask, the HIL link) uses it as Linux uses a serial port. The receive interrupt
// moves each byte into a ring buffer (the UART holds one byte); read_some() takes what the ring
// holds and never waits (the board's tasks never block). write_all() waits for each byte to be
// taken by the transmitter. A full ring leaves the next byte in the UART and turns its receive
// interrupt off until read_some() made room: the sender is held back, nothing is lost.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "symb/io/stream.hpp"

namespace symb::board::mps2 {

class CmsdkUart final : public io::IOStream {
 public:
  // `index` 0 or 1: UART0 or UART1 (their interrupt hooks).
  CmsdkUart(std::string name, int index);

  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_; }
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override;
  kernel::Status write_all(std::span<const std::byte> data) override;

  bool has_input() const { return head_.load(std::memory_order_acquire) != tail_.load(std::memory_order_relaxed); }
  // Times the ring was full and the sender held back.
  std::uint32_t rx_holds() const { return holds_; }
  std::uint64_t bytes_in() const { return bytes_in_; }

 private:
  static void on_rx_interrupt(void* self);
  void drain();
  volatile std::uint32_t& reg(std::uintptr_t offset) const;

  std::uintptr_t base_;
  int index_;
  bool open_ = false;
  static constexpr std::uint32_t kRing = 512;  // a power of two; drained every millisecond
  std::array<std::byte, kRing> ring_{};
  std::atomic<std::uint32_t> head_{0};  // written by the interrupt
  std::atomic<std::uint32_t> tail_{0};  // written by the main context
  volatile std::uint32_t holds_ = 0;
  volatile bool held_ = false;  // the ring was full: the receive interrupt is off
  std::uint64_t bytes_in_ = 0;
};

}  // namespace symb::board::mps2
