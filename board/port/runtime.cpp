#include "port/runtime.hpp"

#include <unistd.h>

#include <cstdlib>
#include <cstring>

extern "C" {
extern char __heap_start[];
extern char __heap_limit[];
extern char __stack_bottom[];
extern char __stack_top[];
void* __real_malloc(std::size_t n);
void* __real_calloc(std::size_t n, std::size_t size);
void* __real_realloc(void* p, std::size_t n);
}

namespace symb::board {
namespace {

// The hardware's one heap and one stack: their counters are the board's, not a framework global.
struct Heap {
  std::uint64_t allocations = 0;
  std::size_t largest = 0;
  char* top = nullptr;
};
Heap heap;

}  // namespace

HeapStats heap_stats() {
  const char* top = heap.top != nullptr ? heap.top : __heap_start;
  return {heap.allocations, static_cast<std::size_t>(top - __heap_start),
          static_cast<std::size_t>(__heap_limit - __heap_start), heap.largest};
}

std::size_t stack_size() { return static_cast<std::size_t>(__stack_top - __stack_bottom); }

std::size_t stack_high_water() {
  const auto* p = reinterpret_cast<const std::uint32_t*>(__stack_bottom);
  const auto* end = reinterpret_cast<const std::uint32_t*>(__stack_top);
  while (p < end && *p == 0xa5a5a5a5u) ++p;
  return static_cast<std::size_t>(reinterpret_cast<const char*>(end) - reinterpret_cast<const char*>(p));
}

void print(std::string_view text) { (void)::write(1, text.data(), text.size()); }

void exit_with(int code) { std::_Exit(code); }

}  // namespace symb::board

void symb_board_fatal(const char* why) {
  symb::board::print("board: fatal: ");
  symb::board::print(why);
  symb::board::print("\n");
  symb::board::exit_with(70);
}

extern "C" {

void* __wrap_malloc(std::size_t n) {
  ++symb::board::heap.allocations;
  if (n > symb::board::heap.largest) symb::board::heap.largest = n;
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t n, std::size_t size) {
  ++symb::board::heap.allocations;
  return __real_calloc(n, size);
}
void* __wrap_realloc(void* p, std::size_t n) {
  ++symb::board::heap.allocations;
  return __real_realloc(p, n);
}

// The heap's arena: from the end of .bss up to the end of RAM; its top is the high-water.
void* __wrap__sbrk(std::ptrdiff_t increment) {
  auto& h = symb::board::heap;
  if (h.top == nullptr) h.top = __heap_start;
  if (increment > __heap_limit - h.top || increment < __heap_start - h.top) return reinterpret_cast<void*>(-1);
  char* old = h.top;
  h.top += increment;
  return old;
}

// What static destructors register against (crtbegin.o's, not linked: -nostartfiles).
void* __dso_handle = &__dso_handle;

// newlib's __libc_init_array calls these (crti.o is not linked: -nostartfiles).
void _init() {}
void _fini() {}

// 64-bit atomics: a Cortex-M3 has none (LDREXD is ARMv7-A), and newlib ships no libatomic. The
// shared layers' 64-bit counters are written by one context; interrupts are masked for the
// access so an interrupt never sees half a value.
namespace {
std::uint32_t mask() {
  std::uint32_t primask;
  __asm volatile("mrs %0, primask\n cpsid i" : "=r"(primask)::"memory");
  return primask;
}
void unmask(std::uint32_t primask) { __asm volatile("msr primask, %0" ::"r"(primask) : "memory"); }
}  // namespace

std::uint64_t __atomic_load_8(const volatile void* p, int) {
  const std::uint32_t m = mask();
  const std::uint64_t v = *static_cast<const volatile std::uint64_t*>(p);
  unmask(m);
  return v;
}
void __atomic_store_8(volatile void* p, std::uint64_t v, int) {
  const std::uint32_t m = mask();
  *static_cast<volatile std::uint64_t*>(p) = v;
  unmask(m);
}
std::uint64_t __atomic_exchange_8(volatile void* p, std::uint64_t v, int) {
  const std::uint32_t m = mask();
  const std::uint64_t old = *static_cast<volatile std::uint64_t*>(p);
  *static_cast<volatile std::uint64_t*>(p) = v;
  unmask(m);
  return old;
}
std::uint64_t __atomic_fetch_add_8(volatile void* p, std::uint64_t v, int) {
  const std::uint32_t m = mask();
  const std::uint64_t old = *static_cast<volatile std::uint64_t*>(p);
  *static_cast<volatile std::uint64_t*>(p) = old + v;
  unmask(m);
  return old;
}
std::uint64_t __atomic_fetch_sub_8(volatile void* p, std::uint64_t v, int) {
  const std::uint32_t m = mask();
  const std::uint64_t old = *static_cast<volatile std::uint64_t*>(p);
  *static_cast<volatile std::uint64_t*>(p) = old - v;
  unmask(m);
  return old;
}
bool __atomic_compare_exchange_8(volatile void* p, void* expected, std::uint64_t desired, bool, int, int) {
  const std::uint32_t m = mask();
  auto* e = static_cast<std::uint64_t*>(expected);
  const std::uint64_t cur = *static_cast<volatile std::uint64_t*>(p);
  const bool ok = cur == *e;
  if (ok)
    *static_cast<volatile std::uint64_t*>(p) = desired;
  else
    *e = cur;
  unmask(m);
  return ok;
}

}  // extern "C"

namespace symb::board {

std::string_view command_line() {
  static char text[256];
  struct Block {
    char* buffer;
    int length;
  } block{text, static_cast<int>(sizeof text)};
  register int op asm("r0") = 0x15;  // SYS_GET_CMDLINE
  register Block* arg asm("r1") = &block;
  __asm volatile("bkpt 0xab" : "+r"(op) : "r"(arg) : "memory");
  if (op != 0) return {};
  return {text, static_cast<std::size_t>(block.length)};
}

}  // namespace symb::board
