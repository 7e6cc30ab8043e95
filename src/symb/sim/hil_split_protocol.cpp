#include "symb/sim/hil_split_protocol.hpp"

#include <cmath>
#include <string>

#include "symb/io/stream_task.hpp"

namespace symb::sim {

namespace {

std::optional<std::uint32_t> whole_number(float v, std::uint32_t most) {
  if (!std::isfinite(v) || v < 0 || v > static_cast<float>(most) || std::floor(v) != v) return std::nullopt;
  return static_cast<std::uint32_t>(v);
}

}  // namespace

namespace {

struct Fnv1a {
  std::uint32_t h = 2166136261u;
  void add(std::string_view s) {
    for (char c : s) {
      h ^= static_cast<std::uint8_t>(c);
      h *= 16777619u;
    }
    h ^= 0xFF;  // a separator, so that "ab","c" and "a","bc" differ
    h *= 16777619u;
  }
  void add(std::int64_t v) { add(std::to_string(v)); }
  void add(double v) { add(std::to_string(v)); }
};

}  // namespace

std::uint32_t robot_digest(const Scenario& sc, std::size_t index) {
  Fnv1a f;
  f.add(static_cast<std::int64_t>(sc.control_period.count()));
  f.add(sc.world.width);
  f.add(sc.world.height);
  f.add(static_cast<std::int64_t>(sc.robots.size()));
  if (sc.world.radio) {
    f.add(sc.world.radio->range);
    f.add(static_cast<std::int64_t>(sc.world.radio->max_message_bytes));
  } else {
    f.add(std::string_view("no radio"));
  }
  if (index >= sc.robots.size()) return f.h;
  const RobotSpec& r = sc.robots[index];
  f.add(r.name);
  f.add(static_cast<std::int64_t>(r.kind));
  for (const TaskSpec& t : r.tasks) {
    f.add(t.name);
    f.add(t.type);
    for (const os::ParamAssignment& p : t.params) {
      f.add(p.name);
      f.add(p.value);
    }
    f.add(static_cast<std::int64_t>(t.priority.value_or(-1)));
    f.add(static_cast<std::int64_t>(t.period ? t.period->count() : -1));
    f.add(static_cast<std::int64_t>(t.queue_capacity ? static_cast<std::int64_t>(*t.queue_capacity) : -1));
    f.add(static_cast<std::int64_t>(t.autostart));
  }
  for (const HookSpec& k : r.hooks) {
    f.add(k.from);
    f.add(k.to);
    f.add(static_cast<std::int64_t>(k.options.priority));
    f.add(static_cast<std::int64_t>(k.options.policy));
    f.add(static_cast<std::int64_t>(k.options.enabled));
    f.add(static_cast<std::int64_t>(k.options.port));
    f.add(static_cast<std::int64_t>(k.options.suppress_window.count()));
  }
  return f.h;
}

std::vector<std::byte> encode_hello_payload(const HilSplitHello& h) {
  float v[kHilHelloValues];
  v[0] = 0;
  for (int k = 0; k < 4; ++k) v[1 + k] = static_cast<float>((h.seed >> (16 * k)) & 0xFFFF);
  v[5] = static_cast<float>(h.robot);
  v[6] = static_cast<float>(h.robots);
  v[7] = static_cast<float>(h.digest & 0xFFFF);
  v[8] = static_cast<float>(h.digest >> 16);
  return io::encode_numbers(v);
}

std::vector<std::byte> encode_bye_payload(std::uint32_t steps) {
  const float v[2] = {-1.0f, static_cast<float>(steps)};
  return io::encode_numbers(v);
}

std::optional<std::uint32_t> decode_bye_payload(std::span<const std::byte> payload) {
  auto n = io::decode_numbers(payload);
  if (!n || n->size() != 2 || (*n)[0] != -1.0f) return std::nullopt;
  return sequence_of((*n)[1]);
}

std::vector<std::byte> encode_split_sensors_payload(const HilSplitSensors& f) {
  float v[kHilSplitSensorValues];
  std::size_t k = 0;
  v[k++] = static_cast<float>(f.seq);
  for (float x : f.ir) v[k++] = x;
  for (float x : f.pose) v[k++] = x;
  for (float x : f.ground) v[k++] = x;
  return io::encode_numbers(v);
}

kernel::Result<HilSplitHello> decode_hello_payload(std::span<const std::byte> payload) {
  auto n = io::decode_numbers(payload);
  if (!n) return kernel::Error{"hello frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (n->size() != kHilHelloValues)
    return kernel::Error{"hello frame: expected " + std::to_string(kHilHelloValues) + " numbers, got " +
                         std::to_string(n->size())};
  if ((*n)[0] != 0) return kernel::Error{"hello frame: sequence number " + std::to_string((*n)[0]) + ", not 0"};
  HilSplitHello h;
  for (int k = 0; k < 4; ++k) {
    const auto piece = whole_number((*n)[1 + k], 0xFFFF);
    if (!piece) return kernel::Error{"hello frame: seed piece " + std::to_string(k) + " is not a 16-bit integer"};
    h.seed |= static_cast<std::uint64_t>(*piece) << (16 * k);
  }
  const auto robot = whole_number((*n)[5], kHilMaxSequence), robots = whole_number((*n)[6], kHilMaxSequence);
  if (!robot || !robots || *robot >= *robots)
    return kernel::Error{"hello frame: robot index " + std::to_string((*n)[5]) + " of " + std::to_string((*n)[6])};
  h.robot = *robot;
  h.robots = *robots;
  for (int k = 0; k < 2; ++k) {
    const auto piece = whole_number((*n)[7 + k], 0xFFFF);
    if (!piece) return kernel::Error{"hello frame: digest piece " + std::to_string(k) + " is not a 16-bit integer"};
    h.digest |= *piece << (16 * k);
  }
  return h;
}

kernel::Result<HilSplitSensors> decode_split_sensors_payload(std::span<const std::byte> payload) {
  auto n = io::decode_numbers(payload);
  if (!n) return kernel::Error{"sensor frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (n->size() != kHilSplitSensorValues)
    return kernel::Error{"sensor frame: expected " + std::to_string(kHilSplitSensorValues) + " numbers, got " +
                         std::to_string(n->size())};
  const auto seq = sequence_of((*n)[0]);
  if (!seq || *seq == 0) return kernel::Error{"sensor frame: bad sequence number " + std::to_string((*n)[0])};
  HilSplitSensors f;
  f.seq = *seq;
  std::size_t k = 1;
  for (float& x : f.ir) x = (*n)[k++];
  for (float& x : f.pose) x = (*n)[k++];
  for (float& x : f.ground) x = (*n)[k++];
  for (std::size_t i = 1; i < n->size(); ++i)
    if (std::isnan((*n)[i]))
      return kernel::Error{"sensor frame " + std::to_string(f.seq) + ": value " + std::to_string(i) + " is NaN"};
  return f;
}

namespace {

void put_u32(std::uint32_t v, std::vector<std::byte>& out) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::byte>((v >> (8 * k)) & 0xFF));
}

std::uint32_t get_u32(std::span<const std::byte> b) {
  std::uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(b[static_cast<std::size_t>(k)]) << (8 * k);
  return v;
}

}  // namespace

void encode_radio_payload(std::uint32_t seq, std::uint32_t robot, std::span<const std::byte> bytes,
                          std::vector<std::byte>& out) {
  out.clear();
  out.reserve(kHilRadioHeader + bytes.size());
  out.push_back(kHilRadioTag);
  put_u32(seq, out);
  put_u32(robot, out);
  out.insert(out.end(), bytes.begin(), bytes.end());
}

kernel::Result<HilSplitRadio> decode_radio_payload(std::span<const std::byte> payload) {
  if (!is_radio_payload(payload)) return kernel::Error{"radio frame: no 'R' tag"};
  if (payload.size() <= kHilRadioHeader)
    return kernel::Error{"radio frame: " + std::to_string(payload.size()) + " bytes, no message after its " +
                         std::to_string(kHilRadioHeader) + "-byte header"};
  HilSplitRadio r;
  r.seq = get_u32(payload.subspan(1, 4));
  r.robot = get_u32(payload.subspan(5, 4));
  r.bytes = payload.subspan(kHilRadioHeader);
  if (r.seq > kHilMaxSequence) return kernel::Error{"radio frame: sequence number " + std::to_string(r.seq)};
  return r;
}

}  // namespace symb::sim
