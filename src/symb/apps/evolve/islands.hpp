// The island model across MPI ranks (`symb evolve SCENARIO --islands`, started by mpirun): one
// evolution run per rank, each an island with its own population (the scenario's one_plus_one or
// mu_plus_one task) and seed (the base seed + rank), and migration along a ring: every `every` of
// simulated time each island sends its champion (its best member) to island rank + 1 (mod ranks)
// and takes the one of rank - 1 as its next candidate (evo::OnePlusOne::immigrate,
// evo::MuPlusOne::immigrate). The exchanges happen at fixed virtual instants, so a run is
// deterministic for a given seed and rank count. MPI (Debian OpenMPI) carries the genomes: no
// home-made cluster code.
//
// A rank that dies (under `mpirun --enable-recovery`, which keeps the others running): the migrant
// it owed does not come and the rank is silent (every live rank says "alive" about once a second)
// for `wait` of wall clock; the migrant is counted missing, and the ring skips that rank from the
// next exchange on (its predecessor sends to its successor; every rank is told).
// The others finish their runs, and the first rank still there writes the report, naming the
// gone island. Each island's folder keeps what it wrote as it went.
//
// Writes OUT/island_<rank>/ (each a `symb evolve` folder) and OUT/islands.txt: per island its
// seed, evaluations, migrants received and taken into its population, champion fitness and
// history hash (or why it is missing), then the best island and a hash over all islands'
// histories (what the determinism test compares).
#pragma once

#include <cstdint>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/evolve/evolve_run.hpp"

namespace symb::apps::evolve {

struct IslandOptions {
  kernel::Duration every = std::chrono::minutes(10);  // migration interval, simulated (0: never)
  std::uint64_t base_seed = 1;
  // Wall clock of silence (no migrant, figures or "alive" word) after which a rank is taken as gone.
  kernel::Duration wait = std::chrono::seconds(60);
  bool quiet = false;
};

// Runs this rank's island (MPI_Init to MPI_Finalize inside; no MPI_Finalize once a peer is gone:
// it would wait for it). Returns the exit code.
int run_islands(EvolveOptions options, const IslandOptions& islands, const CliContext& ctx);

}  // namespace symb::apps::evolve
