// FrameCodec: how messages cross a byte stream (a serial line, TCP) intact. A frame is
//   0x00 | COBS( version | payload | CRC-16/CCITT-FALSE(version | payload), big-endian ) | 0x00
// COBS removes every zero byte from the body, so 0x00 only ever delimits frames: a receiver that
// lost its place (line noise, a reset, a cable pulled mid-frame) resynchronises at the next zero.
// The CRC catches corrupted bytes, the version byte catches a peer speaking another format, and a
// size limit bounds memory. Bad frames are counted by cause and dropped; good ones come out whole.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace symb::io {

inline constexpr std::uint8_t kFrameVersion = 1;

std::uint16_t crc16_ccitt(std::span<const std::byte> data, std::uint16_t crc = 0xFFFF);

// Appends the frame for `payload` to `out` (no allocation when `out` has the room).
// Writes the frame for `payload` into `out`, which must hold max_encoded_size(payload.size())
// bytes; returns the bytes written (0 when `out` is too small). The fastest form: nothing is
// allocated or zero-filled, so a sender keeps one buffer and reuses it.
std::size_t encode_frame(std::span<const std::byte> payload, std::span<std::byte> out);
void encode_frame(std::span<const std::byte> payload, std::vector<std::byte>& out);
std::vector<std::byte> encode_frame(std::span<const std::byte> payload);
// The most bytes encode_frame() appends for a payload of `n` bytes.
constexpr std::size_t max_encoded_size(std::size_t n) { return n + 3 + (n + 3) / 254 + 1 + 2; }

struct FrameStats {
  std::uint64_t frames = 0;        // good frames delivered
  std::uint64_t bytes = 0;         // bytes fed
  std::uint64_t crc_errors = 0;    // checksum mismatch (corrupted)
  std::uint64_t truncated = 0;     // too short to hold version and CRC
  std::uint64_t oversized = 0;     // longer than the payload limit
  std::uint64_t bad_encoding = 0;  // not valid COBS
  std::uint64_t bad_version = 0;   // another format version

  std::uint64_t dropped() const { return crc_errors + truncated + oversized + bad_encoding + bad_version; }
};

class FrameDecoder {
 public:
  explicit FrameDecoder(std::size_t max_payload = 1024);

  // Feeds bytes; calls on_frame(std::span<const std::byte> payload) for each good frame, in
  // order. The span is valid during the call only.
  template <class OnFrame>
  void feed(std::span<const std::byte> bytes, OnFrame&& on_frame) {
    stats_.bytes += bytes.size();
    while (!bytes.empty()) {
      // Frames are found with memchr and handled a whole segment at a time: a byte loop here
      // was the codec's bottleneck.
      const void* zero = std::memchr(bytes.data(), 0, bytes.size());
      if (zero == nullptr) {
        append(bytes);
        return;
      }
      const auto k = static_cast<std::size_t>(static_cast<const std::byte*>(zero) - bytes.data());
      bool good = false;
      if (encoded_.empty() && !overflow_) {
        good = finish(bytes.first(k));  // the whole frame is in this chunk: no copy
      } else {
        append(bytes.first(k));
        good = finish(encoded_);
      }
      if (good) on_frame(std::span<const std::byte>(decoded_.data() + 1, decoded_size_ - 3));
      bytes = bytes.subspan(k + 1);
    }
  }

  const FrameStats& stats() const { return stats_; }
  std::size_t max_payload() const { return max_payload_; }
  // Drops a partly received frame (e.g. after a reconnect) without counting it.
  void reset();

 private:
  // Keeps the bytes of a frame that continues in the next chunk (or notes that it is too long).
  void append(std::span<const std::byte> part);
  // Decodes one frame's bytes (between delimiters) into decoded_; true when they hold a good frame.
  bool finish(std::span<const std::byte> encoded);

  std::size_t max_payload_;
  std::size_t max_encoded_;
  std::vector<std::byte> encoded_;
  std::vector<std::byte> decoded_;  // sized once; decoded_size_ bytes of it are the current frame
  std::size_t decoded_size_ = 0;
  bool overflow_ = false;
  FrameStats stats_;
};

}  // namespace symb::io
