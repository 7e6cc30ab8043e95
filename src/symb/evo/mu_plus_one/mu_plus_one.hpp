// MuPlusOne: the encapsulated (mu+1)-ONLINE evolution strategy of Haasdijk, Eiben and Karafotias
// (CEC 2010; controller-models.md 6.2) as a pure state machine: no tasks, no time, no robot. A
// population of mu genomes lives on one robot; whoever drives it (the mu_plus_one task, a test, a
// benchmark) asks for the genome to evaluate next, runs it for the evaluation period tau (the
// driver's business: recovery not counted, then counted steps) and reports the measured fitness.
//
// The algorithm:
//  - the first mu evaluations fill the population with random genomes (uniform in the bounds);
//  - afterwards, each step: with probability rho a uniformly chosen member is re-evaluated, else a
//    child is made: two parents chosen (binary tournament: the better of two uniform draws; or
//    uniform), with probability `crossover` a uniform crossover of them (else a copy of the
//    first), then Gaussian mutation N(0, sigma) on every gene, reflected into the bounds. sigma is
//    fixed (the CEC 2010 paper tunes it as a parameter; "of overriding importance");
//  - a child replaces the population's worst member when it is strictly better; else it is lost;
//  - an island model's migrant (immigrate()) is evaluated as the next child, in place of a mutant,
//    and enters the population by the same rule: replacing the worst member if strictly better;
//  - a re-evaluation's measurement is AVERAGED with the member's earlier ones by default (the
//    member's fitness is the mean of all its measurements, so a lucky score is diluted but a good
//    genome's record is not thrown away by one unlucky run); `replace` keeps only the newest, as
//    (1+1)-ONLINE does. The paper describes re-evaluation against noisy fitness without fixing
//    the combination here: this default is our choice (docs/evolution.md).
// Deterministic: every random number comes from the stream given at construction.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::evo {

enum class ParentSelection : std::uint8_t { kBinaryTournament, kUniform };
enum class Reevaluation : std::uint8_t { kAverage, kReplace };

struct MuPlusOneOptions {
  std::size_t genes = 16;
  double lo = -4, hi = 4;
  std::size_t mu = 10;     // population size
  double rho = 0.2;        // re-evaluation probability
  double sigma = 1;        // Gaussian mutation step (fixed)
  double crossover = 0.5;  // probability of a uniform crossover of the two parents
  ParentSelection selection = ParentSelection::kBinaryTournament;
  Reevaluation reevaluation = Reevaluation::kAverage;
};

kernel::Status check(const MuPlusOneOptions& o);

// What the genome returned by next() is.
enum class MuCandidate : std::uint8_t { kInitial, kChild, kReevaluation };
const char* to_string(MuCandidate c);

struct MuPlusOneCounts {
  std::uint64_t evaluations = 0;       // reports
  std::uint64_t initial = 0;           // random members evaluated to fill the population
  std::uint64_t children = 0;          // child reports
  std::uint64_t replacements = 0;      // children that replaced the worst member
  std::uint64_t reevaluations = 0;     // member re-runs reported
  std::uint64_t crossovers = 0;        // children made by crossover
  std::uint64_t immigrants = 0;        // migrants evaluated as children (immigrate())
  std::uint64_t immigrants_taken = 0;  // of them, those that replaced the worst member
};

struct Member {
  RealGenome genome;
  double fitness = 0;  // the stored fitness (mean of measurements, or the newest)
  std::uint64_t measurements = 0;
};

class MuPlusOne {
 public:
  // Fails when the options do not pass check().
  static kernel::Result<MuPlusOne> create(MuPlusOneOptions options, kernel::RandomStream random);

  // The genome to evaluate now (the same until report()).
  const RealGenome& next() const { return candidate_; }
  MuCandidate candidate_kind() const { return kind_; }
  // For a re-evaluation (or an initial member): its index in population().
  std::size_t candidate_index() const { return index_; }
  // The fitness measured for next(); non-finite values count as the lowest possible.
  void report(double fitness);

  // An island model's migrant: once the population is full, the next candidate is `genome` (its
  // values put into the bounds, the fixed sigma) as a child instead of a re-evaluation or a mutant
  // (no random number drawn, so a run stays deterministic given when migrants come); it replaces
  // the worst member only if strictly better, as any child. Takes effect at the next candidate
  // (the one under evaluation is not disturbed); a second call before then replaces the first.
  void immigrate(RealGenome genome);

  // The members evaluated so far (mu once the population is full).
  const std::vector<Member>& population() const { return population_; }
  // The best member (meaningful once a report came: has_best()).
  bool has_best() const { return !population_.empty(); }
  const Member& best() const;
  // The population's mean stored fitness (0 while empty).
  double mean_fitness() const;
  const MuPlusOneCounts& counts() const { return counts_; }
  const MuPlusOneOptions& options() const { return options_; }

 private:
  MuPlusOne(MuPlusOneOptions options, kernel::RandomStream random);
  void prepare_next();
  std::size_t pick();
  std::size_t select_parent();
  std::size_t worst() const;

  MuPlusOneOptions options_;
  kernel::RandomStream random_;
  std::vector<Member> population_;
  RealGenome candidate_;
  MuCandidate kind_ = MuCandidate::kInitial;
  std::size_t index_ = 0;
  std::optional<RealGenome> immigrant_;
  bool candidate_immigrated_ = false;  // next() came from immigrate()
  MuPlusOneCounts counts_;
};

}  // namespace symb::evo
