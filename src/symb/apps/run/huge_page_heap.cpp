#include "symb/apps/run/huge_page_heap.hpp"

#include <sys/mman.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::run {
namespace {

#ifndef MADV_COLLAPSE
constexpr int MADV_COLLAPSE = 25;  // Linux 6.1's value; older headers lack it
#endif

std::string megabytes(std::size_t bytes) { return fixed(static_cast<double>(bytes) / (1 << 20), 0) + " MB"; }

}  // namespace

std::size_t huge_page_bytes() {
  std::ifstream rollup("/proc/self/smaps_rollup");
  std::string line;
  while (std::getline(rollup, line)) {
    std::istringstream fields(line);
    std::string key;
    std::size_t kib = 0;
    if (fields >> key >> kib && key == "AnonHugePages:") return kib * 1024;
  }
  return 0;
}

HugePageHeap back_heap_with_huge_pages() {
  HugePageHeap result;
  std::ifstream maps("/proc/self/maps");
  std::string line;
  std::uintptr_t begin = 0, end = 0;
  while (std::getline(maps, line)) {
    if (line.find("[heap]") == std::string::npos) continue;
    std::istringstream range(line);
    char dash = 0;
    range >> std::hex >> begin >> dash >> end;
    break;
  }
  if (end <= begin) {
    result.note = "heap: on 4 KiB pages (no [heap] in /proc/self/maps)";
    return result;
  }
  result.heap_bytes = end - begin;
  void* start = reinterpret_cast<void*>(begin);
  const auto started = std::chrono::steady_clock::now();
  // A collapse may fail for part of the range only (memory too fragmented for some 2 MiB pages):
  // what did move is counted either way.
  int failed = 0;
  if (::madvise(start, result.heap_bytes, MADV_HUGEPAGE) != 0 ||
      ::madvise(start, result.heap_bytes, MADV_COLLAPSE) != 0)
    failed = errno;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.huge_bytes = huge_page_bytes();
  result.note = "heap: " + megabytes(result.heap_bytes) + ", " + megabytes(result.huge_bytes) +
                " of the process on huge pages (collapsed in " + fixed(result.seconds, 2) + " s" +
                (failed != 0 ? std::string("; madvise: ") + std::strerror(failed) : std::string()) + ")";
  return result;
}

}  // namespace symb::apps::run
