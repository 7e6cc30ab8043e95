// `symb evolve --collect DIR... [--out DIR]`: merges the folders of several evolution runs (a job
// array's runs, `scripts/evolve_array`'s, an island model's islands) into one report. A DIR that
// is not itself a run's folder (no fitness.csv) stands for the run folders directly inside it.
// Writes into the output folder (default out/evolve/collected):
//   collected.txt  per run: folder, seed, evaluations, champion fitness; the best run and its
//                  champion; the champion fitness over time across runs (mean, min, max at 20
//                  instants)
//   fitness.svg    every run's champion fitness over time, one line each
//   best.genome    the best run's champion
// A folder that is not a finished run (no summary.txt, or a fitness.csv that does not parse) is
// an error naming the file and line.
#pragma once

#include <filesystem>
#include <vector>

#include "symb/apps/cli_args.hpp"
#include "symb/kernel/result.hpp"

namespace symb::apps::evolve {

struct CollectedRun {
  std::filesystem::path dir;
  std::uint64_t seed = 0;
  std::uint64_t evaluations = 0;
  double champion_fitness = 0;
  std::vector<double> times, champion;  // per evaluation: end time (s), champion fitness after it
};

struct Collected {
  std::vector<CollectedRun> runs;  // in the order given (a parent folder's runs by name)
  std::size_t best = 0;
  std::vector<std::filesystem::path> files;
};

kernel::Result<Collected> collect_runs(const std::vector<std::filesystem::path>& dirs,
                                       const std::filesystem::path& out);

}  // namespace symb::apps::evolve
