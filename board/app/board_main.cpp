// symb-board.elf: the maze robot's node on QEMU's mps2-an385, the board end of hardware in the
// loop (docs/board.md). UART0 carries the frames to and from `symb sim`; UART1 carries the command
// shell (`symb shell --serial`). Semihosting prints the node's log and, at the end, the
// board-stats line with the heap, stack and executor figures.
//
//   qemu-system-arm -machine mps2-an385 -cpu cortex-m3 -display none -monitor none
//     -semihosting-config enable=on,target=native -serial pty -serial pty
//     -kernel symb-board.elf -append "--duration 20 --seed 1"
//
// --duration S: stop after S seconds of board time (default: run until QEMU is stopped);
// --seed N: the scenario's seed (default 1, scenarios/maze.yaml's).
#include <charconv>
#include <cstdio>
#include <memory>
#include <string>

#include "symb/kernel/bare_metal_executor.hpp"
#include "symb/shell/shell_task.hpp"

#include "app/maze_graph.hpp"
#include "mps2/mps2.hpp"
#include "mps2/uart.hpp"
#include "port/runtime.hpp"

namespace {

using namespace symb;
using namespace std::chrono_literals;

// The value after `name` in the command line, or `fallback`.
std::uint64_t option(std::string_view line, std::string_view name, std::uint64_t fallback) {
  const auto at = line.find(name);
  if (at == std::string_view::npos) return fallback;
  std::string_view rest = line.substr(at + name.size());
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  std::uint64_t v = fallback;
  std::from_chars(rest.data(), rest.data() + rest.size(), v);
  return v;
}

// The node's log on the semihosting console, as `symb board` prints it on stderr.
class SemihostingLogSink final : public os::LogSink {
 public:
  void write(const os::LogEntry& e) override { board::print("board thymio: " + os::format_log_entry(e) + "\n"); }
};

}  // namespace

int main() {
  const std::string_view line = board::command_line();
  const std::uint64_t duration_s = option(line, "--duration", 0);
  const std::uint64_t seed = option(line, "--seed", 1);

  kernel::BareMetalExecutor executor(1ms, 12, [](const char* why) { symb_board_fatal(why); });
  auto& hooks = board::mps2::interrupt_hooks();
  hooks.systick = [](void* e) { static_cast<kernel::BareMetalExecutor*>(e)->on_tick_interrupt(); };
  hooks.systick_context = &executor;

  auto built = board::build_maze_graph(executor, seed);
  if (!built) symb_board_fatal(built.error().c_str());
  std::unique_ptr<board::MazeGraph> graph = std::move(built).value();
  auto data = std::make_shared<board::mps2::CmsdkUart>("uart0", 0);
  auto shell_port = std::make_shared<board::mps2::CmsdkUart>("uart1", 1);
  (void)data->open();
  (void)shell_port->open();
  if (auto st = board::attach_maze_link(*graph, data); !st) symb_board_fatal(st.error().c_str());
  os::Node& node = *graph->node;
  auto sink = std::make_shared<SemihostingLogSink>();
  for (const os::LogEntry& e : node.log().since(0)) sink->write(e);
  node.log().add_sink(sink);

  auto devices = std::make_shared<shell::DeviceTable>();
  (*devices)["uart0"] = data;
  (*devices)["uart1"] = shell_port;
  shell::ShellOptions so;
  so.devices = devices;
  // A person's lines and the replies to them: 4 messages each way, each taken at once by the
  // task after it (Linux: 256 and 64, 52 KB of messages here).
  so.input_queue = 4;
  so.output_queue = 4;
  if (auto attached = shell::attach_shell(node, shell_port, so); !attached) symb_board_fatal(attached.error().c_str());
  executor.run_ready();  // every task started
  board::print(
      "board: robot thymio of maze on uart0, shell on uart1; " + std::to_string(node.task_count()) + " tasks; " +
      (duration_s > 0 ? "stops after " + std::to_string(duration_s) + " s" : std::string("runs until QEMU stops")) +
      " [" + std::string(line) + "]\n");

  const std::uint64_t allocations_at_start = board::heap_stats().allocations;
  board::mps2::start_systick(1000);
  const kernel::Time end = duration_s > 0 ? kernel::Time{std::chrono::seconds(duration_s)} : kernel::kTimeNever;
  // The message path's heap use is counted from the 20th IR frame on (the first frames grow
  // what grows once: the log, the hooks' counters).
  // It ends with the last frame: the log lines of a link lost after it are not the message path.
  std::uint64_t allocations_in_run_from = 0, allocations_in_run_to = 0, frames_seen = 0;
  // RAM in use: static data, the stack's and the heap's high-water. ram_maze is taken at the 20th
  // frame (start-up and the maze graph running); the shell's commands add their replies' text.
  auto ram_now = [] {
    extern char __data_start[], __bss_end[];
    return static_cast<std::size_t>(__bss_end - __data_start) + board::stack_high_water() +
           board::heap_stats().high_water;
  };
  std::size_t ram_maze = 0;
  bool counting = false;
  while (executor.now() < end) {
    if (executor.run_ready() == 0) board::mps2::wait_for_interrupt();
    if (graph->stats.ir_frames != frames_seen) {
      frames_seen = graph->stats.ir_frames;
      if (!counting && frames_seen >= 20) {
        counting = true;
        allocations_in_run_from = board::heap_stats().allocations;
        ram_maze = ram_now();
      }
      allocations_in_run_to = board::heap_stats().allocations;
    }
  }

  const board::HeapStats heap = board::heap_stats();
  const kernel::BareMetalStats ex = executor.stats();
  const std::size_t ram = ram_now();
  char buf[400];
  board::format_board_stats(graph->stats, buf, sizeof buf);
  board::print(std::string(buf));
  std::snprintf(buf, sizeof buf,
                " heap_allocs_after_start=%lu heap_allocs_in_run=%lu heap_high_water=%u stack_high_water=%u "
                "ram_maze=%u ram=%u ram_budget=32768 handlers=%lu ticks_late=%lu rx_holds=%u\n",
                static_cast<unsigned long>(heap.allocations - allocations_at_start),
                static_cast<unsigned long>(counting ? allocations_in_run_to - allocations_in_run_from : 0),
                static_cast<unsigned>(heap.high_water), static_cast<unsigned>(board::stack_high_water()),
                static_cast<unsigned>(ram_maze), static_cast<unsigned>(ram), static_cast<unsigned long>(ex.handlers),
                static_cast<unsigned long>(ex.ticks_late),
                static_cast<unsigned>(data->rx_holds() + shell_port->rx_holds()));
  board::print(buf);
  // The maze graph over the RAM budget is a failed run (exit 3), as a dead link is for `symb board`.
  if (ram_maze > 32 * 1024) return 3;
  return 0;
}
