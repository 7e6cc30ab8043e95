#include "symb/io/aseba_message.hpp"

#include <algorithm>

namespace symb::io::aseba {

namespace {

void put_word(std::vector<std::byte>& out, std::uint16_t w) {
  out.push_back(static_cast<std::byte>(w & 0xFF));
  out.push_back(static_cast<std::byte>(w >> 8));
}

std::uint16_t get_word(const std::byte* p) {
  return static_cast<std::uint16_t>(std::to_integer<unsigned>(p[0]) | (std::to_integer<unsigned>(p[1]) << 8));
}

kernel::Result<std::vector<std::int16_t>> read_words(std::span<const std::byte> p, std::string_view what) {
  if (p.size() % 2 != 0)
    return kernel::Error{std::string(what) + ": payload of " + std::to_string(p.size()) +
                         " bytes is not a whole number of words"};
  std::vector<std::int16_t> out(p.size() / 2);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<std::int16_t>(get_word(p.data() + 2 * i));
  return out;
}

}  // namespace

kernel::Result<std::vector<std::byte>> encode(std::uint16_t source, std::uint16_t type,
                                              std::span<const std::byte> payload) {
  if (payload.size() > kMaxPayload)
    return kernel::Error{"aseba: a payload of " + std::to_string(payload.size()) + " bytes is longer than " +
                         std::to_string(kMaxPayload)};
  std::vector<std::byte> out;
  out.reserve(kHeaderBytes + payload.size());
  put_word(out, static_cast<std::uint16_t>(payload.size()));
  put_word(out, source);
  put_word(out, type);
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

AsebaWriter& AsebaWriter::word(std::uint16_t w) {
  put_word(payload_, w);
  return *this;
}

AsebaWriter& AsebaWriter::words(std::span<const std::int16_t> ws) {
  for (std::int16_t w : ws) put_word(payload_, static_cast<std::uint16_t>(w));
  return *this;
}

AsebaWriter& AsebaWriter::string(std::string_view s) {
  if (s.size() > 255) {
    too_long_ = true;
    return *this;
  }
  payload_.push_back(static_cast<std::byte>(s.size()));
  for (char c : s) payload_.push_back(static_cast<std::byte>(c));
  return *this;
}

kernel::Result<std::vector<std::byte>> AsebaWriter::finish(std::uint16_t source, std::uint16_t type) const {
  if (too_long_) return kernel::Error{"aseba: a string longer than 255 bytes"};
  return encode(source, type, payload_);
}

namespace {
std::vector<std::byte> must(kernel::Result<std::vector<std::byte>> r) {
  // Only for requests whose size is fixed and small: they always fit.
  return std::move(r).value();
}
}  // namespace

std::vector<std::byte> list_nodes() {
  return must(AsebaWriter().word(kProtocolVersion).finish(kHostId, type::kListNodes));
}

std::vector<std::byte> get_node_description(std::uint16_t node) {
  return must(AsebaWriter().word(node).word(kProtocolVersion).finish(kHostId, type::kGetNodeDescription));
}

std::vector<std::byte> get_variables(std::uint16_t node, std::uint16_t start, std::uint16_t count) {
  return must(AsebaWriter().word(node).word(start).word(count).finish(kHostId, type::kGetVariables));
}

kernel::Result<std::vector<std::byte>> set_variables(std::uint16_t node, std::uint16_t start,
                                                     std::span<const std::int16_t> values) {
  return AsebaWriter().word(node).word(start).words(values).finish(kHostId, type::kSetVariables);
}

kernel::Result<std::vector<std::byte>> user_event(std::uint16_t event, std::span<const std::int16_t> args) {
  if (event >= type::kFirstSystem)
    return kernel::Error{"aseba: user event " + std::to_string(event) + " is not below 0x8000"};
  return AsebaWriter().words(args).finish(kHostId, event);
}

kernel::Result<std::uint16_t> AsebaReader::word() {
  if (left() < 2)
    return kernel::Error{"a word at byte " + std::to_string(at_) + " past the payload's end (" +
                         std::to_string(p_.size()) + " bytes)"};
  const std::uint16_t w = get_word(p_.data() + at_);
  at_ += 2;
  return w;
}

kernel::Result<std::string> AsebaReader::string() {
  if (left() < 1) return kernel::Error{"a string at byte " + std::to_string(at_) + " past the payload's end"};
  const std::size_t n = std::to_integer<std::size_t>(p_[at_]);
  if (left() < 1 + n)
    return kernel::Error{"a string of " + std::to_string(n) + " bytes at byte " + std::to_string(at_) +
                         " runs past the payload's end (" + std::to_string(p_.size()) + " bytes)"};
  std::string s(reinterpret_cast<const char*>(p_.data() + at_ + 1), n);
  at_ += 1 + n;
  return s;
}

kernel::Result<NodePresent> read_node_present(const Message& m) {
  AsebaReader r(m.payload);
  auto v = r.word();
  if (!v) return kernel::Error{"node present: " + v.error()};
  return NodePresent{*v};
}

kernel::Result<Variables> read_variables(const Message& m) {
  AsebaReader r(m.payload);
  auto start = r.word();
  if (!start) return kernel::Error{"variables: " + start.error()};
  auto values = read_words(std::span<const std::byte>(m.payload).subspan(2), "variables");
  if (!values) return kernel::Error{values.error()};
  return Variables{*start, std::move(values).value()};
}

kernel::Result<std::vector<std::int16_t>> read_event_args(const Message& m) {
  return read_words(m.payload, "user event " + std::to_string(m.type));
}

void AsebaDecoder::reset() {
  header_have_ = 0;
  payload_left_ = 0;
  skip_left_ = 0;
  ready_ = false;
  current_.payload.clear();
}

std::size_t AsebaDecoder::step(std::span<const std::byte> bytes) {
  if (skip_left_ > 0) {
    const std::size_t n = std::min(skip_left_, bytes.size());
    skip_left_ -= n;
    return n;
  }
  if (payload_left_ > 0) {
    const std::size_t n = std::min(payload_left_, bytes.size());
    current_.payload.insert(current_.payload.end(), bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    payload_left_ -= n;
    ready_ = payload_left_ == 0;
    return n;
  }
  const std::size_t n = std::min(kHeaderBytes - header_have_, bytes.size());
  std::copy_n(bytes.begin(), n, header_ + header_have_);
  header_have_ += n;
  if (header_have_ < kHeaderBytes) return n;
  header_have_ = 0;
  const std::size_t length = get_word(header_);
  current_.source = get_word(header_ + 2);
  current_.type = get_word(header_ + 4);
  current_.payload.clear();
  if (length > max_payload_) {
    ++stats_.oversized;
    skip_left_ = length;
  } else if (length == 0) {
    ready_ = true;
  } else {
    current_.payload.reserve(length);
    payload_left_ = length;
  }
  return n;
}

}  // namespace symb::io::aseba
