// AER, address-event representation: the way neuromorphic chips exchange spikes. A spike is an
// event (address, timestamp); a set of them travels as one packet. Here spikes travel between
// tasks (over hooks) and between nodes (over links) in AER packets, as in the paper's Linda
// controller (IV-B).
//
// Address: 32 bits, the module (the node or network that emitted it) in the top kModuleBits and
// the neuron (or, for input and output channels, the channel number) in the low kNeuronBits, so
// several modules' spikes can share one bus and stay apart. Timestamp: 32-bit microseconds that
// wrap after about 71 minutes, exactly jAER's raw event and an AEDAT 2.0 record (aedat.hpp).
//
// In a node, a packet is a shared immutable Blob (AerPacket) that every hooked receiver reads
// without a copy. On a byte link it is encode_aer()'s form: a 4-byte big-endian event count, then
// per event the 32-bit address and 32-bit timestamp, big-endian (AEDAT's record layout).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/message.hpp"

namespace symb::control::snn {

inline constexpr unsigned kModuleBits = 8;
inline constexpr unsigned kNeuronBits = 24;
inline constexpr std::uint32_t kMaxModule = (1u << kModuleBits) - 1;
inline constexpr std::uint32_t kMaxNeuronAddress = (1u << kNeuronBits) - 1;
// More events than this in one packet (or one wire form) is an error: a bound for decoders.
inline constexpr std::size_t kMaxPacketEvents = 1u << 20;

constexpr std::uint32_t aer_address(std::uint32_t module, std::uint32_t neuron) {
  return (module << kNeuronBits) | (neuron & kMaxNeuronAddress);
}
constexpr std::uint32_t aer_module(std::uint32_t address) { return address >> kNeuronBits; }
constexpr std::uint32_t aer_neuron(std::uint32_t address) { return address & kMaxNeuronAddress; }

struct AerEvent {
  std::uint32_t address = 0;
  std::uint32_t timestamp_us = 0;
  bool operator==(const AerEvent&) const = default;
};

// The blob of a spike packet message. Events in non-decreasing timestamp order (not enforced:
// receivers must not rely on it for safety, only for speed).
class AerPacket final : public os::Blob {
 public:
  static constexpr std::uint32_t kKind = 0x41455250;  // "AERP"
  std::uint32_t kind() const override { return kKind; }

  AerPacket() = default;
  explicit AerPacket(std::vector<AerEvent> e) : events(std::move(e)) {}

  std::vector<AerEvent> events;
};

inline os::Payload aer_payload(std::vector<AerEvent> events) {
  return os::Payload(std::make_shared<const AerPacket>(std::move(events)));
}
// The packet a message carries, or nullptr when it carries none.
inline const AerPacket* aer_of(const os::Message& m) { return os::blob_as<AerPacket>(m.payload.blob.get()); }

// A node's time to an AER timestamp (us, wrapping at 2^32).
constexpr std::uint32_t aer_timestamp(kernel::Time t) {
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(t.count() / 1000));
}
// Back from an AER timestamp to node time (us): of the instants it may stand for (it wraps every
// 2^32 us, 71 minutes), the one nearest `now_us`.
constexpr std::int64_t unwrap_us(std::uint32_t timestamp, std::int64_t now_us) {
  return now_us + static_cast<std::int32_t>(timestamp - static_cast<std::uint32_t>(now_us));
}

// The wire form above. decode_aer() errors say "byte OFFSET: message" (a short buffer, a count
// that does not match the length, more than kMaxPacketEvents events); it never reads past `bytes`.
std::vector<std::byte> encode_aer(std::span<const AerEvent> events);
kernel::Result<std::vector<AerEvent>> decode_aer(std::span<const std::byte> bytes);

}  // namespace symb::control::snn
