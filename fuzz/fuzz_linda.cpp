// Fuzzes the Linda genome text (genome.hpp): any text must give a genome or an error
// "LINE:COLUMN: message", never a crash or a hang. An accepted genome must pass check_genome and
// survive to_text exactly; if small enough (grid x ticks x work per tick), it is developed and the
// embryo checked: living cells on distinct sites inside the grid, synapse ends valid, at most
// kMaxSynapsesPerCell each, weights within kMaxGrownWeight, the frozen network accepted by
// SpikingNetwork::create and its channels naming its neurons. A mutant and a crossover must pass
// check_genome too.
#include <cstdint>
#include <cstdlib>
#include <set>
#include <string>
#include <string_view>
#include <utility>

#include "symb/control/snn/development.hpp"
#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/genome_mutation.hpp"
#include "symb/control/snn/spiking_network.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::control::snn;

namespace {

void check_embryo(const Embryo& e) {
  const Genome& g = e.genome();
  std::set<std::pair<int, int>> taken;
  for (const Cell& c : e.cells()) {
    if (!c.alive) continue;
    if (c.x < 0 || c.x >= g.width || c.y < 0 || c.y >= g.height) std::abort();
    if (!taken.insert({c.x, c.y}).second) std::abort();
    if (e.cell_at(c.x, c.y) != &c) std::abort();
    if (c.out.size() > kMaxSynapsesPerCell) std::abort();
    for (const Synapse& s : c.out) {
      if (s.source != c.id || s.target == c.id || s.target >= e.cells().size()) std::abort();
      if (!e.cells()[s.target].alive) std::abort();
      if (!(s.weight >= -kMaxGrownWeight && s.weight <= kMaxGrownWeight) || s.delay > kMaxDelay) std::abort();
    }
  }
  const GrownNetwork net = e.freeze();
  if (net.cell_ids.size() != e.living()) std::abort();
  if (!net.cell_ids.empty() && !SpikingNetwork::create(net.spec)) std::abort();
  for (const auto* channels : {&net.inputs, &net.outputs})
    for (const auto& list : *channels)
      for (std::uint32_t n : list)
        if (n >= net.cell_ids.size()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto r = parse_genome(text);
  if (!r) {
    if (!located(r.error())) std::abort();
    return 0;
  }
  const Genome& g = *r;
  if (!check_genome(g)) std::abort();
  const std::string printed = to_text(g);
  auto again = parse_genome(printed);
  if (!again || !(*again == g) || to_text(*again) != printed) std::abort();

  // Bounded work: sites * (morphogens + genes) per tick.
  const double work = static_cast<double>(g.width) * g.height * (g.ticks + g.warmup + 1) *
                      static_cast<double>(g.morphogens.size() + g.genes.size() + 1);
  if (work <= 4e6) {
    auto e = Embryo::create(g, size);
    if (!e) std::abort();
    Embryo& embryo = e.value();
    for (int t = 0; t < g.ticks; ++t) {
      embryo.tick();
      if (t % 8 == 0) check_embryo(embryo);
    }
    check_embryo(embryo);
  }

  symb::kernel::RandomStream random(size);
  Genome m = g;
  GenomeMutation strong;
  strong.number_rate = 0.5;
  strong.site_rate = 0.5;
  strong.action_change = 0.3;
  strong.term_add = 0.3;
  mutate(m, random, strong);
  if (!check_genome(m)) std::abort();
  if (!check_genome(crossover(g, m, random)) || !check_genome(crossover(m, g, random))) std::abort();
  return 0;
}
