// Medea: mEDEA, the "minimal environment-driven distributed evolutionary algorithm" of Bredeche
// and Montanier (PPSN 2010; controller-models.md 6.3), for ONE robot of a swarm, as a pure state
// machine: no tasks, no radio, no time. Whoever drives it (the medea task, a test) runs genome()
// for a lifetime while broadcasting it, hands every genome heard from a neighbour to receive(),
// and calls end_of_lifetime() when the lifetime is over.
//
// There is no explicit fitness: a genome survives by being heard. The rules, as in roborobo's
// TemplateMedea:
//  - the robot keeps at most one received genome per sender, the latest (a sender's genome only
//    changes between its lifetimes; a later copy replaces the earlier one);
//  - at the end of a lifetime it picks ONE received genome uniformly at random, applies mEDEA's
//    sigma rule (evo::mutate_sigma_medea: with probability p, sigma x1.35 or x0.65) and then
//    Gaussian mutation with that sigma (evo::mutate_gaussian, reflected into the bounds), and
//    runs the result for its next lifetime. The list is emptied;
//  - with an empty list it is INACTIVE for the next lifetime: no controller, no broadcast (it has
//    nothing to spread), but it keeps listening, and at the end of that lifetime the same rule
//    applies.
// The first genome is random (uniform in the bounds, sigma as given) and the robot starts active.
// Received genomes of the wrong length or bounds, or that fail check(), are counted and ignored;
// so are texts that do not parse (receive_text).
// Deterministic: every random number comes from the stream given at construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <utility>

#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::evo {

// Senders a robot keeps genomes from at once; a genome from one more is refused (counted as
// malformed), so a flood of made-up senders cannot make the list grow without limit.
inline constexpr std::size_t kMaxMedeaSenders = 4096;

struct MedeaOptions {
  std::size_t genes = 16;
  double lo = -4, hi = 4;
  double sigma = 0.2;  // sigma_ref: every initial genome's step size (measured: docs/evolution.md)
  double sigma_min = 0.001, sigma_max = 4;
  // gProbaMutation: the probability of changing sigma (x(1 +- factor)) before each mutation. The
  // reference template uses 0: sigma stays sigma_ref.
  double sigma_probability = 0;
  double sigma_factor = 0.35;
};

kernel::Status check(const MedeaOptions& o);

struct MedeaCounts {
  std::uint64_t lifetimes = 0;           // end_of_lifetime() calls
  std::uint64_t active_lifetimes = 0;    // lifetimes that ended with a new genome picked
  std::uint64_t inactive_lifetimes = 0;  // lifetimes that ended with an empty list
  std::uint64_t received = 0;            // genomes accepted by receive()
  std::uint64_t malformed = 0;           // genomes or texts refused
};

class Medea {
 public:
  // Fails when the options do not pass check().
  static kernel::Result<Medea> create(MedeaOptions options, kernel::RandomStream random);

  // The genome the robot runs (meaningful only while active()).
  const RealGenome& genome() const { return genome_; }
  bool active() const { return active_; }

  // A genome heard from `sender` (any key naming the sender: a robot index); replaces what the
  // list held for that sender. Fails (and counts it as malformed) for a genome that does not fit.
  kernel::Status receive(std::uint64_t sender, const RealGenome& g);
  // The same for a genome text (evo::to_text of a real genome). A text identical to the last one
  // from the same sender is not parsed again: a sender repeats its genome all lifetime long.
  kernel::Status receive_text(std::uint64_t sender, std::string_view text);

  // Ends the lifetime: picks, mutates and activates one received genome, or goes inactive.
  // Empties the list.
  void end_of_lifetime();

  // How many genomes the list holds now (one per sender).
  std::size_t received_count() const { return received_.size(); }
  const MedeaCounts& counts() const { return counts_; }
  const MedeaOptions& options() const { return options_; }

 private:
  Medea(MedeaOptions options, kernel::RandomStream random);

  MedeaOptions options_;
  kernel::RandomStream random_;
  RealGenome genome_;
  bool active_ = true;
  std::map<std::uint64_t, RealGenome> received_;  // ordered: the pick is deterministic
  // The last text accepted from each sender and its genome: a repeat is not parsed again.
  std::map<std::uint64_t, std::pair<std::string, RealGenome>> heard_;
  MedeaCounts counts_;
};

}  // namespace symb::evo
