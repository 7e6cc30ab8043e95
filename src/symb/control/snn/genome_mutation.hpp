// Variation operators on Linda genomes (genome.hpp), for evolution (issue 7) and for the parser
// and development tests: every genome they produce passes check_genome(). All randomness comes
// from the stream passed in, so a mutation is reproducible from its seed.
#pragma once

#include "symb/control/snn/genome.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::snn {

struct GenomeMutation {
  double number_rate = 0.1;      // chance per number (bias, term weight, amount, rate, bias of seeds)
  double number_sigma = 0.2;     // Gaussian step, relative to max(|value|, 1)
  double site_rate = 0.05;       // chance per site (source, seed, input, output) to move one step
  double gene_duplicate = 0.02;  // chance per gene to be copied to a random place
  double gene_delete = 0.02;     // chance per gene to go (never the last one)
  double term_add = 0.02;        // chance per gene to gain a term on a random morphogen
  double term_delete = 0.02;     // chance per term to go
  double action_change = 0.01;   // chance per gene to get a random action
};

void mutate(Genome& genome, kernel::RandomStream& random, const GenomeMutation& rates = {});

// One-point crossover of the gene lists; everything else (grid, morphogens, sites) from `a`.
// Genes of `b` naming a morphogen `a` lacks are dropped.
Genome crossover(const Genome& a, const Genome& b, kernel::RandomStream& random);

}  // namespace symb::control::snn
