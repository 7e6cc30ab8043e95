// FrameQueue: the frames waiting to go to one browser, between the run that makes them and the
// thread that writes them to the socket (civetweb's mg_websocket_write blocks until the client
// has taken the bytes). Bounded: when it is full, push() drops the oldest frame and counts it, so
// the run never waits for a slow or stalled client; the client sees the newest state and a frame
// counter with a gap. A frame the consumer took is still queued until it says whether it wrote
// it (done()): a write cut short (the server stopping under it) is a frame the client never got,
// and whoever waits for the queue to empty must wait for the write too. The counters close:
// pushed = sent + dropped + queued.
//
// Thread use: any number of producers (push), one consumer (pop, done). push() holds the queue's
// lock only to move a string in or out: it never waits on the consumer or the socket.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "symb/kernel/time.hpp"

namespace symb::apps::view {

struct FrameQueueStats {
  std::uint64_t pushed = 0;   // push() calls while open
  std::uint64_t sent = 0;     // frames written (done(true))
  std::uint64_t dropped = 0;  // overtaken while the queue was full, left at close, or not written
  std::size_t queued = 0;     // waiting now, the one being written included
};

class FrameQueue {
 public:
  // Throws std::invalid_argument when `capacity` is 0.
  explicit FrameQueue(std::size_t capacity);

  // Appends `frame`; when the queue is full the oldest one goes (counted as dropped). After
  // close(), frames are discarded without being counted. Never blocks for longer than it takes
  // to move the string.
  void push(std::string frame);
  // The oldest frame, waiting up to `timeout` for one; nothing on timeout or once closed. The
  // consumer calls done() once it has tried to write it, before the next pop().
  std::optional<std::string> pop(kernel::Duration timeout);
  // The frame pop() gave out was written (sent) or not (dropped).
  void done(bool written);
  // Wakes the consumer; from then on pop() returns nothing and push() discards. Frames still
  // queued count as dropped.
  void close();
  bool closed() const;

  FrameQueueStats stats() const;
  std::size_t capacity() const { return capacity_; }

 private:
  const std::size_t capacity_;
  mutable std::mutex mu_;
  std::condition_variable ready_;
  std::deque<std::string> frames_;
  FrameQueueStats stats_;
  bool writing_ = false;  // a popped frame not yet done()
  bool closed_ = false;
};

}  // namespace symb::apps::view
