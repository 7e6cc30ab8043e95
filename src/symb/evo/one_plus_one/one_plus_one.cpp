#include "symb/evo/one_plus_one/one_plus_one.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace symb::evo {

kernel::Status check(const OnePlusOneOptions& o) {
  if (o.genes == 0) return kernel::Error{"(1+1)-online: genes must be at least 1"};
  if (!std::isfinite(o.lo) || !std::isfinite(o.hi) || !(o.lo < o.hi))
    return kernel::Error{"(1+1)-online: bounds must be finite with lo < hi"};
  if (!std::isfinite(o.sigma_min) || !std::isfinite(o.sigma_max) || !(o.sigma_min > 0) || !(o.sigma_min <= o.sigma) ||
      !(o.sigma <= o.sigma_max))
    return kernel::Error{"(1+1)-online: need 0 < sigma_min <= sigma <= sigma_max (finite)"};
  if (!(o.reevaluation >= 0 && o.reevaluation <= 1))
    return kernel::Error{"(1+1)-online: the re-evaluation probability must be in [0, 1]"};
  return {};
}

const char* to_string(Candidate c) {
  switch (c) {
    case Candidate::kFirst: return "first";
    case Candidate::kChallenger: return "challenger";
    case Candidate::kReevaluation: return "reevaluation";
  }
  return "?";
}

kernel::Result<OnePlusOne> OnePlusOne::create(OnePlusOneOptions options, kernel::RandomStream random) {
  if (auto st = check(options); !st) return kernel::Error{st.error()};
  return OnePlusOne(options, random);
}

OnePlusOne::OnePlusOne(OnePlusOneOptions options, kernel::RandomStream random) : options_(options), random_(random) {
  champion_ = random_real_genome(options_.genes, random_, options_.lo, options_.hi, options_.sigma);
  champion_.sigma_min = options_.sigma_min;
  champion_.sigma_max = options_.sigma_max;
  candidate_ = champion_;
}

void OnePlusOne::new_challenger() {
  kind_ = Candidate::kChallenger;
  candidate_immigrated_ = immigrant_.has_value();
  if (immigrant_) {
    candidate_ = champion_;
    for (std::size_t i = 0; i < candidate_.values.size() && i < immigrant_->values.size(); ++i)
      candidate_.values[i] = std::clamp(immigrant_->values[i], candidate_.lo, candidate_.hi);
    immigrant_.reset();
    ++counts_.immigrants;
    return;
  }
  candidate_ = champion_;
  mutate_gaussian(candidate_, random_);
}

void OnePlusOne::immigrate(RealGenome genome) { immigrant_ = std::move(genome); }

void OnePlusOne::report(double fitness) {
  if (!std::isfinite(fitness)) fitness = std::numeric_limits<double>::lowest();
  ++counts_.evaluations;
  switch (kind_) {
    case Candidate::kFirst:
      champion_fitness_ = champion_sum_ = fitness;
      new_challenger();
      return;
    case Candidate::kReevaluation:
      ++counts_.reevaluations;
      champion_fitness_ = fitness;  // replaced, not averaged: the reference's choice
      champion_sum_ += fitness;
      new_challenger();
      return;
    case Candidate::kChallenger: break;
  }
  ++counts_.challengers;
  if (fitness > champion_fitness_) {
    ++counts_.successes;
    if (candidate_immigrated_) ++counts_.immigrants_taken;
    champion_ = candidate_;
    on_success(champion_);
    champion_fitness_ = champion_sum_ = fitness;
    new_challenger();
    return;
  }
  on_failure(champion_);
  if (random_.uniform() < options_.reevaluation) {
    candidate_ = champion_;
    kind_ = Candidate::kReevaluation;
    return;
  }
  new_challenger();
}

}  // namespace symb::evo
