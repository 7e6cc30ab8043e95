#include "symb/evo/mu_plus_one/mu_plus_one.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace symb::evo {

kernel::Status check(const MuPlusOneOptions& o) {
  if (o.genes == 0) return kernel::Error{"(mu+1)-online: genes must be at least 1"};
  if (!std::isfinite(o.lo) || !std::isfinite(o.hi) || !(o.lo < o.hi))
    return kernel::Error{"(mu+1)-online: bounds must be finite with lo < hi"};
  if (o.mu < 2 || o.mu > 10000) return kernel::Error{"(mu+1)-online: mu must be 2..10000"};
  if (!(o.rho >= 0 && o.rho < 1)) return kernel::Error{"(mu+1)-online: rho must be in [0, 1)"};
  if (!std::isfinite(o.sigma) || !(o.sigma > 0)) return kernel::Error{"(mu+1)-online: sigma must be positive"};
  if (!(o.crossover >= 0 && o.crossover <= 1))
    return kernel::Error{"(mu+1)-online: the crossover probability must be in [0, 1]"};
  return {};
}

const char* to_string(MuCandidate c) {
  switch (c) {
    case MuCandidate::kInitial: return "initial";
    case MuCandidate::kChild: return "child";
    case MuCandidate::kReevaluation: return "reevaluation";
  }
  return "?";
}

kernel::Result<MuPlusOne> MuPlusOne::create(MuPlusOneOptions options, kernel::RandomStream random) {
  if (auto st = check(options); !st) return kernel::Error{st.error()};
  return MuPlusOne(options, random);
}

MuPlusOne::MuPlusOne(MuPlusOneOptions options, kernel::RandomStream random) : options_(options), random_(random) {
  population_.reserve(options_.mu);
  prepare_next();
}

const Member& MuPlusOne::best() const {
  std::size_t b = 0;
  for (std::size_t i = 1; i < population_.size(); ++i)
    if (population_[i].fitness > population_[b].fitness) b = i;
  return population_[b];
}

double MuPlusOne::mean_fitness() const {
  if (population_.empty()) return 0;
  double s = 0;
  for (const Member& m : population_) s += m.fitness;
  return s / static_cast<double>(population_.size());
}

std::size_t MuPlusOne::pick() { return static_cast<std::size_t>(random_.below(population_.size())); }

std::size_t MuPlusOne::select_parent() {
  const std::size_t a = pick();
  if (options_.selection == ParentSelection::kUniform) return a;
  const std::size_t b = pick();
  return population_[b].fitness > population_[a].fitness ? b : a;
}

// The first of the lowest (ties: the older slot goes).
std::size_t MuPlusOne::worst() const {
  std::size_t w = 0;
  for (std::size_t i = 1; i < population_.size(); ++i)
    if (population_[i].fitness < population_[w].fitness) w = i;
  return w;
}

void MuPlusOne::immigrate(RealGenome genome) { immigrant_ = std::move(genome); }

void MuPlusOne::prepare_next() {
  candidate_immigrated_ = false;
  if (population_.size() < options_.mu) {
    candidate_ = random_real_genome(options_.genes, random_, options_.lo, options_.hi, options_.sigma);
    candidate_.sigma_min = candidate_.sigma_max = options_.sigma;
    kind_ = MuCandidate::kInitial;
    index_ = population_.size();
    return;
  }
  if (immigrant_) {
    candidate_ = population_.front().genome;  // the bounds and the fixed sigma
    candidate_.values.resize(options_.genes, 0.0);
    for (std::size_t i = 0; i < candidate_.values.size(); ++i)
      candidate_.values[i] = i < immigrant_->values.size() ? std::clamp(immigrant_->values[i], options_.lo, options_.hi)
                                                           : candidate_.values[i];
    immigrant_.reset();
    candidate_immigrated_ = true;
    ++counts_.immigrants;
    kind_ = MuCandidate::kChild;
    index_ = 0;
    return;
  }
  if (random_.uniform() < options_.rho) {
    index_ = pick();
    candidate_ = population_[index_].genome;
    kind_ = MuCandidate::kReevaluation;
    return;
  }
  const std::size_t first = select_parent();
  const std::size_t second = select_parent();
  if (random_.uniform() < options_.crossover) {
    candidate_ = crossover_uniform(population_[first].genome, population_[second].genome, random_);
    ++counts_.crossovers;
  } else {
    candidate_ = population_[first].genome;
  }
  mutate_gaussian(candidate_, random_);
  kind_ = MuCandidate::kChild;
  index_ = first;
}

void MuPlusOne::report(double fitness) {
  if (!std::isfinite(fitness)) fitness = std::numeric_limits<double>::lowest();
  ++counts_.evaluations;
  switch (kind_) {
    case MuCandidate::kInitial:
      ++counts_.initial;
      population_.push_back({candidate_, fitness, 1});
      break;
    case MuCandidate::kReevaluation: {
      ++counts_.reevaluations;
      Member& m = population_[index_];
      ++m.measurements;
      if (options_.reevaluation == Reevaluation::kReplace || fitness == std::numeric_limits<double>::lowest() ||
          m.fitness == std::numeric_limits<double>::lowest())
        m.fitness = fitness;  // a failed run (lowest) is never averaged into a finite mean: no overflow
      else
        m.fitness += (fitness - m.fitness) / static_cast<double>(m.measurements);
      break;
    }
    case MuCandidate::kChild: {
      ++counts_.children;
      const std::size_t w = worst();
      if (fitness > population_[w].fitness) {
        ++counts_.replacements;
        if (candidate_immigrated_) ++counts_.immigrants_taken;
        population_[w] = {candidate_, fitness, 1};
      }
      break;
    }
  }
  prepare_next();
}

}  // namespace symb::evo
