#include "symb/control/snn/genome_mutation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "symb/control/snn/development.hpp"
#include "symb/control/snn/spiking_network.hpp"

namespace symb::control::snn {

namespace {

bool chance(kernel::RandomStream& random, double p) { return p > 0 && random.uniform() < p; }

int below(kernel::RandomStream& random, std::size_t n) { return static_cast<int>(random.below(n)); }

// A Gaussian step relative to the value's size, kept within [-limit, limit].
void perturb(float& v, kernel::RandomStream& random, const GenomeMutation& rates, float limit) {
  if (!chance(random, rates.number_rate)) return;
  const double scale = std::max(std::fabs(static_cast<double>(v)), 1.0);
  const double next = static_cast<double>(v) + random.normal() * rates.number_sigma * scale;
  v = static_cast<float>(
      std::clamp(std::isfinite(next) ? next : 0.0, -static_cast<double>(limit), static_cast<double>(limit)));
}

void step_site(int& x, int& y, const Genome& g, kernel::RandomStream& random) {
  static constexpr int kDx[4] = {0, 1, 0, -1};
  static constexpr int kDy[4] = {-1, 0, 1, 0};
  const int d = below(random, 4);
  x = std::clamp(x + kDx[d], 0, g.width - 1);
  y = std::clamp(y + kDy[d], 0, g.height - 1);
}

NeuronClass random_class(kernel::RandomStream& random) {
  return static_cast<NeuronClass>(below(random, kNeuronClassCount));
}

float amount_limit(ActionKind a) {
  switch (a) {
    case ActionKind::kGrow: return kMaxGrownWeight;
    case ActionKind::kBias: return kMaxAbsBias;
    default: return kMaxGenomeNumber;
  }
}

// A gene's action replaced by a random one with random arguments; fields the new action does not
// use go back to their defaults (check_genome).
void random_action(Gene& gene, const Genome& g, kernel::RandomStream& random) {
  const bool have_morphogens = !g.morphogens.empty();
  std::vector<ActionKind> kinds = {ActionKind::kMove,   ActionKind::kDivide, ActionKind::kDie,  ActionKind::kPrune,
                                   ActionKind::kWeight, ActionKind::kBias,   ActionKind::kClass};
  if (have_morphogens) {
    kinds.push_back(ActionKind::kSecrete);
    kinds.push_back(ActionKind::kGrow);
  }
  gene.action = kinds[random.below(kinds.size())];
  gene.direction = Direction::kNorth;
  gene.morphogen = -1;
  gene.cls = NeuronClass::kRS;
  gene.amount = 0;
  gene.delay = 0;
  auto pick_direction = [&] {
    const int n = have_morphogens ? 6 : 4;
    gene.direction = static_cast<Direction>(below(random, static_cast<std::size_t>(n)));
    if (gene.direction == Direction::kUp || gene.direction == Direction::kDown)
      gene.morphogen = below(random, g.morphogens.size());
  };
  switch (gene.action) {
    case ActionKind::kSecrete:
      gene.morphogen = below(random, g.morphogens.size());
      gene.amount = static_cast<float>(random.uniform(0.0, 2.0));
      break;
    case ActionKind::kMove: pick_direction(); break;
    case ActionKind::kDivide:
      pick_direction();
      gene.cls = random_class(random);
      break;
    case ActionKind::kDie:
    case ActionKind::kPrune: break;
    case ActionKind::kGrow:
      gene.direction = random.uniform() < 0.5 ? Direction::kUp : Direction::kDown;
      gene.morphogen = below(random, g.morphogens.size());
      gene.amount = static_cast<float>(random.uniform(-20.0, 20.0));
      gene.delay = below(random, 20) + 1;
      break;
    case ActionKind::kWeight: gene.amount = static_cast<float>(random.normal(0.0, 2.0)); break;
    case ActionKind::kBias: gene.amount = static_cast<float>(random.uniform(-10.0, 10.0)); break;
    case ActionKind::kClass: gene.cls = random_class(random); break;
  }
}

}  // namespace

void mutate(Genome& g, kernel::RandomStream& random, const GenomeMutation& rates) {
  for (auto& s : g.sources) {
    perturb(s.rate, random, rates, kMaxGenomeNumber);
    if (chance(random, rates.site_rate)) step_site(s.x, s.y, g, random);
  }
  for (std::size_t i = 0; i < g.seeds.size(); ++i) {
    auto& c = g.seeds[i];
    perturb(c.bias, random, rates, kMaxAbsBias);
    if (!chance(random, rates.site_rate)) continue;
    int x = c.x, y = c.y;
    step_site(x, y, g, random);
    bool free = true;
    for (std::size_t j = 0; j < g.seeds.size(); ++j)
      if (j != i && g.seeds[j].x == x && g.seeds[j].y == y) free = false;
    if (free) {
      c.x = x;
      c.y = y;
    }
  }
  for (auto* list : {&g.inputs, &g.outputs})
    for (auto& c : *list)
      if (chance(random, rates.site_rate)) step_site(c.x, c.y, g, random);

  for (auto& gene : g.genes) {
    perturb(gene.bias, random, rates, kMaxGenomeNumber);
    for (auto& t : gene.terms) perturb(t.weight, random, rates, kMaxGenomeNumber);
    if (gene.action == ActionKind::kSecrete || gene.action == ActionKind::kGrow || gene.action == ActionKind::kWeight ||
        gene.action == ActionKind::kBias)
      perturb(gene.amount, random, rates, amount_limit(gene.action));
    std::erase_if(gene.terms, [&](const Term&) { return chance(random, rates.term_delete); });
    if (chance(random, rates.term_add) && !g.morphogens.empty() && gene.terms.size() < kMaxTerms)
      gene.terms.push_back({below(random, g.morphogens.size()),
                            static_cast<float>(std::clamp(random.normal(), -static_cast<double>(kMaxGenomeNumber),
                                                          static_cast<double>(kMaxGenomeNumber)))});
    if (chance(random, rates.action_change)) random_action(gene, g, random);
  }

  // Structural changes last, on a copy of the list, so that every gene of the input is visited once.
  std::vector<Gene> genes;
  genes.reserve(g.genes.size() + 4);
  std::vector<Gene> copies;
  for (std::size_t i = 0; i < g.genes.size(); ++i) {
    const bool keep = !chance(random, rates.gene_delete);
    if (chance(random, rates.gene_duplicate)) copies.push_back(g.genes[i]);
    if (keep) genes.push_back(std::move(g.genes[i]));
  }
  if (genes.empty() && !g.genes.empty()) genes.push_back(g.genes.back());  // never the last one
  for (auto& copy : copies) {
    if (genes.size() >= kMaxGenes) break;
    const auto at = static_cast<std::ptrdiff_t>(random.below(genes.size() + 1));
    genes.insert(genes.begin() + at, std::move(copy));
  }
  g.genes = std::move(genes);
}

Genome crossover(const Genome& a, const Genome& b, kernel::RandomStream& random) {
  Genome child = a;
  // b's morphogen indices in a, by name (-1: a lacks it).
  std::vector<int> map(b.morphogens.size(), -1);
  for (std::size_t i = 0; i < b.morphogens.size(); ++i)
    for (std::size_t j = 0; j < a.morphogens.size(); ++j)
      if (a.morphogens[j].name == b.morphogens[i].name) map[i] = static_cast<int>(j);
  auto translate = [&](int m, bool& ok) {
    if (m < 0) return m;
    if (static_cast<std::size_t>(m) >= map.size() || map[static_cast<std::size_t>(m)] < 0) {
      ok = false;
      return -1;
    }
    return map[static_cast<std::size_t>(m)];
  };
  const std::size_t cut = random.below(a.genes.size() + 1);
  child.genes.assign(a.genes.begin(), a.genes.begin() + static_cast<std::ptrdiff_t>(cut));
  for (std::size_t i = cut; i < b.genes.size() && child.genes.size() < kMaxGenes; ++i) {
    Gene gene = b.genes[i];
    bool ok = true;
    gene.morphogen = translate(gene.morphogen, ok);
    for (auto& t : gene.terms) t.morphogen = translate(t.morphogen, ok);
    if (ok) child.genes.push_back(std::move(gene));
  }
  return child;
}

}  // namespace symb::control::snn
