#include "symb/control/snn/development.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace symb::control::snn {

namespace {

// Cells ever made (living and dead); further divisions do nothing. Bounds memory when genes make
// cells divide and die over and over.
constexpr std::size_t kMaxCellsEver = std::size_t{1} << 16;

// Neighbours in the tie order of gradient walks: north, east, south, west.
constexpr int kWalkDx[4] = {0, 1, 0, -1};
constexpr int kWalkDy[4] = {-1, 0, 1, 0};

float sigmoid(float x) { return 1.0f / (1.0f + std::exp(-x)); }

}  // namespace

kernel::Result<Embryo> Embryo::create(const Genome& genome, std::uint64_t seed) {
  if (auto st = check_genome(genome); !st) return kernel::Error{st.error()};
  Embryo e;
  e.genome_ = genome;
  e.random_ = kernel::RandomStream(seed);
  const std::size_t sites = static_cast<std::size_t>(genome.width) * static_cast<std::size_t>(genome.height);
  e.occupant_.assign(sites, -1);
  e.fields_.assign(genome.morphogens.size(), std::vector<float>(sites, 0.0f));
  e.secretion_.assign(genome.morphogens.size() * sites, 0.0f);
  e.scratch_.assign(sites, 0.0f);
  for (const auto& s : genome.seeds) e.add_cell(s.x, s.y, s.cls, s.bias);
  return e;
}

void Embryo::add_cell(int x, int y, NeuronClass cls, float bias) {
  Cell c;
  c.id = static_cast<std::uint32_t>(cells_.size());
  c.x = x;
  c.y = y;
  c.cls = cls;
  c.bias = bias;
  c.spent.assign(genome_.genes.size(), false);
  occupant_[site(x, y)] = static_cast<std::int32_t>(c.id);
  cells_.push_back(std::move(c));
}

std::size_t Embryo::living() const {
  return static_cast<std::size_t>(std::count_if(cells_.begin(), cells_.end(), [](const Cell& c) { return c.alive; }));
}

const Cell* Embryo::cell_at(int x, int y) const {
  if (!inside(x, y)) return nullptr;
  const std::int32_t id = occupant_[site(x, y)];
  return id < 0 ? nullptr : &cells_[static_cast<std::size_t>(id)];
}

float Embryo::morphogen(int m, int x, int y) const {
  if (m < 0 || static_cast<std::size_t>(m) >= fields_.size() || !inside(x, y)) return 0.0f;
  return fields_[static_cast<std::size_t>(m)][site(x, y)];
}

void Embryo::set_morphogen(int m, int x, int y, float value) {
  if (m < 0 || static_cast<std::size_t>(m) >= fields_.size() || !inside(x, y)) return;
  fields_[static_cast<std::size_t>(m)][site(x, y)] = value;
}

void Embryo::add_sources() {
  const std::size_t sites = occupant_.size();
  for (const auto& s : genome_.sources)
    secretion_[static_cast<std::size_t>(s.morphogen) * sites + site(s.x, s.y)] += s.rate;
}

void Embryo::update_fields() {
  const int w = genome_.width, h = genome_.height;
  const std::size_t sites = occupant_.size();
  for (std::size_t m = 0; m < fields_.size(); ++m) {
    const float d = genome_.morphogens[m].diffusion;
    const float keep = 1.0f - genome_.morphogens[m].decay;
    const float* f = fields_[m].data();
    float* sec = secretion_.data() + m * sites;
    float* out = scratch_.data();
    for (int y = 0; y < h; ++y) {
      // Zero flux: a missing neighbour counts as the site itself.
      const float* row = f + static_cast<std::size_t>(y) * w;
      const float* up = y > 0 ? row - w : row;
      const float* down = y + 1 < h ? row + w : row;
      float* o = out + static_cast<std::size_t>(y) * w;
      const float* s = sec + static_cast<std::size_t>(y) * w;
      auto at = [&](int x, float left, float right) {
        const float c = row[x];
        const float laplacian = up[x] + down[x] + left + right - 4.0f * c;
        o[x] = keep * (c + d * laplacian) + s[x];
      };
      if (w == 1) {
        at(0, row[0], row[0]);
      } else {
        at(0, row[0], row[1]);
        for (int x = 1; x + 1 < w; ++x) {  // the interior without branches, so it vectorises
          const float c = row[x];
          const float laplacian = up[x] + down[x] + row[x - 1] + row[x + 1] - 4.0f * c;
          o[x] = keep * (c + d * laplacian) + s[x];
        }
        at(w - 1, row[w - 2], row[w - 1]);
      }
    }
    fields_[m].swap(scratch_);
    std::fill(sec, sec + sites, 0.0f);
  }
}

