// bump(): adds to a counter that one thread writes (a task's own context) and any thread may read
// (stats getters). A relaxed load and store instead of a locked read-modify-write: on a control
// step's path a dozen such counts cost as much as a message delivery.
#pragma once

#include <atomic>
#include <cstdint>

namespace symb::kernel {

inline void bump(std::atomic<std::uint64_t>& counter, std::uint64_t n = 1) {
  counter.store(counter.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
}

}  // namespace symb::kernel
