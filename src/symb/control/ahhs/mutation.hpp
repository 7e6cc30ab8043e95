// Mutation of an AHHS network's numbers, after the authors' 2009 operator (per hormone with one
// probability, per rule with another), with its slip fixed: the reference code drew one of two
// cases for a hormone and kept base emission as an unreachable third, so base emission never
// evolved. Here each of base, decay and diffusion is drawn with probability 1/3 (docs/ahhs.md,
// pitfall 3). Structure (compartments, links, placements, rule kinds) is left alone.
#pragma once

#include "symb/control/ahhs/network.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::ahhs {

struct MutationOptions {
  double hormone_probability = 0.5;  // per hormone
  double rule_probability = 0.5;     // per rule
  double step = 0.1;                 // a changed number moves by U[-step, step]
};

// Which number of a hormone a mutation changes.
enum class HormoneSlot : std::uint8_t { kBase, kDecay, kDiffusion };

// Mutates `n` in place; the result is still valid (values are clamped into their ranges, diffusion
// to 1 / the largest degree). Returns how many numbers changed.
std::size_t mutate(Network& n, kernel::RandomStream& random, const MutationOptions& options = {});

// One hormone number: the slot drawn uniformly among the three.
HormoneSlot mutate_hormone(Network& n, std::size_t hormone, kernel::RandomStream& random, double step);

}  // namespace symb::control::ahhs
