// Fuzzes the AEDAT 2.0 reader and the AER wire decoder: any bytes must give a file or an error
// located as "LINE:COLUMN: " (header) or "byte OFFSET: " (records), never a crash, a hang or a
// read past the input; whatever is accepted must write back and read again to the same events and
// comments.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>

#include "symb/control/snn/aedat.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::control::snn;

namespace {

bool at_byte(const std::string& e) {
  if (e.rfind("byte ", 0) != 0) return false;
  std::size_t i = 5;
  const std::size_t s = i;
  while (i < e.size() && e[i] >= '0' && e[i] <= '9') ++i;
  return i > s && e.compare(i, 2, ": ") == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto f = read_aedat(text);
  if (!f) {
    if (!located(f.error()) && !at_byte(f.error())) std::abort();
  } else {
    std::string again = aedat_header(f->header);
    append_aedat_records(again, f->events);
    auto g = read_aedat(again);
    if (!g || g->header != f->header || g->events != f->events) std::abort();
  }
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  auto p = decode_aer(bytes);
  if (!p) {
    if (!at_byte(p.error())) std::abort();
  } else {
    const auto wire = encode_aer(*p);
    if (wire.size() != size || !std::equal(wire.begin(), wire.end(), bytes.begin())) std::abort();
  }
  return 0;
}
