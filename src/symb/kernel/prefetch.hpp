// Prefetch: asking the memory system for bytes a little before they are read. Only a hint (no
// effect on behaviour); what it is for is a loop over many independent pieces of state that no
// longer fit in the cache (a large swarm's lanes), where each piece is a chain of pointers.
#pragma once

#include <cstddef>

namespace symb::kernel {

inline constexpr std::size_t kCacheLine = 64;

// Every cache line of [p, p + bytes).
inline void prefetch_bytes(const void* p, std::size_t bytes) {
  const auto* c = static_cast<const char*>(p);
  for (std::size_t off = 0; off < bytes; off += kCacheLine) __builtin_prefetch(c + off);
}

}  // namespace symb::kernel
