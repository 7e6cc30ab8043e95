// Aseba messages: how a host talks to a Thymio II (and to Aseba Playground's simulated robots,
// which speak the same protocol on TCP). Protocol version 5, little-endian throughout:
//
//   u16 payload length in bytes | u16 source node | u16 type | payload
//
// The payload is a sequence of fields: u16 words (variable addresses, counts, values as int16)
// and strings (a length byte, then that many characters). Types below 0x8000 are user events
// (the payload is the event's arguments, one word each); the protocol's own messages are above.
// The host's own source id is 0.
//
// What is here: the message types the host uses, encoders for what the host sends, a payload
// reader for what nodes send, and AsebaDecoder, which cuts a byte stream into messages. The
// decoder trusts nothing: a payload longer than its limit (Aseba's own packets are at most a few
// hundred bytes) is skipped byte by byte without being stored, and counted; everything else is
// handed on whole, to be checked field by field by whoever reads it (AsebaReader refuses a read
// past the end with the byte offset it stopped at).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::io::aseba {

inline constexpr std::uint16_t kProtocolVersion = 5;
inline constexpr std::uint16_t kHostId = 0;
inline constexpr std::size_t kHeaderBytes = 6;
// The longest payload the decoder keeps. Aseba's largest messages (a native function's
// description, a bytecode chunk) stay well below it.
inline constexpr std::size_t kMaxPayload = 1024;

// Message types (Aseba's msg.h numbering).
namespace type {
// node -> host
inline constexpr std::uint16_t kDescription = 0x9000;
inline constexpr std::uint16_t kNamedVariableDescription = 0x9001;
inline constexpr std::uint16_t kLocalEventDescription = 0x9002;
inline constexpr std::uint16_t kNativeFunctionDescription = 0x9003;
inline constexpr std::uint16_t kVariables = 0x9005;
inline constexpr std::uint16_t kNodePresent = 0x900C;
// host -> node(s)
inline constexpr std::uint16_t kGetVariables = 0xA00B;
inline constexpr std::uint16_t kSetVariables = 0xA00C;
inline constexpr std::uint16_t kGetNodeDescription = 0xA010;
inline constexpr std::uint16_t kListNodes = 0xA011;
// Below this: user events.
inline constexpr std::uint16_t kFirstSystem = 0x8000;
}  // namespace type

struct Message {
  std::uint16_t source = 0;
  std::uint16_t type = 0;
  std::vector<std::byte> payload;

  bool is_user_event() const { return type < type::kFirstSystem; }
};

// The wire bytes of one message (header and payload). An error when the payload is longer than
// kMaxPayload: a peer would drop it.
kernel::Result<std::vector<std::byte>> encode(std::uint16_t source, std::uint16_t type,
                                              std::span<const std::byte> payload);

// Builds a payload field by field.
class AsebaWriter {
 public:
  AsebaWriter& word(std::uint16_t w);
  AsebaWriter& words(std::span<const std::int16_t> ws);
  // At most 255 bytes (a length byte); longer text is an error at finish().
  AsebaWriter& string(std::string_view s);
  kernel::Result<std::vector<std::byte>> finish(std::uint16_t source, std::uint16_t type) const;
  const std::vector<std::byte>& payload() const { return payload_; }

 private:
  std::vector<std::byte> payload_;
  bool too_long_ = false;
};

// The host's requests, whole messages from source kHostId.
std::vector<std::byte> list_nodes();
std::vector<std::byte> get_node_description(std::uint16_t node);
std::vector<std::byte> get_variables(std::uint16_t node, std::uint16_t start, std::uint16_t count);
// `values` must fit a payload: at most (kMaxPayload - 4) / 2 words (an error otherwise).
kernel::Result<std::vector<std::byte>> set_variables(std::uint16_t node, std::uint16_t start,
                                                     std::span<const std::int16_t> values);
kernel::Result<std::vector<std::byte>> user_event(std::uint16_t event, std::span<const std::int16_t> args);

// Reads a payload field by field. Each read past the end fails with the offset it needed.
class AsebaReader {
 public:
  explicit AsebaReader(std::span<const std::byte> payload) : p_(payload) {}
  kernel::Result<std::uint16_t> word();
  kernel::Result<std::string> string();
  std::size_t offset() const { return at_; }
  std::size_t left() const { return p_.size() - at_; }

 private:
  std::span<const std::byte> p_;
  std::size_t at_ = 0;
};

// The payloads nodes send, read and checked.
struct NodePresent {
  std::uint16_t version = 0;
};
kernel::Result<NodePresent> read_node_present(const Message& m);

struct Variables {
  std::uint16_t start = 0;
  std::vector<std::int16_t> values;
};
// An odd payload length (half a word) is an error.
kernel::Result<Variables> read_variables(const Message& m);

// A user event's arguments (an odd payload length is an error).
kernel::Result<std::vector<std::int16_t>> read_event_args(const Message& m);

struct DecoderStats {
  std::uint64_t bytes = 0;      // fed
  std::uint64_t messages = 0;   // handed on whole
  std::uint64_t oversized = 0;  // payload longer than the limit: skipped unread
};

// Cuts a byte stream into messages. Memory is bounded by the payload limit whatever arrives.
class AsebaDecoder {
 public:
  explicit AsebaDecoder(std::size_t max_payload = kMaxPayload) : max_payload_(max_payload) {}

  // Calls on_message(const Message&) for every whole message in `bytes` (the message is valid
  // during the call only).
  template <class OnMessage>
  void feed(std::span<const std::byte> bytes, OnMessage&& on_message) {
    stats_.bytes += bytes.size();
    while (!bytes.empty()) {
      const std::size_t used = step(bytes);
      bytes = bytes.subspan(used);
      if (ready_) {
        ready_ = false;
        ++stats_.messages;
        on_message(static_cast<const Message&>(current_));
      }
    }
  }
  const DecoderStats& stats() const { return stats_; }
  // Drops a half-received message (after a reconnect) without counting it.
  void reset();
  // Bytes of a message in progress (header or payload).
  bool mid_message() const { return header_have_ > 0 || payload_left_ > 0 || skip_left_ > 0; }

 private:
  // Consumes a prefix of `bytes`; sets ready_ when a message is complete.
  std::size_t step(std::span<const std::byte> bytes);

  std::size_t max_payload_;
  std::byte header_[kHeaderBytes]{};
  std::size_t header_have_ = 0;
  std::size_t payload_left_ = 0;
  std::size_t skip_left_ = 0;
  bool ready_ = false;
  Message current_;
  DecoderStats stats_;
};

}  // namespace symb::io::aseba
