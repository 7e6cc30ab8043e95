// Genome: what on-line evolution varies, one of three kinds behind one interface, so that an
// evolution task, a checkpoint or `symb run` replaying a champion handles every kind the same way:
//  - real:  a RealGenome (real_genome.hpp), the weights of a neural-network controller;
//  - ahhs:  an AHHS network (control/ahhs/network.hpp), hormones and rules;
//  - linda: a Linda developmental genome (control/snn/genome.hpp), what grows a spiking network.
//
// One text form for all kinds (docs/genomes.md), so a genome can be saved, loaded and diffed:
//
//   # any comments ('#' to the end of a line, anywhere)
//   genome real                    the first statement: genome real | ahhs | linda
//   bounds -4 4                    real: lo hi                          (default -4 4)
//   sigma 1 min 0.0001 max 4       real: step size [min A] [max B]      (default 1 min 1e-4 max 4)
//   values 0.5 -0.25 ...           real: the genes; lines starting with a number continue the list
//
// `bounds`, `sigma` and `values` come in any order, each at most once; `values` is required (it may
// be empty). For ahhs and linda the `genome KIND` line is followed by the controller's own
// description text (docs/ahhs.md, docs/linda.md): everything after that line, parsed by that
// controller's parser.
//
// Every parse error is "LINE:COLUMN: message" for the whole text; an error inside an embedded
// description keeps that parser's message with its line moved to the line of the whole text.
// to_text() writes numbers in std::to_chars' shortest exact form, so parse_genome_text(to_text(g))
// == g for every g that passes check().
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/control/ahhs/mutation.hpp"
#include "symb/control/ahhs/network.hpp"
#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/genome_mutation.hpp"
#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::evo {

// The index of each alternative in Genome (the variant's index()).
enum class GenomeKind : std::uint8_t { kReal = 0, kAhhs = 1, kLinda = 2 };

using Genome = std::variant<RealGenome, control::ahhs::Network, control::snn::Genome>;

GenomeKind kind_of(const Genome& g);
// "real", "ahhs", "linda": the word of the `genome` line.
const char* kind_name(GenomeKind k);

// Bounds on the real kind's text, so a hostile file cannot make the parser allocate without limit.
inline constexpr std::size_t kMaxGenomeTextBytes = 8u << 20;
inline constexpr std::size_t kMaxRealGenes = 1u << 20;

// A genome every operator accepts: real: check(); ahhs: validate(); linda: check_genome().
kernel::Status check(const Genome& g);

// A checked genome, or "LINE:COLUMN: message".
kernel::Result<Genome> parse_genome_text(std::string_view text);
std::string to_text(const Genome& g);

// What differs between a and b, one short line each ("value 3: 0.5 -> 0.75", "sigma: 1 -> 0.5";
// for ahhs and linda a line diff of their texts: "line 7: - ...", "line 7: + ..."). Empty when
// a == b. Long lists end with "... and N more".
std::vector<std::string> diff(const Genome& a, const Genome& b);

struct GenomeMutation {
  control::ahhs::MutationOptions ahhs;
  control::snn::GenomeMutation linda;
};

// The kind's mutation operator: real: log-normal self-adaptation of sigma, then Gaussian mutation
// with the new sigma (reflected into the bounds); ahhs: ahhs::mutate; linda: snn::mutate.
void mutate(Genome& g, kernel::RandomStream& random, const GenomeMutation& options = {});

// The kind's crossover; a copy of a when the kinds differ. real: crossover_uniform (a copy of a
// for different lengths or bounds); linda: snn::crossover (one-point on the gene lists); ahhs: when
// both networks have the same structure (compartments, links, placements, hormone names, rule
// kinds, ends and compartments), each hormone's base, decay and diffusion and each rule's centre,
// width, fixed and dependent from b with even odds (a hormone's min, max and start travel
// together, so start stays within its bounds); otherwise a copy of a.
Genome crossover(const Genome& a, const Genome& b, kernel::RandomStream& random);

// Whether two AHHS networks differ only in their numbers (the condition of ahhs crossover).
bool same_structure(const control::ahhs::Network& a, const control::ahhs::Network& b);

}  // namespace symb::evo
