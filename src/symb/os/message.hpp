// Message: what one send delivers to every hooked task (the paper's QueueMessage): the sending
// task's id, a port, the send time and a payload. Up to kInlineValues numbers travel inside the
// message itself, so sensor and actuator traffic never touches the heap; larger data (an image, a
// spike packet) travels as a shared, immutable Blob that all receivers read without a copy.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <span>

#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"

namespace symb::os {

// Base for large payloads. kind() tells receivers what it is without RTTI.
class Blob {
 public:
  virtual ~Blob() = default;
  virtual std::uint32_t kind() const = 0;
};

// Casts a blob to T when its kind() is T::kKind; nullptr otherwise.
template <class T>
const T* blob_as(const Blob* b) {
  return (b != nullptr && b->kind() == T::kKind) ? static_cast<const T*>(b) : nullptr;
}

// Copies n numbers (n <= 32, a payload's inline capacity), reading and writing none past them,
// as a few moves of fixed size that overlap where n is not one of those sizes. A copy of a
// variable count compiles to a call to memmove or to a `rep movs`, whose start-up alone costs
// more than moving the handful of numbers a message or a sensor sample carries (perf, the 1-robot
// maze: a sample's copies in Sensor::take were its costliest framework function). Always in
// line: a call and its return cost about as much as the moves themselves.
[[gnu::always_inline]] inline void copy_numbers(float* to, const float* from, std::size_t n) {
  const auto move = [&](std::size_t at, std::size_t count) { std::memcpy(to + at, from + at, count * sizeof(float)); };
  if (n >= 8) {
    if (n > 16) {
      move(0, 8);
      move(8, 8);
      if (n > 24) move(16, 8);
    } else {
      move(0, 8);
    }
    move(n - 8, 8);
  } else if (n >= 4) {
    move(0, 4);
    move(n - 4, 4);
  } else if (n >= 2) {
    move(0, 2);
    move(n - 2, 2);
  } else if (n == 1) {
    to[0] = from[0];
  }
}

struct Payload {
  static constexpr std::size_t kInlineValues = 32;

  std::uint8_t count = 0;
  // Before the numbers: what a message of a few numbers touches (the message's fields, the count,
  // the blob, values[0, count)) is then one run of bytes, two cache lines of a queue slot rather
  // than three (in a swarm every robot's queues are out of the cache at each step).
  std::shared_ptr<const Blob> blob;
  // Only values[0, count) is ever read. A default payload is all zeros; the others leave the
  // tail unwritten: a message is built and copied four times on its way from sender to handler,
  // most carry a handful of numbers, and clearing or copying all kInlineValues each time was a
  // fifth of a delivery's cost.
  float values[kInlineValues];

  Payload() : values{} {}
  // A payload whose numbers are left unset, to be assigned over (a message taken out of a queue).
  enum Unset { kUnset };
  explicit Payload(Unset) {}
  Payload(const Payload& o) : count(o.count), blob(o.blob) { copy_values(o); }
  Payload(Payload&& o) noexcept : count(o.count), blob(std::move(o.blob)) { copy_values(o); }
  Payload& operator=(const Payload& o) {
    if (this == &o) return *this;
    count = o.count;
    copy_values(o);
    blob = o.blob;
    return *this;
  }
  Payload& operator=(Payload&& o) noexcept {
    if (this == &o) return *this;
    count = o.count;
    copy_values(o);
    blob = std::move(o.blob);
    return *this;
  }
  ~Payload() = default;
  // Keeps the first kInlineValues numbers; callers with more use a Blob.
  explicit Payload(std::span<const float> v) { assign(v); }
  Payload(std::initializer_list<float> v) { assign({v.begin(), v.size()}); }
  explicit Payload(std::shared_ptr<const Blob> b) : blob(std::move(b)), values{} {}

  void assign(std::span<const float> v) {
    count = static_cast<std::uint8_t>(std::min(v.size(), kInlineValues));
    copy_numbers(values, v.data(), count);
  }
  std::span<const float> numbers() const { return {values, count}; }

 private:
  void copy_values(const Payload& o) { copy_numbers(values, o.values, o.count); }
};

// How many answers in a row a message may be: a message sent while handling a message is one hop
// further than it; one sent from on_start, on_tick or from outside any task starts again at 0. A
// chain longer than kMaxHops is a cycle of tasks that answer every message (a -> b -> a): it
// would keep a virtual-time run at one instant for ever and spin a thread executor's cores, so
// the node refuses the send that would exceed it and faults its sender, naming the cycle in the
// log and in Node::cycle_error() (symb run stops on it and fails). The longest chain in the shipped
// scenarios is 2 hops (Node::longest_chain() over 120 s of each), the longest bounded exchange in
// the project 1000 (bench_pingpong's batch of 500 round trips): the bound leaves them a margin of
// 5000 and 10, and still cuts a cycle within milliseconds (virtual time: about 2 ms of CPU). A
// cycle with a tick between answers is not cut: it advances.
// Whether every number is finite: what a handler checks before it acts on numbers from a hook
// (a NaN from a faulty sensor or a bad genome must not reach the wheels).
inline bool all_finite(std::span<const float> v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

inline constexpr std::uint16_t kMaxHops = 10000;

struct Message {
  TaskId source;  // invalid for messages posted from outside any task
  Port port = 0;
  std::uint16_t hops = 0;  // see kMaxHops; set by the node
  // The hook it came through, as the receiver's hook slot + 1 (0: posted); set by the node, for
  // the per-hook accounting. It and `hops` fill what was padding: the message is no larger.
  std::uint32_t edge = 0;
  kernel::Time time{0};  // the sender's node clock at send
  Payload payload;

  std::span<const float> numbers() const { return payload.numbers(); }
};
// Rounded up to the message's alignment: on a 32-bit target (the Cortex-M board) the payload's
// shared_ptr is 8 bytes, not 16, and the tail padding is the alignment's, not a grown field's.
static_assert(sizeof(Message) == (16 + sizeof(kernel::Time) + sizeof(Payload) + alignof(Message) - 1) /
                                     alignof(Message) * alignof(Message),
              "Message grew past its padding");

}  // namespace symb::os
