// The island model across MPI ranks (`symb evolve SCENARIO --islands`, started by mpirun): one
// evolution run per rank, each an island with its own population (the scenario's one_plus_one
// task) and seed (the base seed + rank), and migration along a ring: every `every` of simulated
// time each island sends its champion to island rank + 1 (mod ranks) and takes the one of rank -
// 1 as its next challenger (evo::OnePlusOne::immigrate). The exchanges happen at fixed virtual
// instants, so a run is deterministic for a given seed and rank count. MPI (Debian OpenMPI)
// carries the genomes: no home-made cluster code. A rank that dies ends the job (MPI's default
// error handler: mpirun reports which rank and kills the others); each island's folder keeps its
// checkpoints.
//
// Writes OUT/island_<rank>/ (each a `symb evolve` folder) and, on rank 0, OUT/islands.txt: per
// island its seed, evaluations, migrants taken, champion fitness and history hash, then the best
// island and a hash over all islands' histories (what the determinism test compares).
#pragma once

#include <cstdint>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/evolve/evolve_run.hpp"

namespace symb::apps::evolve {

struct IslandOptions {
  kernel::Duration every = std::chrono::minutes(10);  // migration interval, simulated (0: never)
  std::uint64_t base_seed = 1;
  bool quiet = false;
};

// Runs this rank's island (MPI_Init to MPI_Finalize inside). Returns the exit code.
int run_islands(EvolveOptions options, const IslandOptions& islands, const CliContext& ctx);

}  // namespace symb::apps::evolve
