// Fuzzes the MDL2e toolchain: program text -> parser -> compiler -> byte code. Any input must give
// a program or an error "LINE:COLUMN: message", never a crash; every accepted program must encode,
// decode to an equal program and run a few hundred interpreter steps. The same bytes are also fed
// to decode() as byte code, which must reject or verify them.
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string_view>

#include "symb/control/mdl2e/compiler.hpp"
#include "symb/control/mdl2e/interpreter.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::control::mdl2e;

namespace {

void run(const Program& p) {
  Interpreter in(p);
  double sensors[16] = {};
  for (int t = 0; t < 300; ++t) {
    for (int k = 0; k < 16; ++k) sensors[k] = static_cast<double>((t * (k + 3)) % 4096);
    auto out = in.step(std::chrono::milliseconds(t * 17), InterruptInputs{sensors, static_cast<std::uint64_t>(t)});
    if (out.event_count > kMaxEventsPerStep) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto p = compile_source(text);
  if (!p) {
    if (!located(p.error())) std::abort();
  } else {
    const auto bytes = encode(*p);
    auto back = decode(bytes);
    if (!back || !(*back == *p)) std::abort();
    (void)disassemble(*back);
    run(*back);
  }
  auto raw = decode(std::span<const std::uint8_t>(data, size));
  if (raw) run(*raw);
  return 0;
}