void Embryo::target_site(const Cell& cell, const Gene& gene, int& x, int& y) const {
  x = cell.x;
  y = cell.y;
  switch (gene.direction) {
    case Direction::kNorth: --y; return;
    case Direction::kSouth: ++y; return;
    case Direction::kEast: ++x; return;
    case Direction::kWest: --x; return;
    case Direction::kUp:
    case Direction::kDown: break;
  }
  const bool up = gene.direction == Direction::kUp;
  const auto& f = fields_[static_cast<std::size_t>(gene.morphogen)];
  float best = f[site(cell.x, cell.y)];
  for (int k = 0; k < 4; ++k) {
    const int nx = cell.x + kWalkDx[k], ny = cell.y + kWalkDy[k];
    if (!inside(nx, ny)) continue;
    const float v = f[site(nx, ny)];
    if (up ? v > best : v < best) {
      best = v;
      x = nx;
      y = ny;
    }
  }
}

std::int64_t Embryo::nearest(int x, int y, std::int64_t self, const std::vector<Synapse>* existing) const {
  const double reach = genome_.reach;
  const double reach2 = reach * reach;
  const int r = static_cast<int>(std::min(std::floor(reach), static_cast<double>(kMaxGridSide)));
  std::int64_t best = -1;
  long best_d2 = 0;
  for (int yy = std::max(0, y - r); yy <= std::min(genome_.height - 1, y + r); ++yy)
    for (int xx = std::max(0, x - r); xx <= std::min(genome_.width - 1, x + r); ++xx) {
      const std::int32_t id = occupant_[site(xx, yy)];
      if (id < 0 || id == self) continue;
      const long d2 = static_cast<long>(xx - x) * (xx - x) + static_cast<long>(yy - y) * (yy - y);
      if (static_cast<double>(d2) > reach2) continue;
      if (best >= 0 && (d2 > best_d2 || (d2 == best_d2 && id > best))) continue;
      if (existing) {
        bool taken = false;
        for (const auto& s : *existing) taken = taken || s.target == static_cast<std::uint32_t>(id);
        if (taken) continue;
      }
      best = id;
      best_d2 = d2;
    }
  return best;
}

void Embryo::act(std::size_t c, std::size_t g, float x) {
  const Gene& gene = genome_.genes[g];
  switch (gene.action) {
    case ActionKind::kSecrete: {
      float amount = gene.amount * sigmoid(x);
      if (genome_.noise > 0)
        amount += static_cast<float>(random_.uniform(-static_cast<double>(genome_.noise), genome_.noise));
      secretion_[static_cast<std::size_t>(gene.morphogen) * occupant_.size() + site(cells_[c].x, cells_[c].y)] +=
          amount;
      return;
    }
    case ActionKind::kMove: {
      int tx = 0, ty = 0;
      target_site(cells_[c], gene, tx, ty);
      if (!inside(tx, ty) || occupant_[site(tx, ty)] >= 0) return;
      occupant_[site(cells_[c].x, cells_[c].y)] = -1;
      cells_[c].x = tx;
      cells_[c].y = ty;
      occupant_[site(tx, ty)] = static_cast<std::int32_t>(c);
      return;
    }
    case ActionKind::kDivide: {
      int tx = 0, ty = 0;
      target_site(cells_[c], gene, tx, ty);
      if (!inside(tx, ty) || occupant_[site(tx, ty)] >= 0 || cells_.size() >= kMaxCellsEver) return;
      add_cell(tx, ty, gene.cls, cells_[c].bias);  // may reallocate cells_: no references held
      return;
    }
    case ActionKind::kDie: {
      Cell& cell = cells_[c];
      cell.alive = false;
      cell.out.clear();
      occupant_[site(cell.x, cell.y)] = -1;
      for (auto& other : cells_)
        if (other.alive) std::erase_if(other.out, [&](const Synapse& s) { return s.target == cell.id; });
      return;
    }
    case ActionKind::kGrow: {
      Cell& cell = cells_[c];
      if (cell.out.size() >= kMaxSynapsesPerCell) return;
      const bool up = gene.direction == Direction::kUp;
      const auto& f = fields_[static_cast<std::size_t>(gene.morphogen)];
      int wx = cell.x, wy = cell.y;
      for (std::size_t steps = 0; steps < occupant_.size(); ++steps) {
        float best = f[site(wx, wy)];
        int bx = wx, by = wy;
        for (int k = 0; k < 4; ++k) {
          const int nx = wx + kWalkDx[k], ny = wy + kWalkDy[k];
          if (!inside(nx, ny)) continue;
          const float v = f[site(nx, ny)];
          if (up ? v > best : v < best) {
            best = v;
            bx = nx;
            by = ny;
          }
        }
        if (bx == wx && by == wy) break;
        wx = bx;
        wy = by;
      }
      const std::int64_t target = nearest(wx, wy, static_cast<std::int64_t>(c), &cell.out);
      if (target < 0) return;
      cell.out.push_back(
          {cell.id, static_cast<std::uint32_t>(target), gene.amount, static_cast<std::uint32_t>(gene.delay)});
      return;
    }
    case ActionKind::kPrune: {
      auto& out = cells_[c].out;
      if (out.empty()) return;
      auto weakest = out.begin();
      for (auto it = out.begin(); it != out.end(); ++it) {
        const float a = std::fabs(it->weight), b = std::fabs(weakest->weight);
        if (a < b || (a == b && it->target < weakest->target)) weakest = it;
      }
      out.erase(weakest);
      return;
    }
    case ActionKind::kWeight:
      for (auto& s : cells_[c].out) s.weight = std::clamp(s.weight + gene.amount, -kMaxGrownWeight, kMaxGrownWeight);
      return;
    case ActionKind::kBias: cells_[c].bias = gene.amount; return;
    case ActionKind::kClass: cells_[c].cls = gene.cls; return;
  }
}

