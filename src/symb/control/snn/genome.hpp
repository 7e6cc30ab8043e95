// The Linda genome: what grows a spiking network (development.hpp) from one or a few seed cells on
// a 2-D grid, in the spirit of the paper's Linda controller (IV-B) and of GRN-driven neural
// development (controller-models.md 4): regulatory genes read the diffusing morphogens at a cell's
// site; their products are either morphogens (secreted) or actions (move, divide, die, grow or
// prune a synapse, change weights, the tonic current or the neuron class). The genome also places
// the sensor (input) and actuator (output) channels on the grid, so evolution can search that
// mapping too.
//
// Text form, one statement a line, '#' starts a comment, numbers are decimal (no nan/inf):
//
//   grid W H                        grid size, 1..64 each (x to the east, y to the south)
//   ticks N                         developmental ticks, 0..2000
//   warmup N                        ticks of sources and diffusion alone before cells act (0)
//   noise A                         each cell's secretion gets U[-A, A] per tick (0; needs the seed)
//   integration published|euler     of the grown network (published)
//   reach R                         how far (sites) an input/output/synapse end may land (1.5)
//   morphogen NAME diffusion D decay L        D in [0, 0.25], L in [0, 1]; at most 16
//   source NAME at X Y rate R                 constant secretion at a site
//   seed at X Y class C [bias B]              a starting cell (at least one, sites distinct)
//   input K at X Y                  sensor channel K (0..31) drives the cell nearest (X, Y)
//   output K at X Y                 output channel K (0..31) reads the cell nearest (X, Y)
//   gene [once] [class C] when B [W*NAME ...] do ACTION
//
// A gene's activation is x = B + sum W * m_NAME at the cell's site; it is active when x > 0.
// `class C` restricts it to cells of that class; `once` lets it act at most once per cell.
// ACTION is one of:
//   secrete NAME AMOUNT             adds AMOUNT * sigmoid(x) of NAME at the site (every tick,
//                                   active or not: graded expression)
//   move DIR                        to the neighbouring site, when free and inside the grid
//   divide DIR CLASS                a daughter of CLASS (same bias, no synapses) in that site
//   die                             the cell and its synapses (in and out) go
//   grow up|down NAME weight W delay D    a synapse toward the gradient (development.hpp)
//   prune                           removes the cell's weakest outgoing synapse
//   weight DELTA                    adds DELTA to each outgoing weight
//   bias VALUE                      sets the cell's tonic current
//   class C                         changes the cell's neuron class
// DIR is north, south, east, west, `up NAME` (the neighbour with the most NAME, if more than
// here) or `down NAME` (the least). Names of morphogens are declared before use: [A-Za-z_][A-Za-z0-9_]*
// up to 32 characters; neuron classes are RS IB CH FS LTS TC RZ (izhikevich.hpp).
//
// A term W*NAME is one token (no spaces around '*'). Statements come in any order, except that a
// morphogen is declared before a statement names it and `grid` comes before any site (X Y); each
// statement other than morphogen, source, seed, input, output and gene appears at most once. A line
// is at most 1024 characters, a name at most 32. Numbers: every real within +-kMaxGenomeNumber,
// except seed bias and `bias VALUE` (+-kMaxAbsBias, so the grown network is valid), the grown
// weight W (+-kMaxGrownWeight), delay D (0..kMaxDelay), noise and reach (0..kMaxGenomeNumber).
// An input/output channel may be placed at several sites. A genome may have no genes.
//
// Every error starts with LINE:COLUMN of the offending token (for a missing argument: just after
// the statement's last token; for a missing `grid` or seed: the end of the text). to_text() writes
// every field (defaults too, numbers in std::to_chars' shortest exact form) such that
// parse_genome(to_text(g)) == g bit for bit for every g that passes check_genome(). For that,
// check_genome() also requires a gene's fields its action does not use to hold their defaults
// (direction kNorth, morphogen -1, cls kRS, amount 0, delay 0): the text could not express them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/control/snn/izhikevich.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::snn {

inline constexpr int kMaxGridSide = 64;
inline constexpr int kMaxTicks = 2000;
inline constexpr std::size_t kMaxMorphogens = 16;
inline constexpr std::size_t kMaxGenes = 256;
inline constexpr std::size_t kMaxTerms = 16;     // per gene
inline constexpr int kMaxChannels = 32;          // input and output channels each
inline constexpr std::size_t kMaxSites = 256;    // sources, seeds, inputs, outputs each
inline constexpr float kMaxGenomeNumber = 1e4f;  // |any number| in a genome

struct Morphogen {
  std::string name;
  float diffusion = 0.1f;
  float decay = 0.05f;
  bool operator==(const Morphogen&) const = default;
};

struct Source {
  int morphogen = 0;  // index into Genome::morphogens
  int x = 0, y = 0;
  float rate = 1;
  bool operator==(const Source&) const = default;
};

struct SeedCell {
  int x = 0, y = 0;
  NeuronClass cls = NeuronClass::kRS;
  float bias = 0;
  bool operator==(const SeedCell&) const = default;
};

struct ChannelSite {
  int channel = 0;
  int x = 0, y = 0;
  bool operator==(const ChannelSite&) const = default;
};

enum class Direction : std::uint8_t { kNorth, kSouth, kEast, kWest, kUp, kDown };
enum class ActionKind : std::uint8_t { kSecrete, kMove, kDivide, kDie, kGrow, kPrune, kWeight, kBias, kClass };

struct Term {
  int morphogen = 0;
  float weight = 0;
  bool operator==(const Term&) const = default;
};

struct Gene {
  bool once = false;
  std::optional<NeuronClass> only;  // acts in cells of this class only
  float bias = 0;
  std::vector<Term> terms;
  ActionKind action = ActionKind::kSecrete;
  Direction direction = Direction::kNorth;  // move, divide; grow: kUp or kDown
  int morphogen = -1;                       // secrete; grow; move/divide/grow up|down: the gradient
  NeuronClass cls = NeuronClass::kRS;       // divide: the daughter's; class: the new one
  float amount = 0;                         // secrete: amount; grow: weight; weight: delta; bias: value
  int delay = 0;                            // grow: ms, 0..kMaxDelay
  bool operator==(const Gene&) const = default;
};

struct Genome {
  int width = 8, height = 8;
  int ticks = 20;
  int warmup = 0;
  float noise = 0;
  float reach = 1.5f;
  Integration integration = Integration::kPublished;
  std::vector<Morphogen> morphogens;
  std::vector<Source> sources;
  std::vector<SeedCell> seeds;
  std::vector<ChannelSite> inputs, outputs;
  std::vector<Gene> genes;
  bool operator==(const Genome&) const = default;
};

kernel::Result<Genome> parse_genome(std::string_view text);
std::string to_text(const Genome& genome);
// The checks parse_genome() makes on the values (ranges, sites inside the grid, seeds distinct,
// indices valid, limits above), for a genome built or mutated in code. Errors name the item.
kernel::Status check_genome(const Genome& genome);

}  // namespace symb::control::snn
