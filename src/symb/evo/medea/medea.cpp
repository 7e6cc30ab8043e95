#include "symb/evo/medea/medea.hpp"

#include <cmath>
#include <iterator>
#include <utility>
#include <variant>

#include "symb/evo/genome/genome.hpp"

namespace symb::evo {

kernel::Status check(const MedeaOptions& o) {
  if (o.genes == 0 || o.genes > kMaxRealGenes)
    return kernel::Error{"medea: genes must be 1.." + std::to_string(kMaxRealGenes)};
  if (!(std::isfinite(o.lo) && std::isfinite(o.hi) && o.lo < o.hi)) return kernel::Error{"medea: need finite lo < hi"};
  if (!(o.sigma_min > 0 && o.sigma_min <= o.sigma && o.sigma <= o.sigma_max && std::isfinite(o.sigma_max)))
    return kernel::Error{"medea: need 0 < sigma_min <= sigma <= sigma_max (finite)"};
  if (!(o.sigma_probability >= 0 && o.sigma_probability <= 1))
    return kernel::Error{"medea: sigma_probability must be in [0, 1]"};
  if (!(o.sigma_factor >= 0 && o.sigma_factor < 1)) return kernel::Error{"medea: sigma_factor must be in [0, 1)"};
  return {};
}

kernel::Result<Medea> Medea::create(MedeaOptions options, kernel::RandomStream random) {
  if (auto st = check(options); !st) return kernel::Error{st.error()};
  return Medea(std::move(options), std::move(random));
}

Medea::Medea(MedeaOptions options, kernel::RandomStream random) : options_(std::move(options)), random_(random) {
  genome_ = random_real_genome(options_.genes, random_, options_.lo, options_.hi, options_.sigma);
  genome_.sigma_min = options_.sigma_min;
  genome_.sigma_max = options_.sigma_max;
}

kernel::Status Medea::receive(std::uint64_t sender, const RealGenome& g) {
  kernel::Status st = check(g);
  if (st && g.values.size() != options_.genes)
    st = kernel::Error{"medea: a genome of " + std::to_string(g.values.size()) + " genes, expected " +
                       std::to_string(options_.genes)};
  if (st && (g.lo != options_.lo || g.hi != options_.hi)) st = kernel::Error{"medea: a genome with other bounds"};
  if (st && received_.size() >= kMaxMedeaSenders && received_.count(sender) == 0)
    st = kernel::Error{"medea: more than " + std::to_string(kMaxMedeaSenders) + " senders in one lifetime"};
  if (!st) {
    ++counts_.malformed;
    return st;
  }
  received_[sender] = g;
  ++counts_.received;
  return {};
}

kernel::Status Medea::receive_text(std::uint64_t sender, std::string_view text) {
  if (auto last = heard_.find(sender); last != heard_.end() && last->second.first == text)
    return receive(sender, last->second.second);
  auto parsed = parse_genome_text(text);
  kernel::Status st;
  if (!parsed) {
    st = kernel::Error{"medea: " + parsed.error()};
  } else if (!std::holds_alternative<RealGenome>(*parsed)) {
    st = kernel::Error{"medea: a genome of another kind than real"};
  }
  if (!st) {
    ++counts_.malformed;
    return st;
  }
  if (st = receive(sender, std::get<RealGenome>(*parsed)); !st) return st;
  if (heard_.size() >= kMaxMedeaSenders) heard_.clear();  // only a cache
  heard_[sender] = {std::string(text), std::get<RealGenome>(*parsed)};
  return {};
}

void Medea::end_of_lifetime() {
  ++counts_.lifetimes;
  if (received_.empty()) {
    active_ = false;
    ++counts_.inactive_lifetimes;
    return;
  }
  auto it = received_.begin();
  std::advance(it, static_cast<std::ptrdiff_t>(random_.below(received_.size())));
  genome_ = std::move(it->second);
  received_.clear();
  mutate_sigma_medea(genome_, random_, options_.sigma_probability, options_.sigma_factor);
  mutate_gaussian(genome_, random_);
  active_ = true;
  ++counts_.active_lifetimes;
}

}  // namespace symb::evo
