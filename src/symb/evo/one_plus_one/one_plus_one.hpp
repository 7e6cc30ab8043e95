// OnePlusOne: the (1+1)-ONLINE evolution strategy of Bredeche, Haasdijk and Eiben (EA'09;
// controller-models.md 6.1) as a pure state machine: no tasks, no time, no robot. Whoever drives
// it (the one_plus_one task, a test, a benchmark) asks for the genome to evaluate next, runs it
// (recovery steps not counted, then counted steps) and reports the measured fitness.
//
// The algorithm, exactly as in the reference implementation (roborobo, 2009):
//  - one champion (with its stored fitness) and one challenger at a time. The very first genome
//    is random (uniform in the bounds) and its first measurement is its stored fitness;
//  - a challenger is the champion plus Gaussian noise N(0, sigma) on every gene, reflected into
//    the bounds (evo::mutate_gaussian), sigma being the champion's own step size;
//  - a challenger strictly better than the stored fitness becomes champion and sigma <- sigma_min
//    (evo::on_success); otherwise sigma <- min(2 sigma, sigma_max) (evo::on_failure), and with
//    probability `reevaluation` (0.2) the champion itself is run again next, its stored fitness
//    REPLACED by the new measurement (a noisy lucky score does not survive for ever); the summed
//    measurements of the champion are kept too;
//  - after a re-evaluation, the next genome is a new challenger.
// Deterministic: every random number comes from the stream given at construction.
#pragma once

#include <cstdint>
#include <optional>

#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::evo {

struct OnePlusOneOptions {
  std::size_t genes = 16;
  double lo = -4, hi = 4;
  double sigma = 1;  // sigma_0
  double sigma_min = 1e-4, sigma_max = 4;
  double reevaluation = 0.2;  // probability of re-running the champion after a failed challenger
};

kernel::Status check(const OnePlusOneOptions& o);

// What the genome returned by next() is.
enum class Candidate : std::uint8_t { kFirst, kChallenger, kReevaluation };
const char* to_string(Candidate c);

struct OnePlusOneCounts {
  std::uint64_t evaluations = 0;       // reports
  std::uint64_t challengers = 0;       // challenger reports
  std::uint64_t successes = 0;         // challengers that became champion
  std::uint64_t reevaluations = 0;     // champion re-runs reported
  std::uint64_t immigrants = 0;        // challengers that came from immigrate()
  std::uint64_t immigrants_taken = 0;  // of them, those that became champion
};

class OnePlusOne {
 public:
  // Fails when the options do not pass check().
  static kernel::Result<OnePlusOne> create(OnePlusOneOptions options, kernel::RandomStream random);

  // The genome to evaluate now (the same until report()).
  const RealGenome& next() const { return candidate_; }
  Candidate candidate_kind() const { return kind_; }
  // The fitness measured for next(); non-finite values count as the lowest possible.
  void report(double fitness);

  // An island model's migrant: the next challenger drawn is `genome` (its values put into the
  // bounds, with the champion's step size) instead of a mutant of the champion; it becomes
  // champion only by beating the stored fitness here, as any challenger must. Takes effect at the
  // next challenger (the candidate under evaluation is not disturbed); a second call before then
  // replaces the first. Draws no random number, so a run stays deterministic given when migrants
  // come.
  void immigrate(RealGenome genome);

  // The champion (meaningful once the first report came) and its stored fitness.
  const RealGenome& champion() const { return champion_; }
  double champion_fitness() const { return champion_fitness_; }
  // The sum of all measurements of the current champion (its first and every re-evaluation).
  double champion_fitness_sum() const { return champion_sum_; }
  bool has_champion() const { return counts_.evaluations > 0; }
  // The step size the next challenger is (or was) drawn with.
  double sigma() const { return champion_.sigma; }
  const OnePlusOneCounts& counts() const { return counts_; }
  const OnePlusOneOptions& options() const { return options_; }

 private:
  OnePlusOne(OnePlusOneOptions options, kernel::RandomStream random);
  void new_challenger();

  OnePlusOneOptions options_;
  kernel::RandomStream random_;
  RealGenome champion_;
  RealGenome candidate_;
  Candidate kind_ = Candidate::kFirst;
  double champion_fitness_ = 0;
  double champion_sum_ = 0;
  std::optional<RealGenome> immigrant_;
  bool candidate_immigrated_ = false;  // next() came from immigrate()
  OnePlusOneCounts counts_;
};

}  // namespace symb::evo
