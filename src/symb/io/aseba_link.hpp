// AsebaLink: the host's end of an Aseba connection over any byte stream: a USB serial line to a
// Thymio II (io::SerialPort on /dev/ttyACM0), a TCP connection to Aseba Playground or to Aseba's
// switch (io::TcpStream), a loopback pair in tests. It finds nodes (list nodes -> node present),
// reads a node's description with its named variables, reads and writes variables by address and
// sends and receives user events (aseba_message.hpp has the wire format).
//
// Use: one thread owns reading (discover, describe, get, pump: each waits for its answer up to a
// timeout, handing user events that arrive meanwhile to the event handler); any thread may write
// at the same time (set, emit), as a task applying a wheel command does. Nothing a node sends is
// trusted: messages are bounded (AsebaDecoder), descriptions checked (DescriptionBuilder), a
// variables reply is taken only when it is the block that was asked for, inside the node's
// memory, and every refusal is counted in stats() by cause. After a stream error the link is
// unusable until the stream is open again and reset() is called (a reconnect).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "symb/io/aseba_description.hpp"
#include "symb/io/aseba_message.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::io::aseba {

struct LinkStats {
  DecoderStats decoder;           // bytes, whole messages, oversized (skipped)
  std::uint64_t malformed = 0;    // whole messages whose payload did not read (half a word, a short string)
  std::uint64_t bad_address = 0;  // variables replies outside the node's memory
  std::uint64_t unasked = 0;      // variables replies for another block or node (a late answer)
  std::uint64_t ignored = 0;      // messages the host has no use for (event and function descriptions, ...)
  std::uint64_t user_events = 0;  // handed to the event handler
  std::uint64_t requests = 0;     // get variables sent
  std::uint64_t replies = 0;      // ... answered
  std::uint64_t timeouts = 0;     // ... not answered in time
  std::uint64_t writes = 0;       // messages written
  std::uint64_t write_errors = 0;

  // Messages (or bytes) refused as hostile or broken.
  std::uint64_t refused() const { return decoder.oversized + malformed + bad_address; }
};

// "12 messages, 0 refused (oversized 0, malformed 0, bad address 0), 0 unasked, 3 requests 3 replies 0 timeouts"
std::string describe(const LinkStats& s);

class AsebaLink {
 public:
  using EventHandler = std::function<void(std::uint16_t source, std::uint16_t event, std::span<const std::int16_t>)>;

  explicit AsebaLink(std::shared_ptr<IOStream> stream, std::size_t max_payload = kMaxPayload);

  IOStream& stream() { return *stream_; }
  const std::shared_ptr<IOStream>& shared_stream() const { return stream_; }
  // User events from nodes (set before reading starts).
  void on_event(EventHandler handler) { on_event_ = std::move(handler); }

  // Sends list nodes and waits up to `timeout` for the first node present: that node's id.
  kernel::Result<std::uint16_t> discover(kernel::Duration timeout);
  // Asks `node` for its description and waits up to `timeout` for all of it.
  kernel::Result<NodeDescription> describe(std::uint16_t node, kernel::Duration timeout);
  // Reads `count` words at `start` of the described node, waiting up to `timeout`.
  kernel::Result<std::vector<std::int16_t>> get(const NodeDescription& node, std::uint16_t start, std::uint16_t count,
                                                kernel::Duration timeout);
  // Writes `values` at `start` (any thread). Refused when outside the node's memory.
  kernel::Status set(const NodeDescription& node, std::uint16_t start, std::span<const std::int16_t> values);
  // Sends user event `event` with `args` to every node (any thread).
  kernel::Status emit(std::uint16_t event, std::span<const std::int16_t> args);
  // Reads and handles what arrives for up to `timeout` (events go to the handler). An error when
  // the stream ended or failed.
  kernel::Status pump(kernel::Duration timeout);

  // Forgets a half-received message, after the stream was opened again.
  void reset();
  LinkStats stats() const;

 private:
  kernel::Status write(std::span<const std::byte> wire);
  // Reads once (up to `timeout`) and hands every whole message to `on`, which returns true for a
  // message it took; the rest are handled here (events, counts).
  template <class On>
  kernel::Status read_once(kernel::Duration timeout, On&& on);
  void handle_unclaimed(const Message& m);
  template <class F>
  void count(F&& f) {
    std::lock_guard lock(stats_mu_);
    f(stats_);
  }

  std::shared_ptr<IOStream> stream_;
  AsebaDecoder decoder_;
  EventHandler on_event_;
  std::mutex write_mu_;
  mutable std::mutex stats_mu_;
  LinkStats stats_;
  std::vector<std::byte> buffer_;
};

}  // namespace symb::io::aseba