void Embryo::warm_up() {
  if (warmed_up_) return;
  for (int t = 0; t < genome_.warmup; ++t) {
    add_sources();
    update_fields();
  }
  warmed_up_ = true;
}

void Embryo::tick() {
  warm_up();
  const std::size_t n = cells_.size();
  const std::size_t genes = genome_.genes.size();
  // 1. Every gene of every living cell on the fields as they are now.
  activation_.assign(n * genes, 0.0f);
  expressed_.assign(n * genes, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const Cell& cell = cells_[c];
    if (!cell.alive) continue;
    const std::size_t here = site(cell.x, cell.y);
    for (std::size_t g = 0; g < genes; ++g) {
      const Gene& gene = genome_.genes[g];
      if (gene.only && *gene.only != cell.cls) continue;
      float x = gene.bias;
      for (const auto& t : gene.terms) x += t.weight * fields_[static_cast<std::size_t>(t.morphogen)][here];
      activation_[c * genes + g] = x;
      expressed_[c * genes + g] = 1;
    }
  }
  // 2. Products, in the same order, to the cells of the tick's start.
  for (std::size_t c = 0; c < n; ++c) {
    for (std::size_t g = 0; g < genes; ++g) {
      if (!cells_[c].alive) break;
      if (!expressed_[c * genes + g]) continue;
      const Gene& gene = genome_.genes[g];
      const float x = activation_[c * genes + g];
      if (gene.once && cells_[c].spent[g]) continue;
      if (gene.action != ActionKind::kSecrete && !(x > 0)) continue;
      if (gene.once) cells_[c].spent[g] = true;
      act(c, g, x);
    }
  }
  // 3. The fields, with the sources and the secretion collected above.
  add_sources();
  update_fields();
  ++ticks_done_;
}

void Embryo::run() {
  warm_up();
  while (ticks_done_ < genome_.ticks) tick();
}

GrownNetwork Embryo::freeze() const {
  GrownNetwork net;
  net.width = genome_.width;
  net.height = genome_.height;
  net.spec.integration = genome_.integration;
  std::vector<std::int64_t> neuron(cells_.size(), -1);
  for (const Cell& c : cells_) {
    if (!c.alive) continue;
    neuron[c.id] = static_cast<std::int64_t>(net.cell_ids.size());
    net.cell_ids.push_back(c.id);
    net.x.push_back(c.x);
    net.y.push_back(c.y);
    net.classes.push_back(c.cls);
    net.spec.neurons.push_back(params_of(c.cls));
    net.spec.bias.push_back(c.bias);
  }
  for (const Cell& c : cells_) {
    if (!c.alive) continue;
    for (const Synapse& s : c.out) {
      if (s.target >= cells_.size() || neuron[s.target] < 0) continue;
      net.spec.synapses.push_back(
          {static_cast<std::uint32_t>(neuron[c.id]), static_cast<std::uint32_t>(neuron[s.target]), s.weight, s.delay});
    }
  }
  auto map_channels = [&](const std::vector<ChannelSite>& sites, std::vector<std::vector<std::uint32_t>>& out) {
    int highest = -1;
    for (const auto& s : sites) highest = std::max(highest, s.channel);
    out.assign(static_cast<std::size_t>(highest + 1), {});
    for (const auto& s : sites) {
      const std::int64_t cell = nearest(s.x, s.y, -1, nullptr);
      if (cell < 0) continue;
      const auto n = static_cast<std::uint32_t>(neuron[static_cast<std::size_t>(cell)]);
      auto& list = out[static_cast<std::size_t>(s.channel)];
      if (std::find(list.begin(), list.end(), n) == list.end()) list.push_back(n);
    }
  };
  map_channels(genome_.inputs, net.inputs);
  map_channels(genome_.outputs, net.outputs);
  return net;
}

kernel::Result<GrownNetwork> develop(const Genome& genome, std::uint64_t seed) {
  auto e = Embryo::create(genome, seed);
  if (!e) return kernel::Error{e.error()};
  Embryo& embryo = e.value();
  embryo.run();
  return embryo.freeze();
}

}  // namespace symb::control::snn
