// Fuzzes the serial frame codec (io/frame_codec): the decoder reads whatever a serial line or a
// socket delivers, so any bytes must give frames or counted drops, never a crash or a frame over
// the size limit. Checked on every input:
//  - decoding in one piece and in pieces split anywhere gives the same frames and counters;
//  - every frame fits the limit; every frame and every drop ended at a delimiter;
//  - the input, taken as a payload, survives encode -> decode whole with no drop, and still does
//    when it arrives right after the (possibly half-frame) garbage of the same input.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "symb/io/frame_codec.hpp"

using namespace symb::io;

namespace {

using Frames = std::vector<std::vector<std::byte>>;

void check(bool ok) {
  if (!ok) std::abort();
}

bool same_stats(const FrameStats& a, const FrameStats& b) {
  return a.frames == b.frames && a.bytes == b.bytes && a.crc_errors == b.crc_errors && a.truncated == b.truncated &&
         a.oversized == b.oversized && a.bad_encoding == b.bad_encoding && a.bad_version == b.bad_version;
}

void decode_both_ways(std::span<const std::byte> in, std::size_t max_payload) {
  FrameDecoder whole(max_payload), pieces(max_payload);
  Frames a, b;
  whole.feed(in, [&](std::span<const std::byte> f) { a.emplace_back(f.begin(), f.end()); });
  // Piece sizes come from the data itself, so the fuzzer explores the split points too.
  std::size_t at = 0;
  while (at < in.size()) {
    const std::size_t n = 1 + static_cast<std::size_t>(in[at]) % 37;
    const auto piece = in.subspan(at, std::min(n, in.size() - at));
    pieces.feed(piece, [&](std::span<const std::byte> f) { b.emplace_back(f.begin(), f.end()); });
    at += piece.size();
  }
  check(a == b);
  check(same_stats(whole.stats(), pieces.stats()));
  const FrameStats& s = whole.stats();
  check(s.bytes == in.size());
  check(s.frames == a.size());
  std::size_t zeros = 0;
  for (std::byte x : in) zeros += x == std::byte{0} ? 1 : 0;
  check(s.frames + s.dropped() <= zeros);
  for (const auto& f : a) check(f.size() <= max_payload);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> in(reinterpret_cast<const std::byte*>(data), size);
  decode_both_ways(in, 1024);
  decode_both_ways(in, 16);  // a small limit reaches the oversized paths with short inputs
  decode_both_ways(in, 0);

  const auto payload = in.first(std::min<std::size_t>(in.size(), 1024));
  const auto frame = encode_frame(payload);
  check(frame.size() <= max_encoded_size(payload.size()));
  check(frame.front() == std::byte{0} && frame.back() == std::byte{0});
  for (std::size_t i = 1; i + 1 < frame.size(); ++i) check(frame[i] != std::byte{0});

  FrameDecoder clean(1024);
  Frames got;
  clean.feed(frame, [&](std::span<const std::byte> f) { got.emplace_back(f.begin(), f.end()); });
  check(got.size() == 1 && std::span<const std::byte>(got[0]).size() == payload.size());
  check(std::equal(got[0].begin(), got[0].end(), payload.begin()));
  check(clean.stats().dropped() == 0);

  // After arbitrary bytes (maybe half a frame), the frame's leading delimiter resynchronises the
  // decoder: the frame still comes out, and what the garbage left unfinished ends as one drop
  // (or as one more frame, when the input ended with a whole frame body but no delimiter).
  FrameDecoder dirty(1024);
  dirty.feed(in, [](std::span<const std::byte>) {});
  const FrameStats before = dirty.stats();
  Frames after;
  dirty.feed(frame, [&](std::span<const std::byte> f) { after.emplace_back(f.begin(), f.end()); });
  check(!after.empty() && after.size() <= 2 && after.back() == got[0]);
  check(dirty.stats().dropped() <= before.dropped() + 1);
  return 0;
}
