// Fitness formulas of on-line obstacle avoidance (controller-models.md 6.1 and 6.5): what one
// control step is worth, from the wheel command the robot drove with and the IR readings it saw.
// One implementation of each, shared by every algorithm (the `fitness` task calls them; so can a
// test or a benchmark). All are pure functions of normalised quantities:
//
//   wheel speeds  v = command / 500 (Thymio motor units), clamped to [-1, 1]
//   IR activation i = max over the readings given (all 7 Thymio sensors) of reading / 4505,
//                     clamped to [0, 1]; the nearest obstacle's normalised distance d_min = 1 - i
//                     (1 = nothing in range, 0 = touching)
//
// Formulas, per step (v_l, v_r the left and right wheel speeds as above):
//   Floreano-Mondada (1994)  phi = V (1 - sqrt(dv)) (1 - i),
//                            V = (|v_l| + |v_r|) / 2 (mean absolute speed, in [0, 1]),
//                            dv = |v_l - v_r| / 2 (in [0, 1]: the halving maps the full range of a
//                            difference of two [-1, 1] speeds onto [0, 1]); phi in [0, 1].
//   (1+1)-ONLINE (Nolfi's classical fitness, Bredeche et al. 2009)
//                            phi = (|v_t| / v_t,max) (1 - |v_r| / v_r,max) d_min,
//                            v_t = (v_l + v_r) / 2 (translation, v_t,max = 1),
//                            v_r = (v_l - v_r) / 2 (rotation, v_r,max = 1); phi in [0, 1].
//   LioLib (Haasdijk 2009)   v_t = min(|v_l|, |v_r|), v_rot = |v_l - v_r| (in [0, 2]),
//                            s_min = d_min; phi = v_t (1 - v_rot) s_min, except when touching
//                            (s_min <= 0.1): phi = 0.01 s_min. phi in [-1, 1]: a fast spin
//                            (v_rot > 1) is punished, as in LioLib.
// Non-finite inputs count as 0 (a speed) or as touching (an IR reading), never as NaN.
#pragma once

#include <optional>
#include <span>
#include <string_view>

namespace symb::evo {

inline constexpr double kWheelUnitsMax = 500;  // Thymio motor units at full speed
inline constexpr double kIrReadingMax = 4505;  // the Thymio's highest IR reading

enum class FitnessFormula { kFloreanoMondada, kOnePlusOne, kLioLib };

// "floreano_mondada", "one_plus_one", "liolib"; nullopt for anything else.
std::optional<FitnessFormula> parse_fitness_formula(std::string_view name);
const char* to_string(FitnessFormula f);

// A wheel command in motor units -> [-1, 1].
double normalised_wheel(double units);
// The highest IR activation i in [0, 1] of raw readings (0 for none).
double highest_ir_activation(std::span<const float> readings);

// The formulas on normalised inputs: left, right in [-1, 1], i in [0, 1] (clamped if outside).
double floreano_mondada(double left, double right, double i);
double one_plus_one_step(double left, double right, double i);
double liolib_step(double left, double right, double i);

// One step of `f` from raw values: wheel command [left, right] in motor units, IR readings raw.
double fitness_step(FitnessFormula f, double left_units, double right_units, std::span<const float> ir);

}  // namespace symb::evo
