#include "symb/evo/fitness/fitness.hpp"

#include <algorithm>
#include <cmath>

namespace symb::evo {

namespace {

double clamp_speed(double v) { return std::isfinite(v) ? std::clamp(v, -1.0, 1.0) : 0.0; }
double clamp_activation(double i) { return std::isfinite(i) ? std::clamp(i, 0.0, 1.0) : 1.0; }

}  // namespace

std::optional<FitnessFormula> parse_fitness_formula(std::string_view name) {
  if (name == "floreano_mondada") return FitnessFormula::kFloreanoMondada;
  if (name == "one_plus_one") return FitnessFormula::kOnePlusOne;
  if (name == "liolib") return FitnessFormula::kLioLib;
  return std::nullopt;
}

const char* to_string(FitnessFormula f) {
  switch (f) {
    case FitnessFormula::kFloreanoMondada: return "floreano_mondada";
    case FitnessFormula::kOnePlusOne: return "one_plus_one";
    case FitnessFormula::kLioLib: return "liolib";
  }
  return "?";
}

double normalised_wheel(double units) { return clamp_speed(units / kWheelUnitsMax); }

double highest_ir_activation(std::span<const float> readings) {
  double i = 0;
  for (float r : readings) i = std::max(i, clamp_activation(static_cast<double>(r) / kIrReadingMax));
  return i;
}

double floreano_mondada(double left, double right, double i) {
  left = clamp_speed(left), right = clamp_speed(right), i = clamp_activation(i);
  const double v = (std::abs(left) + std::abs(right)) / 2;
  const double dv = std::abs(left - right) / 2;
  return v * (1 - std::sqrt(dv)) * (1 - i);
}

double one_plus_one_step(double left, double right, double i) {
  left = clamp_speed(left), right = clamp_speed(right), i = clamp_activation(i);
  const double translation = std::abs(left + right) / 2;
  const double rotation = std::abs(left - right) / 2;
  return translation * (1 - rotation) * (1 - i);
}

double liolib_step(double left, double right, double i) {
  left = clamp_speed(left), right = clamp_speed(right), i = clamp_activation(i);
  const double s_min = 1 - i;
  if (s_min <= 0.1) return 0.01 * s_min;  // touching: only the floor term
  const double translation = std::min(std::abs(left), std::abs(right));
  const double rotation = std::abs(left - right);
  return translation * (1 - rotation) * s_min;
}

double fitness_step(FitnessFormula f, double left_units, double right_units, std::span<const float> ir) {
  const double l = normalised_wheel(left_units), r = normalised_wheel(right_units);
  const double i = highest_ir_activation(ir);
  switch (f) {
    case FitnessFormula::kFloreanoMondada: return floreano_mondada(l, r, i);
    case FitnessFormula::kOnePlusOne: return one_plus_one_step(l, r, i);
    case FitnessFormula::kLioLib: return liolib_step(l, r, i);
  }
  return 0;
}

}  // namespace symb::evo
