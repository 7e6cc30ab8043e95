#include "symb/io/frame_codec.hpp"

namespace symb::io {

std::uint16_t crc16_ccitt(std::span<const std::byte> data, std::uint16_t crc) {
  // Bitwise on purpose: a 512-byte table costs more than it saves on a microcontroller, and the
  // frame benchmark shows this is fast enough for any serial line.
  for (std::byte byte : data) {
    crc ^= static_cast<std::uint16_t>(static_cast<std::uint8_t>(byte)) << 8;
    for (int i = 0; i < 8; ++i)
      crc = (crc & 0x8000) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021) : static_cast<std::uint16_t>(crc << 1);
  }
  return crc;
}

void encode_frame(std::span<const std::byte> payload, std::vector<std::byte>& out) {
  const std::byte version{kFrameVersion};
  std::uint16_t crc = crc16_ccitt({&version, 1});
  crc = crc16_ccitt(payload, crc);
  const std::byte tail[2] = {std::byte(crc >> 8), std::byte(crc & 0xff)};

  out.push_back(std::byte{0});
  // COBS over version | payload | tail, streamed without building the body first.
  std::size_t code_at = out.size();
  out.push_back(std::byte{1});
  std::uint8_t code = 1;
  auto put = [&](std::byte b) {
    if (b == std::byte{0}) {
      out[code_at] = std::byte{code};
      code_at = out.size();
      out.push_back(std::byte{1});
      code = 1;
      return;
    }
    out.push_back(b);
    if (++code == 0xff) {
      out[code_at] = std::byte{code};
      code_at = out.size();
      out.push_back(std::byte{1});
      code = 1;
    }
  };
  put(version);
  for (std::byte b : payload) put(b);
  put(tail[0]);
  put(tail[1]);
  out[code_at] = std::byte{code};
  out.push_back(std::byte{0});
}

std::vector<std::byte> encode_frame(std::span<const std::byte> payload) {
  std::vector<std::byte> out;
  out.reserve(max_encoded_size(payload.size()));
  encode_frame(payload, out);
  return out;
}

FrameDecoder::FrameDecoder(std::size_t max_payload)
    : max_payload_(max_payload), max_encoded_(max_encoded_size(max_payload) - 2) {
  encoded_.reserve(max_encoded_);
  decoded_.reserve(max_encoded_);
}

void FrameDecoder::reset() {
  encoded_.clear();
  overflow_ = false;
}

bool FrameDecoder::finish() {
  if (overflow_) {
    ++stats_.oversized;
    reset();
    return false;
  }
  if (encoded_.empty()) return false;  // back-to-back delimiters are idle line, not a frame
  decoded_.clear();
  bool ok = true;
  for (std::size_t i = 0; i < encoded_.size();) {
    const auto code = static_cast<std::uint8_t>(encoded_[i]);
    if (i + code > encoded_.size()) {
      ok = false;
      break;
    }
    for (std::size_t k = 1; k < code; ++k) decoded_.push_back(encoded_[i + k]);
    i += code;
    if (code != 0xff && i < encoded_.size()) decoded_.push_back(std::byte{0});
  }
  encoded_.clear();
  if (!ok) {
    ++stats_.bad_encoding;
    return false;
  }
  if (decoded_.size() < 3) {
    ++stats_.truncated;
    return false;
  }
  if (decoded_.size() - 3 > max_payload_) {
    ++stats_.oversized;
    return false;
  }
  const std::size_t body = decoded_.size() - 2;
  const auto crc = static_cast<std::uint16_t>((static_cast<unsigned>(decoded_[body]) << 8) |
                                              static_cast<unsigned>(decoded_[body + 1]));
  if (crc16_ccitt({decoded_.data(), body}) != crc) {
    ++stats_.crc_errors;
    return false;
  }
  if (static_cast<std::uint8_t>(decoded_[0]) != kFrameVersion) {
    ++stats_.bad_version;
    return false;
  }
  ++stats_.frames;
  return true;
}

}  // namespace symb::io
