// Development: grows a spiking network from a Linda genome (genome.hpp) on a 2-D grid, in
// developmental ticks, deterministically for a given genome and seed (the seed only feeds the
// genome's `noise`), so a robot can re-grow its controller on board.
//
// The grid holds at most one cell per site; every cell is a neuron (class, tonic bias) with its
// outgoing synapses. Morphogen fields (one float per site and morphogen) obey, per tick,
//     m <- (1 - decay) * (m + diffusion * laplacian(m)) + secretion
// with a 5-point Laplacian and zero flux at the grid's border (a missing neighbour counts as the
// site itself), secretion = the sources' rates plus the cells' `secrete` products of that tick.
//
// One tick, in this order:
//  1. every living cell evaluates every gene on the fields as they were at the tick's start
//     (cells in id order, genes in genome order): x = bias + sum w * m; active when x > 0;
//  2. products are applied in the same order, to cells that existed at the tick's start:
//     secretion (amount * sigmoid(x)) is collected; actions of active genes act at once on the
//     grid (so a site one cell takes is no longer free to the next); a `once` gene that acted
//     never acts again in that cell; a dead cell does nothing more;
//  3. the fields are updated with the collected secretion (plus noise).
// `warmup` ticks before the first run only step 3 with the sources.
//
// Details of steps 1 and 2 (decided here, tested in snn_development_test.cpp):
//  - `class C` reads the cell's class at the tick's start (a `class` action acts on restricted
//    genes from the next tick);
//  - `secrete` acts every tick, active or not (graded: amount * sigmoid(x)), at the cell's site at
//    that moment (after a move earlier in the tick); with noise > 0 each secretion gets its own
//    U[-noise, noise] draw, in cell and gene order (no draws when noise is 0: the seed is unused);
//  - every other action acts only when active (x > 0); a `once` gene is spent the first tick it
//    acts: for actions the first tick it is active even if the action could not take effect (a
//    blocked move), for `secrete` its first tick;
//  - move/divide DIR: the target site is chosen first (up/down: the best of the existing
//    neighbours, ties north, east, south, west, and only if strictly better than here), then the
//    action happens only if that site is inside the grid and free;
//  - a daughter gets a fresh cell (id = cells().size(), no spent genes) and acts from the next tick;
//    at most 65536 cells are ever made (living and dead): further divisions do nothing.
//  - "within reach" is inclusive: distance <= reach.
//
// grow up|down NAME weight W delay D: from the cell's site, walk to the neighbour with the
// highest (lowest) NAME while it is strictly higher (lower) than the current site (ties: north,
// east, south, west); the synapse goes to the living cell nearest the walk's end (Euclidean,
// ties: lowest id) within `reach` of it, other than the cell itself and cells it already has a
// synapse to. No such cell: nothing grows. At most kMaxSynapsesPerCell per cell.
// prune removes the outgoing synapse of least |weight| (ties: lowest target id). weight DELTA
// adds to every outgoing weight, each kept within +-kMaxGrownWeight.
// Cells are never renumbered: a cell's id is its index in cells(), dead ones stay (alive false).
//
// freeze(): the living cells in id order become the neurons; their synapses to living cells the
// network's; inputs and outputs map each channel site to the living cell nearest to it within
// `reach` (ties: lowest id), or to nothing; a channel lists each neuron once, in site order.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::snn {

inline constexpr std::size_t kMaxSynapsesPerCell = 64;
inline constexpr float kMaxGrownWeight = 100.0f;

struct Cell {
  std::uint32_t id = 0;
  int x = 0, y = 0;
  NeuronClass cls = NeuronClass::kRS;
  float bias = 0;
  bool alive = true;
  std::vector<Synapse> out;  // source = this id, target = a cell id
  std::vector<bool> spent;   // per gene: a `once` gene that has acted
};

// The developed network and where its neurons sit, for the controller task and for pictures.
struct GrownNetwork {
  NetworkSpec spec;  // neuron i is the i-th living cell by id
  int width = 0, height = 0;
  std::vector<std::uint32_t> cell_ids;  // per neuron: its cell id
  std::vector<int> x, y;                // per neuron: its site
  std::vector<NeuronClass> classes;     // per neuron
  // Per channel 0..(highest channel named in the genome): the neurons it drives / is read from.
  std::vector<std::vector<std::uint32_t>> inputs, outputs;
};

class Embryo {
 public:
  // Checks the genome (check_genome) and places the seed cells.
  static kernel::Result<Embryo> create(const Genome& genome, std::uint64_t seed);

  // Runs the warmup (first call only) and then one developmental tick.
  void tick();
  // Runs what is left of warmup and ticks.
  void run();
  int ticks_done() const { return ticks_done_; }

  const Genome& genome() const { return genome_; }
  const std::vector<Cell>& cells() const { return cells_; }
  std::size_t living() const;
  // The living cell at a site, or nullptr.
  const Cell* cell_at(int x, int y) const;
  float morphogen(int m, int x, int y) const;
  // For tests of single actions: sets a field value.
  void set_morphogen(int m, int x, int y, float value);

  GrownNetwork freeze() const;

 private:
  Embryo() = default;

  Genome genome_;
  kernel::RandomStream random_;
  bool warmed_up_ = false;
  int ticks_done_ = 0;
  std::vector<Cell> cells_;
  std::vector<std::int32_t> occupant_;      // per site: cell id or -1
  std::vector<std::vector<float>> fields_;  // per morphogen: width*height, row-major

  std::size_t site(int x, int y) const { return static_cast<std::size_t>(y) * genome_.width + x; }
  bool inside(int x, int y) const { return x >= 0 && x < genome_.width && y >= 0 && y < genome_.height; }
  void add_cell(int x, int y, NeuronClass cls, float bias);
  // Step 3: diffusion, decay, then the secretion collected in secretion_.
  void update_fields();
  void add_sources();
  void warm_up();
  // The site a move or divide gene points to from the cell's site (may be outside the grid).
  void target_site(const Cell& cell, const Gene& gene, int& x, int& y) const;
  // The living cell nearest to (x, y) within reach (ties: lowest id) other than `self` and the
  // targets of `existing`; -1 if none.
  std::int64_t nearest(int x, int y, std::int64_t self, const std::vector<Synapse>* existing) const;
  void act(std::size_t cell, std::size_t gene, float x);

  std::vector<float> secretion_, scratch_;  // morphogens * sites
  std::vector<float> activation_;           // cells at the tick's start * genes
  std::vector<std::uint8_t> expressed_;     // cells at the tick's start * genes: class matched
};

// Embryo::create + run + freeze.
kernel::Result<GrownNetwork> develop(const Genome& genome, std::uint64_t seed);

}  // namespace symb::control::snn
