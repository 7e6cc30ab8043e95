// symb-board-selftest.elf: the board's self-test under QEMU (semihosting; its exit code is
// QEMU's). It runs the maze graph of symb-board.elf on the BareMetalExecutor with the tick driven
// by hand (board time, not QEMU's), over an in-memory line instead of UART0, and checks:
//  - every IR frame gets its wheel frame, with the seq it answers; a clear view drives forward
//    (300, 300), a wall ahead turns (-300, 300);
//  - a corrupted frame is counted bad and the next one is answered;
//  - no heap allocation on the message path after start-up (malloc is wrapped and counted);
//  - RAM: data + bss + stack high-water + heap high-water within the 32 KiB budget.
// It prints the control step's cost (IR frame in, wheel frame out) in SysTick counts of the
// 25 MHz clock: under `-icount shift=0` one instruction is one virtual nanosecond, so a count is
// 40 instructions (QEMU models no DWT cycle counter: CYCCNT reads 0, which this checks too).
#include <array>
#include <atomic>
#include <bit>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/kernel/bare_metal_executor.hpp"

#include "app/maze_graph.hpp"
#include "app/memory_line.hpp"
#include "mps2/mps2.hpp"
#include "port/runtime.hpp"

extern "C" char __data_start[], __bss_end[];

namespace {

using namespace symb;
using namespace std::chrono_literals;

int failures = 0;
void check(bool ok, const char* what) {
  if (!ok) {
    ++failures;
    symb::board::print(std::string("selftest: FAIL: ") + what + "\n");
  }
}

// Puts frame 'N' [seq, ir...] into the line's input (after what was read).
void send_ir(board::MemoryLine& line, float seq, const std::array<float, 7>& ir, bool corrupt = false) {
  std::array<std::byte, 1 + 4 * 8> payload{};
  payload[0] = std::byte{'N'};
  for (std::size_t k = 0; k < 8; ++k) {
    const auto bits = std::bit_cast<std::uint32_t>(k == 0 ? seq : ir[k - 1]);
    for (std::size_t i = 0; i < 4; ++i) payload[1 + 4 * k + i] = static_cast<std::byte>((bits >> (8 * i)) & 0xff);
  }
  line.in_size = line.in_pos = 0;
  line.in_size = io::encode_frame(payload, std::span<std::byte>(line.in.data(), line.in.size()));
  if (corrupt) line.in[5] ^= std::byte{0x10};  // a data byte of the COBS body: CRC catches it
}

struct Wheels {
  int count = 0;
  float seq = -1, left = 0, right = 0;
};

// Decodes every wheel frame the board wrote since the last call; keeps the last.
Wheels take_wheels(board::MemoryLine& line, io::FrameDecoder& decoder) {
  Wheels w;
  decoder.feed(std::span<const std::byte>(line.out.data(), line.out_size), [&](std::span<const std::byte> f) {
    if (f.size() != 13) return;
    float v[3];
    for (std::size_t k = 0; k < 3; ++k) {
      std::uint32_t bits = 0;
      for (std::size_t i = 0; i < 4; ++i) bits |= static_cast<std::uint32_t>(f[1 + 4 * k + i]) << (8 * i);
      v[k] = std::bit_cast<float>(bits);
    }
    ++w.count;
    w.seq = v[0];
    w.left = v[1];
    w.right = v[2];
  });
  line.out_size = 0;
  return w;
}

}  // namespace

