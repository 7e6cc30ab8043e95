#include "mps2/uart.hpp"

#include "mps2/mps2.hpp"

namespace symb::board::mps2 {

namespace {
constexpr std::uintptr_t kData = 0x00, kState = 0x04, kCtrl = 0x08, kIntClear = 0x0c, kBaudDiv = 0x10;
constexpr std::uint32_t kTxFull = 1u << 0, kRxFull = 1u << 1;
constexpr std::uint32_t kTxEnable = 1u << 0, kRxEnable = 1u << 1, kRxIntEnable = 1u << 3;
constexpr std::uint32_t kRxInt = 1u << 1;
}  // namespace

CmsdkUart::CmsdkUart(std::string name, int index)
    : Device(name), IOStream(name), base_(index == 0 ? kUart0 : kUart1), index_(index) {}

volatile std::uint32_t& CmsdkUart::reg(std::uintptr_t offset) const {
  return *reinterpret_cast<volatile std::uint32_t*>(base_ + offset);
}

kernel::Status CmsdkUart::open() {
  if (open_) return {};
  InterruptHooks& h = interrupt_hooks();
  h.uart_rx[index_] = &CmsdkUart::on_rx_interrupt;
  h.uart_rx_context[index_] = this;
  reg(kBaudDiv) = 16;  // the smallest divider the CMSDK UART accepts; QEMU ignores the rate
  reg(kCtrl) = kTxEnable | kRxEnable | kRxIntEnable;
  enable_irq(index_ == 0 ? kUart0RxIrq : kUart1RxIrq);
  open_ = true;
  return {};
}

void CmsdkUart::close() {
  reg(kCtrl) = 0;
  open_ = false;
}

void CmsdkUart::on_rx_interrupt(void* self) {
  auto& u = *static_cast<CmsdkUart*>(self);
  u.reg(kIntClear) = kRxInt;
  while (u.reg(kState) & kRxFull) {
    const auto b = static_cast<std::byte>(u.reg(kData) & 0xff);
    const std::uint32_t head = u.head_.load(std::memory_order_relaxed);
    if (head - u.tail_.load(std::memory_order_acquire) == kRing) {
      u.overruns_.store(u.overruns_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      continue;
    }
    u.ring_[head % kRing] = b;
    u.head_.store(head + 1, std::memory_order_release);
  }
}

kernel::Result<std::size_t> CmsdkUart::read_some(std::span<std::byte> buf, kernel::Duration) {
  if (!open_) return kernel::Error{"'" + name() + "' is closed"};
  const std::uint32_t head = head_.load(std::memory_order_acquire);
  std::uint32_t tail = tail_.load(std::memory_order_relaxed);
  std::size_t n = 0;
  while (tail != head && n < buf.size()) buf[n++] = ring_[tail++ % kRing];
  tail_.store(tail, std::memory_order_release);
  bytes_in_ += n;
  return n;
}

kernel::Status CmsdkUart::write_all(std::span<const std::byte> data) {
  if (!open_) return kernel::Error{"'" + name() + "' is closed"};
  for (std::byte b : data) {
    while (reg(kState) & kTxFull) {
    }
    reg(kData) = static_cast<std::uint32_t>(b);
  }
  return {};
}

}  // namespace symb::board::mps2
