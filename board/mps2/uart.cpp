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
  u.drain();
}

// Moves what the UART holds into the ring. With the ring full the byte stays in the UART and its
// receive interrupt is turned off: the UART refuses more (QEMU's character backend then holds
// the rest: flow control, nothing lost) until read_some() made room.
void CmsdkUart::drain() {
  while (reg(kState) & kRxFull) {
    const std::uint32_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == kRing) {
      reg(kCtrl) = kTxEnable | kRxEnable;
      held_ = true;
      holds_ = holds_ + 1;
      return;
    }
    ring_[head % kRing] = static_cast<std::byte>(reg(kData) & 0xff);
    head_.store(head + 1, std::memory_order_release);
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
  if (held_ && n > 0) {
    // Room again: take what the UART held back and let it interrupt again.
    std::uint32_t primask;
    __asm volatile("mrs %0, primask\n cpsid i" : "=r"(primask)::"memory");
    held_ = false;
    drain();
    if (!held_) reg(kCtrl) = kTxEnable | kRxEnable | kRxIntEnable;
    __asm volatile("msr primask, %0" ::"r"(primask) : "memory");
  }
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
