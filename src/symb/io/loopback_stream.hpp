// Loopback streams: two in-memory IOStreams joined back to back, what one writes the other reads.
// For tests and for wiring a shell or a board to a simulator inside one process without a
// pseudo-terminal. Bounded: a writer waits (up to a second) for room rather than growing memory.
#pragma once

#include <memory>
#include <utility>

#include "symb/io/stream.hpp"

namespace symb::io {

// Returns the two ends, named `<name>.a` and `<name>.b`, both open. Closing either end makes the
// other read end-of-stream once it has drained what was written before.
std::pair<std::unique_ptr<IOStream>, std::unique_ptr<IOStream>> make_loopback_pair(const std::string& name,
                                                                                   std::size_t capacity = 65536);

}  // namespace symb::io
