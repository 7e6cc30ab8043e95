// Fuzzes the unified genome text (src/symb/evo/genome/genome.hpp): any text must give a genome or an error
// "LINE:COLUMN: message", never a crash or a hang. An accepted genome must pass check(), survive
// to_text exactly (and diff nothing against its reparse); a mutant and a crossover of it must pass
// check() and round-trip too, and diff must describe the mutant without crashing.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "symb/evo/genome/genome.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::evo;

namespace {

void round_trip(const Genome& g) {
  if (!check(g)) std::abort();
  const std::string printed = to_text(g);
  auto again = parse_genome_text(printed);
  if (!again || !(*again == g) || to_text(*again) != printed || !diff(g, *again).empty()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto r = parse_genome_text(text);
  if (!r) {
    if (!located(r.error())) std::abort();
    return 0;
  }
  const Genome& g = *r;
  round_trip(g);

  symb::kernel::RandomStream random(size);
  Genome m = g;
  mutate(m, random);
  round_trip(m);
  if (!(m == g) && diff(g, m).empty()) std::abort();
  round_trip(crossover(g, m, random));
  round_trip(crossover(m, g, random));
  return 0;
}
