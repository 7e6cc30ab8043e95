// RealGenome: a vector of real genes in [lo, hi] with its own mutation step size sigma, the genome
// of on-line evolution of neural-network controllers (controller-models.md 6.1: 18 perceptron
// weights in [-4, 4]). Variation follows the reference algorithms:
//  - Gaussian mutation N(0, sigma) on every gene; a gene leaving [lo, hi] bounces back (reflected,
//    as often as needed), so no value sticks to a bound;
//  - sigma adaptation by one of three rules: (1+1)-ONLINE's success rule (the algorithm calls
//    on_success / on_failure: sigma_min after a success, doubled up to sigma_max after a failure),
//    mEDEA's carried sigma (x1.35 or x0.65 with a probability), or log-normal self-adaptation
//    (sigma * exp(tau N(0, 1)), tau = 1 / sqrt(n));
//  - crossover: uniform (each gene from either parent) or arithmetic (a blend).
// Randomness only from the stream passed in.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::evo {

struct RealGenome {
  std::vector<double> values;
  double lo = -4, hi = 4;
  double sigma = 1;  // the current mutation step size
  double sigma_min = 1e-4, sigma_max = 4;
  bool operator==(const RealGenome&) const = default;
};

// Checks lo < hi (finite), every value finite and inside, 0 < sigma_min <= sigma <= sigma_max.
kernel::Status check(const RealGenome& g);

// A genome of n genes drawn uniformly in [lo, hi], sigma as given.
RealGenome random_real_genome(std::size_t n, kernel::RandomStream& random, double lo = -4, double hi = 4,
                              double sigma = 1);

// v reflected into [lo, hi] (bouncing off both bounds as often as needed). Finite v only.
double reflect(double v, double lo, double hi);

// Adds N(0, sigma) to every gene, reflecting into the bounds.
void mutate_gaussian(RealGenome& g, kernel::RandomStream& random);

// (1+1)-ONLINE's step-size rule (Bredeche et al. 2009): after a challenger won, sigma <- sigma_min;
// after it lost, sigma <- min(2 sigma, sigma_max).
void on_success(RealGenome& g);
void on_failure(RealGenome& g);
// mEDEA's carried sigma: with probability `p`, sigma <- sigma * 1.35 or * 0.65 (even odds),
// clamped into [sigma_min, sigma_max].
void mutate_sigma_medea(RealGenome& g, kernel::RandomStream& random, double p, double factor = 0.35);
// Log-normal self-adaptation: sigma <- sigma exp(tau N(0, 1)), tau = 1 / sqrt(n), clamped.
void mutate_sigma_lognormal(RealGenome& g, kernel::RandomStream& random);

// Same length and bounds required (else a's copy). Uniform: each gene from a or b with even odds.
// Arithmetic: w a + (1 - w) b with one w ~ U[0, 1]. Sigma: the mean of the parents'.
RealGenome crossover_uniform(const RealGenome& a, const RealGenome& b, kernel::RandomStream& random);
RealGenome crossover_arithmetic(const RealGenome& a, const RealGenome& b, kernel::RandomStream& random);

// The genes as a weight list a network task takes (`weights=` parameter, docs/networks.md):
// numbers separated by spaces, written so that they read back to the same floats (each gene as
// the float it becomes; one beyond the float range as the largest float of its sign).
std::string weights_text(const RealGenome& g);

}  // namespace symb::evo
