// Fuzzes the Aseba decoder and description reader (io/aseba_message, io/aseba_description): they
// read whatever a robot, a switch or anything listening on its port sends, so any bytes must give
// messages or counted drops, never a crash, unbounded memory or a description that points outside
// the node's memory. Checked on every input:
//  - decoding in one piece and in pieces split anywhere gives the same messages and counters;
//  - every message's payload fits the limit; the counters add up to the bytes fed;
//  - every payload reader either reads or fails, never past the end;
//  - a description assembled from the messages, when complete, has every variable inside the
//    declared memory, at the running sum of the sizes before it, with distinct names.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "symb/io/aseba_description.hpp"
#include "symb/io/aseba_message.hpp"

using namespace symb::io::aseba;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

struct Seen {
  std::uint16_t source, type;
  std::vector<std::byte> payload;
  bool operator==(const Seen&) const = default;
};

std::vector<Seen> decode_both_ways(std::span<const std::byte> in, std::size_t max_payload) {
  AsebaDecoder whole(max_payload), pieces(max_payload);
  std::vector<Seen> a, b;
  whole.feed(in, [&](const Message& m) { a.push_back({m.source, m.type, m.payload}); });
  std::size_t at = 0;
  while (at < in.size()) {
    const std::size_t n = 1 + static_cast<std::size_t>(in[at]) % 23;
    const auto piece = in.subspan(at, std::min(n, in.size() - at));
    pieces.feed(piece, [&](const Message& m) { b.push_back({m.source, m.type, m.payload}); });
    at += piece.size();
  }
  check(a == b);
  check(whole.stats().messages == pieces.stats().messages && whole.stats().oversized == pieces.stats().oversized);
  check(whole.stats().bytes == in.size() && whole.stats().messages == a.size());
  std::size_t used = 0;
  for (const Seen& s : a) {
    check(s.payload.size() <= max_payload);
    used += kHeaderBytes + s.payload.size();
  }
  check(used <= in.size());
  return a;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> in(reinterpret_cast<const std::byte*>(data), size);
  (void)decode_both_ways(in, 16);  // a small limit reaches the skipping paths with short inputs
  const std::vector<Seen> messages = decode_both_ways(in, kMaxPayload);
  if (messages.empty()) return 0;

  DescriptionBuilder builder(messages.front().source);
  for (const Seen& s : messages) {
    Message m{s.source, s.type, s.payload};
    // Every reader either reads or refuses.
    if (auto v = read_variables(m)) check(v->values.size() * 2 + 2 == m.payload.size());
    if (auto e = read_event_args(m)) check(e->size() * 2 == m.payload.size());
    (void)read_node_present(m);
    AsebaReader r(m.payload);
    while (r.left() > 0) {
      const std::size_t before = r.offset();
      if (!(before % 3 == 0 ? r.string().ok() : r.word().ok())) break;
      check(r.offset() > before && r.offset() <= m.payload.size());
    }
    builder.take(m);
  }
  if (builder.complete()) {
    const NodeDescription& d = builder.description();
    check(d.variables.size() <= kMaxNamedVariables && d.variables_size <= kMaxVariableWords);
    std::uint32_t address = 0;
    std::set<std::string> names;
    for (const NamedVariable& v : d.variables) {
      check(v.address == address && v.size > 0 && d.holds(v.address, v.size));
      check(names.insert(v.name).second);
      address += v.size;
    }
  }
  return 0;
}
