// Prefetch: asking the memory system for bytes a little before they are read. Only a hint (no
// effect on behaviour); what it is for is a loop over many independent pieces of state that no
// longer fit in the cache (a large swarm's lanes), where each piece is a chain of pointers.
#pragma once

#include <cstddef>

namespace symb::kernel {

inline constexpr std::size_t kCacheLine = 64;

// The line holding p, into the level-2 cache, not the level-1 (locality 1: prefetcht2). A swarm's
// lanes ask for a hundred lines or so each, a dozen lanes ahead: more than the level-1 cache
// holds, so lines asked for into it pushed out each other and the lines in use. Measured at
// 10,000 robots (symb run, alternately, 2 threads): 2.5-2.6 s of stepping for 4 simulated s with
// locality 3 (prefetcht0) or 0 (prefetchnta), 2.0-2.1 s with 1, 2.1-2.2 s with 2.
inline void prefetch_line(const void* p) { __builtin_prefetch(p, 0, 1); }

// The cache lines at p, p + 64, ... below p + bytes: when p is not at a line's start the last
// line of the range is left out. Covering it too (the object's last partial line: one line more
// in most calls) made the 10,000-robot run above 50 % slower (2.0 -> 3.0 s, alternately, three
// runs each); why is not established, so the cheaper reading stays.
inline void prefetch_bytes(const void* p, std::size_t bytes) {
  const auto* c = static_cast<const char*>(p);
  for (std::size_t off = 0; off < bytes; off += kCacheLine) prefetch_line(c + off);
}

}  // namespace symb::kernel
