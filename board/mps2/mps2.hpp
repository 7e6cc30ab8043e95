// QEMU's mps2-an385 (an ARM MPS2 board with the AN385 Cortex-M3 image): the registers the board
// image uses, its interrupt table's hooks and its cycle measures. CMSDK APB UARTs at 0x40004000
// (UART0) and 0x40005000 (UART1), receive interrupts 0 and 2 (QEMU hw/arm/mps2.c); SysTick from
// the 25 MHz system clock.
#pragma once

#include <cstdint>

namespace symb::board::mps2 {

inline constexpr std::uint32_t kCpuHz = 25'000'000;
inline constexpr std::uintptr_t kUart0 = 0x40004000;
inline constexpr std::uintptr_t kUart1 = 0x40005000;
inline constexpr int kUart0RxIrq = 0;
inline constexpr int kUart1RxIrq = 2;

// What the interrupt handlers call. The vector table is the hardware's one table, so these are
// the board's (set once by main before interrupts are enabled), not a framework global.
struct InterruptHooks {
  void (*systick)(void* context) = nullptr;
  void* systick_context = nullptr;
  void (*uart_rx[2])(void* context) = {nullptr, nullptr};
  void* uart_rx_context[2] = {nullptr, nullptr};
};
InterruptHooks& interrupt_hooks();

// SysTick every `period_us` microseconds of the 25 MHz clock.
void start_systick(std::uint32_t period_us);
void enable_irq(int irq);
// Sleeps until an interrupt (WFI).
inline void wait_for_interrupt() { __asm volatile("wfi"); }
// SysTick's down-counter and reload, for sub-tick timing (QEMU does not model the DWT cycle
// counter: its registers read as zero).
std::uint32_t systick_value();
std::uint32_t systick_reload();

}  // namespace symb::board::mps2
