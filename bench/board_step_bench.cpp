// board_step_bench: the board's control step on the host, beside its figure on the Cortex-M3
// (docs/board.md). The same maze graph as symb-board.elf (board/app: link -> ir -> MDL2e
// controller -> wheels -> link on the BareMetalExecutor, over an in-memory line), the same
// files compiled for the host: one step is an IR frame in (COBS + CRC decoded), the controller's
// step, and the wheel frame out (encoded), the executor's tick included. The board's figure comes
// from its self-test under QEMU (`-icount shift=0`: instructions per step), printed by
//   qemu-system-arm -machine mps2-an385 -cpu cortex-m3 -nographic -icount shift=0
//     -semihosting-config enable=on,target=native -kernel build/board/symb-board-selftest.elf
#include <array>
#include <bit>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <benchmark/benchmark.h>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/bare_metal_executor.hpp"

#include "app/maze_graph.hpp"
#include "app/memory_line.hpp"

namespace symb::board {
// The board embeds the program at build time; the host reads the same file.
std::string_view maze_program_text() {
  static const std::string text = [] {
    std::ifstream in(std::string(SYMB_SCENARIO_DIR) + "/mdl2e/obstacle_avoidance.mdl2e");
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }();
  return text;
}
}  // namespace symb::board

namespace {

using namespace symb;
using namespace std::chrono_literals;

void BM_BoardControlStep(benchmark::State& state) {
  kernel::BareMetalExecutor executor(1ms, 8, [](const char* why) { throw std::runtime_error(why); });
  auto graph = board::build_maze_graph(executor, 1);
  if (!graph) throw std::runtime_error(graph.error());
  auto line = std::make_shared<board::MemoryLine>();
  if (auto st = board::attach_maze_link(**graph, line); !st) throw std::runtime_error(st.error());
  executor.run_ready();
  std::uint32_t seq = 0;
  std::size_t answered = 0;
  for (auto _ : state) {
    // A clear view (the controller drives on): [seq, 7 x 0].
    const float values[8] = {static_cast<float>(++seq), 0, 0, 0, 0, 0, 0, 0};
    const std::vector<std::byte> frame = io::encode_frame(io::encode_numbers(values));
    std::copy(frame.begin(), frame.end(), line->in.begin());
    line->in_size = frame.size();
    line->in_pos = 0;
    // Timed as on the board: the tick at which the frame is read, decoded, passed through the
    // controller and answered. The rest of the 30 ms period (the controller's own tick) is not.
    const auto t0 = std::chrono::steady_clock::now();
    executor.on_tick_interrupt();
    executor.run_ready();
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    for (int t = 1; t < 30; ++t) {
      executor.on_tick_interrupt();
      executor.run_ready();
    }
    answered += line->out_size > 0 ? 1 : 0;
    line->out_size = 0;
  }
  if (answered != static_cast<std::size_t>(state.iterations())) state.SkipWithError("a frame was not answered");
  state.counters["steps/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoardControlStep)->UseManualTime()->Unit(benchmark::kNanosecond);

}  // namespace

BENCHMARK_MAIN();
