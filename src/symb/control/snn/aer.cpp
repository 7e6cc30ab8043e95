#include "symb/control/snn/aer.hpp"

#include <string>

namespace symb::control::snn {

namespace {

constexpr std::size_t kCountBytes = 4;
constexpr std::size_t kEventBytes = 8;

void put32(std::byte* p, std::uint32_t v) {
  p[0] = static_cast<std::byte>(v >> 24);
  p[1] = static_cast<std::byte>(v >> 16);
  p[2] = static_cast<std::byte>(v >> 8);
  p[3] = static_cast<std::byte>(v);
}

std::uint32_t get32(const std::byte* p) {
  return (std::to_integer<std::uint32_t>(p[0]) << 24) | (std::to_integer<std::uint32_t>(p[1]) << 16) |
         (std::to_integer<std::uint32_t>(p[2]) << 8) | std::to_integer<std::uint32_t>(p[3]);
}

kernel::Error at(std::size_t offset, const std::string& message) {
  return kernel::Error{"byte " + std::to_string(offset) + ": " + message};
}

}  // namespace

std::vector<std::byte> encode_aer(std::span<const AerEvent> events) {
  std::vector<std::byte> out(kCountBytes + kEventBytes * events.size());
  // A packet larger than 2^32 events cannot be counted; decoders refuse anything above
  // kMaxPacketEvents anyway, so the count is simply truncated.
  put32(out.data(), static_cast<std::uint32_t>(events.size()));
  std::byte* p = out.data() + kCountBytes;
  for (const AerEvent& e : events) {
    put32(p, e.address);
    put32(p + 4, e.timestamp_us);
    p += kEventBytes;
  }
  return out;
}

kernel::Result<std::vector<AerEvent>> decode_aer(std::span<const std::byte> bytes) {
  if (bytes.size() < kCountBytes)
    return at(0, "packet of " + std::to_string(bytes.size()) + " bytes is shorter than its 4-byte event count");
  const std::uint32_t count = get32(bytes.data());
  if (count > kMaxPacketEvents)
    return at(0,
              "event count " + std::to_string(count) + " is more than the limit " + std::to_string(kMaxPacketEvents));
  // Sizes in 64 bits: count <= 2^20 keeps this far from overflow on any target.
  const std::uint64_t expected = kCountBytes + std::uint64_t{kEventBytes} * count;
  if (bytes.size() < expected) {
    const std::size_t complete = (bytes.size() - kCountBytes) / kEventBytes;
    return at(kCountBytes + complete * kEventBytes, "packet ends inside event " + std::to_string(complete) + " of " +
                                                        std::to_string(count) + " (" + std::to_string(bytes.size()) +
                                                        " bytes, the count needs " + std::to_string(expected) + ")");
  }
  if (bytes.size() > expected)
    return at(static_cast<std::size_t>(expected), std::to_string(bytes.size() - expected) + " bytes after the " +
                                                      std::to_string(count) + " events the count announces");
  std::vector<AerEvent> events(count);
  const std::byte* p = bytes.data() + kCountBytes;
  for (AerEvent& e : events) {
    e.address = get32(p);
    e.timestamp_us = get32(p + 4);
    p += kEventBytes;
  }
  return events;
}

}  // namespace symb::control::snn
