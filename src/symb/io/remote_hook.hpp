// Remote hook: a hook whose sender and receiver live on different nodes, joined by a bus (the
// organism bus of docked modules, sim/mujoco/organism_bus.hpp; the DDS bus between processes,
// io/dds/dds_bus.hpp, which keeps these books but carries a message with no proxy task: see there).
// Hooks never cross nodes inside the os layer, so on the organism bus a remote hook is made of two
// local hooks and two proxy tasks:
//
//   sender --local hook (the remote hook's options)--> OutboundProxy  ==bus frames==>
//   InboundProxy --local hook--> receiver
//
// The outbound proxy, on the sender's node, encodes each message it handles as a hook frame and
// hands the bytes to a HookMedium; the medium delivers them (at its own pace) to the inbound
// proxy's queue as an io::Bytes message; the inbound proxy, on the receiver's node, decodes the
// frame and sends its numbers on, port preserved. The local hooks keep the local rules (port
// filter, priority, queue policy) and their own books; the medium keeps the books of the middle.
//
// Hook frame: the payload of one io frame (frame_codec.hpp: COBS, CRC, delimiters), so the bytes
// on the bus are real and a corrupted frame is caught by its CRC. Little-endian fields:
//   offset 0   u8    'H' (kHookFrameType; number frames are 'N')
//          1   u32   remote hook id
//          5   u32   sequence number (per remote hook, from 0)
//          9   i64   send time, ns of the sender's node clock
//         17   u16   port
//         19   u8    count of numbers (at most os::Payload::kInlineValues)
//         20   f32   x count
// so a hook frame's payload is 20 + 4 count bytes and its encoded frame hook_frame_wire_bytes()
// = payload + 6 (delimiters, version byte, CRC, one COBS code byte; one more per 254 bytes,
// which a 148-byte payload never reaches): 26 + 4 count bytes.
//
// Blob payloads (images, spike packets, io::Bytes) do not cross: the outbound proxy refuses them,
// counted as HookDrop::kBlob. Sensor- and hormone-sized data travels inline.
//
// Books of a remote hook (RemoteHookBooks), exact at every moment the nodes are quiet (between
// handlers under the virtual-time executor):
//   attempted == delivered + dropped() + in_flight
// where attempted are the sender's messages offered to the outbound local hook and delivered those
// the receiver handled; see RemoteHookBooks for what each cause counts.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"

namespace symb::io {

inline constexpr std::uint8_t kHookFrameType = 'H';
inline constexpr std::size_t kHookFrameHeader = 20;

struct HookFrame {
  std::uint32_t hook = 0;
  std::uint32_t sequence = 0;
  kernel::Time time{0};
  os::Port port = 0;
  os::Payload payload;  // numbers only
};

// Bytes of a hook frame's payload carrying `count` numbers, and of its encoded frame on the wire.
constexpr std::size_t hook_frame_payload_bytes(std::size_t count) { return kHookFrameHeader + 4 * count; }
constexpr std::size_t hook_frame_wire_bytes(std::size_t count) {
  return max_encoded_size(hook_frame_payload_bytes(count));
}

// Writes the whole encoded frame (delimiters included) of `frame` into `out` (replacing it).
void encode_hook_frame(const HookFrame& frame, std::vector<std::byte>& out);
// Parses a decoded frame payload (what FrameDecoder hands out); an error names the byte offset.
kernel::Result<HookFrame> parse_hook_frame(std::span<const std::byte> payload);

// Why a message of a remote hook did not arrive.
enum class HookDrop : std::uint8_t {
  kSender,     // the sender's side dropped it: the outbound proxy's queue (the hook's policy), an inhibition
  kBlob,       // it carried a blob: not carried over a bus
  kQueueFull,  // the sending module's transmit queue was full
  kLinkDown,   // the ends were apart when it was sent, or came apart while it travelled
  kDecode,     // the inbound proxy could not decode the frame
  kReceiver,   // the inbound proxy's or the receiver's queue refused it (or a window dropped it)
  kCount
};
const char* to_string(HookDrop cause);

struct RemoteHookBooks {
  std::uint64_t attempted = 0;
  std::uint64_t delivered = 0;
  std::array<std::uint64_t, static_cast<std::size_t>(HookDrop::kCount)> dropped_by{};
  std::uint64_t in_flight = 0;  // in either proxy's queue, in a transmit queue, on the wire

  std::uint64_t dropped() const {
    std::uint64_t n = 0;
    for (const auto d : dropped_by) n += d;
    return n;
  }
  std::uint64_t& dropped(HookDrop cause) { return dropped_by[static_cast<std::size_t>(cause)]; }
  std::uint64_t dropped(HookDrop cause) const { return dropped_by[static_cast<std::size_t>(cause)]; }
  bool closes() const { return attempted == delivered + dropped() + in_flight; }
};

// What the medium counts of one remote hook between the two proxies.
struct MediumBooks {
  std::uint64_t handed = 0;      // frames the outbound proxy handed over, blobs refused included
  std::uint64_t blob = 0;        // refused by the outbound proxy: blob payloads
  std::uint64_t queue_full = 0;  // refused by the transmit queue
  std::uint64_t link_down = 0;   // dropped: link down
  std::uint64_t in_medium = 0;   // queued, on the wire, or within the latency
  std::uint64_t posted = 0;      // put in the inbound proxy's queue
  std::uint64_t refused = 0;     // refused by the inbound proxy's queue
  std::uint64_t decode = 0;      // the inbound proxy could not decode them
};

// Sums the three stages: the outbound local hook, the medium, the inbound local hook. The
// inbound proxy's queue holds posted - decode - inbound.sent.
RemoteHookBooks remote_hook_books(const os::HookTraffic& outbound, const MediumBooks& medium,
                                  const os::HookTraffic& inbound);

// What proxies talk to. Calls come from the proxies' own contexts.
class HookMedium {
 public:
  virtual ~HookMedium() = default;
  // The outbound proxy of remote hook `hook` hands over one encoded frame; `numbers` is the count
  // of numbers it carries (the frame's size follows from it).
  virtual void transmit(std::uint32_t hook, std::span<const std::byte> frame, std::size_t numbers) = 0;
  // A proxy of `hook` refused a message itself (kBlob, kDecode).
  virtual void refuse(std::uint32_t hook, HookDrop cause) = 0;
};

// On the sender's node: hooked from the sender with the remote hook's options.
class OutboundProxy final : public os::Task {
 public:
  OutboundProxy(HookMedium& medium, std::uint32_t hook) : medium_(medium), hook_(hook) {}

 protected:
  void on_message(const os::Message& m) override;

 private:
  HookMedium& medium_;
  const std::uint32_t hook_;
  std::uint32_t sequence_ = 0;
  std::vector<std::byte> frame_;  // reused: no allocation per message once grown
};

// On the receiver's node: takes the medium's io::Bytes messages, decodes their hook frames, and
// sends the numbers on the frame's port.
class InboundProxy final : public os::Task {
 public:
  InboundProxy(HookMedium& medium, std::uint32_t hook) : medium_(medium), hook_(hook), decoder_(256) {}

 protected:
  void on_message(const os::Message& m) override;

 private:
  HookMedium& medium_;
  const std::uint32_t hook_;
  FrameDecoder decoder_;
};

}  // namespace symb::io