int main() {
  kernel::BareMetalExecutor executor(1ms, 8, [](const char* why) { symb_board_fatal(why); });
  auto built = board::build_maze_graph(executor, 1);
  if (!built) symb_board_fatal(built.error().c_str());
  std::unique_ptr<board::MazeGraph> graph = std::move(built).value();
  auto line = std::make_shared<board::MemoryLine>();
  if (auto st = board::attach_maze_link(*graph, line); !st) symb_board_fatal(st.error().c_str());
  executor.run_ready();
  io::FrameDecoder wheel_decoder(64);

  // SysTick as a fine clock: wraps counted by its interrupt.
  static std::atomic<std::uint32_t> wraps{0};
  auto& hooks = board::mps2::interrupt_hooks();
  hooks.systick = [](void*) { wraps.store(wraps.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed); };
  board::mps2::start_systick(1000);
  auto counts = [] {
    for (;;) {
      const std::uint32_t w = wraps, v = board::mps2::systick_value();
      if (w == wraps)
        return static_cast<std::uint64_t>(w) * (board::mps2::systick_reload() + 1) +
               (board::mps2::systick_reload() - v);
    }
  };
  // DWT: enable CYCCNT and see whether it moves.
  *reinterpret_cast<volatile std::uint32_t*>(0xE000EDFC) |= 1u << 24;  // DEMCR.TRCENA
  *reinterpret_cast<volatile std::uint32_t*>(0xE0001000) |= 1u;        // DWT_CTRL.CYCCNTENA
  const std::uint32_t cyc0 = *reinterpret_cast<volatile std::uint32_t*>(0xE0001004);
  for (int i = 0; i < 1000; ++i) __asm volatile("nop");
  const std::uint32_t cyc1 = *reinterpret_cast<volatile std::uint32_t*>(0xE0001004);

  const std::array<float, 7> clear{0, 0, 0, 0, 0, 0, 0};
  const std::array<float, 7> wall{0, 0, 3000, 0, 0, 0, 0};
  constexpr int kSteps = 200;
  std::uint64_t allocations_after_warmup = 0;
  std::uint64_t step_counts = 0;
  int answered = 0;
  Wheels last;
  for (int k = 0; k <= kSteps; ++k) {
    if (k == 20) allocations_after_warmup = board::heap_stats().allocations;
    const bool see_wall = k >= 100 && k < 110;
    send_ir(*line, static_cast<float>(k), see_wall ? wall : clear);
    const std::uint64_t t0 = counts();
    // The frame is read at the link's next tick; the controller answers at once.
    executor.on_tick_interrupt();
    executor.run_ready();
    const std::uint64_t t1 = counts();
    if (k >= 20) step_counts += t1 - t0;
    const Wheels w = take_wheels(*line, wheel_decoder);
    if (w.count == 1 && w.seq == static_cast<float>(k)) ++answered;
    if (k == 50) check(w.left == 300 && w.right == 300, "a clear view drives forward (300, 300)");
    if (k == 101) check(w.left == 300 && w.right == -300, "a wall ahead turns right (300, -300)");
    last = w;
    for (int i = 1; i < 30; ++i) {  // the rest of the 30 ms period
      executor.on_tick_interrupt();
      executor.run_ready();
    }
    (void)take_wheels(*line, wheel_decoder);
  }
  check(answered == kSteps + 1, "every IR frame answered with its seq");
  const std::uint64_t allocations = board::heap_stats().allocations - allocations_after_warmup;
  check(allocations == 0, "no heap allocation on the message path after start-up");

  // A corrupted frame: counted bad, dropped; the next frame is answered.
  send_ir(*line, kSteps + 1, clear, true);
  for (int i = 0; i < 30; ++i) {
    executor.on_tick_interrupt();
    executor.run_ready();
  }
  // The controller's own tick may command the wheels meanwhile, with the last good seq.
  check(take_wheels(*line, wheel_decoder).seq != kSteps + 1, "a corrupted frame is not answered");
  send_ir(*line, kSteps + 2, clear);
  executor.on_tick_interrupt();
  executor.run_ready();
  const Wheels after = take_wheels(*line, wheel_decoder);
  check(graph->stats.decoder.crc_errors == 1, "the corrupted frame is counted as a CRC error");
  check(after.count == 1 && after.seq == kSteps + 2, "the frame after the corrupted one is answered");
  check(graph->stats.missed == 1, "the corrupted frame's seq is counted missed");

  const board::HeapStats heap = board::heap_stats();
  const std::size_t static_ram = static_cast<std::size_t>(__bss_end - __data_start);
  const std::size_t ram = static_ram + board::stack_high_water() + heap.high_water;
  check(ram <= 32 * 1024, "RAM (static + stack high-water + heap high-water) within 32 KiB");
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "selftest: control step %lu SysTick counts (25 MHz) over %d steps, %.1f per step "
                "(under -icount shift=0 one count is 40 instructions: %.0f instructions a step); "
                "dwt_cyccnt_moves=%d\n"
                "selftest: ram static=%u stack_high_water=%u heap_high_water=%u total=%u (budget 32768); "
                "heap_allocs_after_start=%lu; tasks=%u\n",
                static_cast<unsigned long>(step_counts), kSteps - 19, static_cast<double>(step_counts) / (kSteps - 19),
                40.0 * static_cast<double>(step_counts) / (kSteps - 19), cyc1 != cyc0 ? 1 : 0,
                static_cast<unsigned>(static_ram), static_cast<unsigned>(board::stack_high_water()),
                static_cast<unsigned>(heap.high_water), static_cast<unsigned>(ram),
                static_cast<unsigned long>(allocations), static_cast<unsigned>(graph->node->task_count()));
  board::print(buf);
  for (const os::LogEntry& e : graph->node->log().since(0))
    board::print("selftest: log: " + os::format_log_entry(e) + "\n");
  board::print(failures == 0 ? "selftest: PASS\n" : "selftest: FAIL\n");
  return failures == 0 ? 0 : 1;
}
