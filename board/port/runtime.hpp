// The board's runtime services: stopping with a reason, the heap's counters (every malloc is
// counted, so a test can show the message path allocates nothing after start-up), the stack's
// high-water, semihosting output and exit (QEMU's exit code is the image's).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

[[noreturn]] void symb_board_fatal(const char* why);

namespace symb::board {

struct HeapStats {
  std::uint64_t allocations = 0;  // malloc, calloc and realloc calls since reset
  std::size_t high_water = 0;     // bytes the heap's arena reached (sbrk's top)
  std::size_t limit = 0;          // bytes the arena may reach
  std::size_t largest = 0;        // the largest single request
};
HeapStats heap_stats();
// Bytes of the reserved stack ever used (the stack is painted at reset).
std::size_t stack_high_water();
std::size_t stack_size();

// Text to the host over semihosting (QEMU's stdout).
void print(std::string_view text);
// Ends the run: QEMU exits with `code`.
[[noreturn]] void exit_with(int code);

}  // namespace symb::board

namespace symb::board {
// The command line QEMU was given with -append (semihosting SYS_GET_CMDLINE), or empty.
std::string_view command_line();
}  // namespace symb::board
