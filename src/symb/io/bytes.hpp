// Bytes: a message blob holding raw bytes (a chunk read from a stream, a decoded frame, a line of
// text), so byte traffic rides the same hooks as numbers and is shared, not copied, between the
// tasks hooked to a stream task.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "symb/os/message.hpp"

namespace symb::io {

class Bytes final : public os::Blob {
 public:
  static constexpr std::uint32_t kKind = 0x42595445;  // "BYTE"
  std::uint32_t kind() const override { return kKind; }

  Bytes() = default;
  explicit Bytes(std::span<const std::byte> b) : data(b.begin(), b.end()) {}
  explicit Bytes(std::string_view s)
      : data(reinterpret_cast<const std::byte*>(s.data()), reinterpret_cast<const std::byte*>(s.data()) + s.size()) {}

  std::string_view text() const { return {reinterpret_cast<const char*>(data.data()), data.size()}; }

  std::vector<std::byte> data;
};

inline os::Payload bytes_payload(std::span<const std::byte> b) { return os::Payload(std::make_shared<const Bytes>(b)); }
inline os::Payload text_payload(std::string_view s) { return os::Payload(std::make_shared<const Bytes>(s)); }
// The bytes a message carries, or nullptr when it carries none.
inline const Bytes* bytes_of(const os::Message& m) { return os::blob_as<Bytes>(m.payload.blob.get()); }

}  // namespace symb::io
