// Huge pages under a big swarm's heap. A robot is many small objects (its node, task records,
// queues, devices, controller state), and a world step touches every robot's: at thousands of
// robots that is hundreds of MB of heap, where with 4 KiB pages nearly every cache miss also
// misses the TLB and walks the page tables. Once such a run is built, its heap is marked for
// transparent huge pages and collapsed into 2 MiB pages at once (madvise MADV_HUGEPAGE, then
// MADV_COLLAPSE: Linux 6.1 and later); the robots' objects keep their addresses, so the run is
// the same run. Where the kernel cannot (THP off, an older kernel), the run goes on as it was and
// the note says why.
#pragma once

#include <cstddef>
#include <string>

namespace symb::apps::run {

struct HugePageHeap {
  std::size_t heap_bytes = 0;  // the heap's size when it was asked
  std::size_t huge_bytes = 0;  // anonymous memory of this process on huge pages afterwards
  double seconds = 0;          // what collapsing took
  std::string note;            // one line for summary.txt: what was done, or why not
};

// Collapses the process's heap ([heap] in /proc/self/maps) into transparent huge pages.
HugePageHeap back_heap_with_huge_pages();

// This process's anonymous memory on transparent huge pages (AnonHugePages of
// /proc/self/smaps_rollup), in bytes; 0 when unknown.
std::size_t huge_page_bytes();

}  // namespace symb::apps::run
