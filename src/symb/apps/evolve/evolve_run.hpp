// Running an evolution experiment headless (`symb evolve`): a scenario with an evolution task
// (type one_plus_one or mu_plus_one) on the virtual-time executor, watched through the task's
// probes ("fitness", "champion_fitness" or "best_fitness", "sigma" (1+1 only), "evaluations",
// "champion"), with periodic checkpoints
// (evolve_checkpoint.hpp) and an output folder:
//   fitness.csv      one row per evaluation: time, kind, fitness, champion fitness, sigma
//   fitness.svg      fitness and champion fitness over time
//   champion.genome  the final champion (evo::Genome text, docs/genomes.md)
//   champions/       every new champion's genome, numbered by evaluation
//   checkpoint.txt   the last checkpoint
//   summary.txt      what ran, what came out
// The evolution task is the first task of type one_plus_one or mu_plus_one in the scenario (one
// robot evolves; the others, if any, just run). For (mu+1) the "champion" is the population's
// best member, and its genomes' sigma range is the task's fixed sigma.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "symb/apps/view/view_request.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::apps::evolve {

struct EvolveProgress {
  double simulated_seconds = 0;
  double total_seconds = 0;
  double wall_seconds = 0;
  std::uint64_t evaluations = 0;
  double best = 0;         // the champion's stored fitness
  double mean = 0;         // mean measured fitness over the last (up to) 20 evaluations
  double per_second = 0;   // evaluations per wall-clock second
  bool replaying = false;  // --resume: re-running to the checkpoint
  double fraction() const { return total_seconds > 0 ? simulated_seconds / total_seconds : 1.0; }
};

struct EvolveOptions {
  std::string scenario_path;
  std::optional<std::uint64_t> seed;
  std::optional<kernel::Duration> duration;
  std::filesystem::path out_dir;
  kernel::Duration checkpoint_every = std::chrono::minutes(10);  // 0: no checkpoints
  bool resume = false;
  double speed = 0;  // 0: as fast as possible; s > 0: s times the wall clock
  // Tests: stop at this virtual time as if killed (the checkpoints so far stay, no final files).
  std::optional<kernel::Duration> stop_at;
  std::function<void(const EvolveProgress&)> on_progress;
  // --view: the web view of the run (docs/view.md), the evolving robot shown first; its fitness
  // probes among the probes. Pause, step and speed work as in `symb run --view` (not while a
  // --resume replays to its checkpoint). on_notice hears the URL.
  view::ViewRequest view;
  std::function<void(const std::string&)> on_notice;
  // The island model (islands.hpp): every `migrate_every` of simulated time (0: never) `migrate`
  // is called on the run's thread with this run's champion genes (empty before there is one) and
  // its stored fitness; the genes it returns (empty: none) reach the evolution task as a migrant
  // (evo::kImmigrantPort; one_plus_one or mu_plus_one), at that virtual instant, so a run stays
  // deterministic.
  kernel::Duration migrate_every{0};
  std::function<std::vector<float>(const std::vector<float>& champion, double fitness)> migrate;
};

struct EvolveResult {
  std::string scenario;
  std::uint64_t seed = 0;
  double simulated_seconds = 0;
  double wall_seconds = 0;
  std::uint64_t evaluations = 0;
  std::uint64_t champions = 0;  // new champions seen
  double champion_fitness = 0;
  std::uint64_t history_hash = 0;
  std::uint64_t migrants = 0;        // migrants handed to the evolution task
  std::uint64_t migrants_taken = 0;  // of them, those that entered its population (champion; or
                                     // for (mu+1) a member, replacing the worst)
  std::vector<float> champion_genes;
  bool resumed = false;
  double resumed_from_seconds = 0;
  bool stopped = false;  // stop_at reached
  std::vector<std::filesystem::path> files;
};

kernel::Result<EvolveResult> run_evolution(const EvolveOptions& options);

}  // namespace symb::apps::evolve
