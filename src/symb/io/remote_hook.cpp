#include "symb/io/remote_hook.hpp"

#include <bit>
#include <cstring>
#include <string>

#include "symb/io/bytes.hpp"

namespace symb::io {
namespace {

template <class T>
void put(std::vector<std::byte>& out, T value) {
  using U = std::make_unsigned_t<T>;
  const auto u = static_cast<U>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<std::byte>((u >> (8 * i)) & 0xFF));
}

template <class T>
T get(std::span<const std::byte> in, std::size_t at) {
  using U = std::make_unsigned_t<T>;
  U u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) u |= static_cast<U>(static_cast<U>(in[at + i]) << (8 * i));
  return static_cast<T>(u);
}

}  // namespace

void encode_hook_frame(const HookFrame& frame, std::vector<std::byte>& out) {
  const auto numbers = frame.payload.numbers();
  std::vector<std::byte> payload;
  payload.reserve(hook_frame_payload_bytes(numbers.size()));
  payload.push_back(static_cast<std::byte>(kHookFrameType));
  put<std::uint32_t>(payload, frame.hook);
  put<std::uint32_t>(payload, frame.sequence);
  put<std::int64_t>(payload, frame.time.count());
  put<std::uint16_t>(payload, frame.port);
  payload.push_back(static_cast<std::byte>(numbers.size()));
  for (const float v : numbers) put<std::uint32_t>(payload, std::bit_cast<std::uint32_t>(v));
  out.clear();
  encode_frame(payload, out);
}

kernel::Result<HookFrame> parse_hook_frame(std::span<const std::byte> payload) {
  if (payload.size() < kHookFrameHeader)
    return kernel::Error{"hook frame: " + std::to_string(payload.size()) + " bytes, shorter than its " +
                         std::to_string(kHookFrameHeader) + "-byte header"};
  if (static_cast<std::uint8_t>(payload[0]) != kHookFrameType)
    return kernel::Error{"hook frame: byte 0 is type " + std::to_string(static_cast<int>(payload[0])) + ", not 'H'"};
  const auto count = static_cast<std::size_t>(payload[19]);
  if (count > os::Payload::kInlineValues)
    return kernel::Error{"hook frame: byte 19 counts " + std::to_string(count) + " numbers, more than " +
                         std::to_string(os::Payload::kInlineValues)};
  if (payload.size() != hook_frame_payload_bytes(count))
    return kernel::Error{"hook frame: " + std::to_string(payload.size()) + " bytes where " + std::to_string(count) +
                         " numbers make " + std::to_string(hook_frame_payload_bytes(count))};
  HookFrame f;
  f.hook = get<std::uint32_t>(payload, 1);
  f.sequence = get<std::uint32_t>(payload, 5);
  f.time = kernel::Time{get<std::int64_t>(payload, 9)};
  f.port = get<std::uint16_t>(payload, 17);
  f.payload.count = static_cast<std::uint8_t>(count);
  for (std::size_t i = 0; i < count; ++i)
    f.payload.values[i] = std::bit_cast<float>(get<std::uint32_t>(payload, kHookFrameHeader + 4 * i));
  return f;
}

const char* to_string(HookDrop cause) {
  switch (cause) {
    case HookDrop::kSender: return "sender_queue";
    case HookDrop::kBlob: return "blob";
    case HookDrop::kQueueFull: return "queue_full";
    case HookDrop::kLinkDown: return "link_down";
    case HookDrop::kDecode: return "decode_error";
    case HookDrop::kReceiver: return "receiver";
    case HookDrop::kCount: break;
  }
  return "?";
}

RemoteHookBooks remote_hook_books(const os::HookTraffic& outbound, const MediumBooks& medium,
                                  const os::HookTraffic& inbound) {
  RemoteHookBooks b;
  b.attempted = outbound.traffic.attempted;
  b.delivered = inbound.traffic.delivered;
  b.dropped(HookDrop::kSender) = outbound.traffic.dropped();
  b.dropped(HookDrop::kBlob) = medium.blob;
  b.dropped(HookDrop::kQueueFull) = medium.queue_full;
  b.dropped(HookDrop::kLinkDown) = medium.link_down;
  b.dropped(HookDrop::kDecode) = medium.decode;
  b.dropped(HookDrop::kReceiver) = medium.refused + inbound.traffic.dropped();
  // What the inbound proxy holds: posted, minus what it decoded badly or sent on.
  const std::uint64_t in_inbound = medium.posted - medium.decode - inbound.sent;
  b.in_flight = outbound.queued + medium.in_medium + in_inbound + inbound.queued;
  return b;
}

void OutboundProxy::on_message(const os::Message& m) {
  if (m.payload.blob) {
    medium_.refuse(hook_, HookDrop::kBlob);
    return;
  }
  encode_hook_frame({hook_, sequence_++, m.time, m.port, m.payload}, frame_);
  medium_.transmit(hook_, frame_, m.payload.count);
}

void InboundProxy::on_message(const os::Message& m) {
  const Bytes* bytes = bytes_of(m);
  bool sent = false;
  if (bytes != nullptr) {
    decoder_.feed(bytes->data, [&](std::span<const std::byte> payload) {
      if (sent) return;  // one frame per message; anything after it is not ours
      auto frame = parse_hook_frame(payload);
      if (!frame.ok() || frame->hook != hook_) return;
      send(frame->port, frame->payload);
      sent = true;
    });
    decoder_.reset();
  }
  if (!sent) medium_.refuse(hook_, HookDrop::kDecode);
}

}  // namespace symb::io
