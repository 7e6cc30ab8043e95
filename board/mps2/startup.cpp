// Reset and the vector table of the mps2-an385 image: copy .data, clear .bss, paint the stack
// (its high-water is measured), start semihosting and the C++ constructors, run main, exit.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "mps2/mps2.hpp"
#include "port/runtime.hpp"

extern "C" {
// Linker script symbols, declared as char everywhere in the image (one unity batch may hold
// several files that name them).
extern char __data_start[], __data_end[], __data_load[];
extern char __bss_start[], __bss_end[];
extern char __stack_bottom[], __stack_top[];
void __libc_init_array();
void initialise_monitor_handles();
int main();
void Reset_Handler();
}

namespace symb::board::mps2 {

namespace {
InterruptHooks hooks;

volatile std::uint32_t& reg(std::uintptr_t address) { return *reinterpret_cast<volatile std::uint32_t*>(address); }

void fault_handler() { symb_board_fatal("hard fault"); }
void unexpected_handler() { symb_board_fatal("unexpected interrupt"); }
void systick_handler() {
  if (hooks.systick != nullptr) hooks.systick(hooks.systick_context);
}
void uart0_rx_handler() {
  if (hooks.uart_rx[0] != nullptr) hooks.uart_rx[0](hooks.uart_rx_context[0]);
}
void uart1_rx_handler() {
  if (hooks.uart_rx[1] != nullptr) hooks.uart_rx[1](hooks.uart_rx_context[1]);
}
}  // namespace

InterruptHooks& interrupt_hooks() { return hooks; }

void start_systick(std::uint32_t period_us) {
  reg(0xE000E014) = kCpuHz / 1'000'000 * period_us - 1;  // SYST_RVR
  reg(0xE000E018) = 0;                                   // SYST_CVR
  reg(0xE000E010) = 0x7;                                 // SYST_CSR: processor clock, interrupt, enable
}

void enable_irq(int irq) { reg(0xE000E100 + 4 * static_cast<std::uintptr_t>(irq / 32)) = 1u << (irq % 32); }

std::uint32_t systick_value() { return reg(0xE000E018); }
std::uint32_t systick_reload() { return reg(0xE000E014); }

using Handler = void (*)();
// 16 system exceptions and the AN385's 32 external interrupts.
extern "C" __attribute__((section(".isr_vector"), used)) const Handler vector_table[16 + 32] = {
    reinterpret_cast<Handler>(__stack_top),
    Reset_Handler,
    unexpected_handler,  // NMI
    fault_handler,       // HardFault
    fault_handler,       // MemManage
    fault_handler,       // BusFault
    fault_handler,       // UsageFault
    nullptr,
    nullptr,
    nullptr,
    nullptr,
    unexpected_handler,  // SVCall
    unexpected_handler,  // DebugMon
    nullptr,
    unexpected_handler,  // PendSV
    systick_handler,
    uart0_rx_handler,    // IRQ 0: UART0 RX
    unexpected_handler,  // IRQ 1: UART0 TX
    uart1_rx_handler,    // IRQ 2: UART1 RX
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
    unexpected_handler,
};

}  // namespace symb::board::mps2

extern "C" void Reset_Handler() {
  auto* d = reinterpret_cast<std::uint32_t*>(__data_start);
  for (auto* s = reinterpret_cast<const std::uint32_t*>(__data_load); d < reinterpret_cast<std::uint32_t*>(__data_end);)
    *d++ = *s++;
  for (auto* b = reinterpret_cast<std::uint32_t*>(__bss_start); b < reinterpret_cast<std::uint32_t*>(__bss_end);)
    *b++ = 0;
  // Paint the stack below the current frame, for stack_high_water().
  std::uint32_t* sp;
  __asm volatile("mov %0, sp" : "=r"(sp));
  for (auto* p = reinterpret_cast<std::uint32_t*>(__stack_bottom); p < sp - 16;) *p++ = 0xa5a5a5a5u;
  initialise_monitor_handles();
  __libc_init_array();
  std::exit(main());
}
