#include "symb/robot/thymio_ir.hpp"

#include <cmath>

namespace symb::robot::thymio {

namespace {
constexpr double kM = kIrMax, kX0 = 0.03, kC = 73;
}

double ir_reading(double distance) {
  if (!(distance >= kX0)) return kM;  // also NaN: treat as contact, the safe side
  if (distance > kIrRange) return 0;
  return kM * (kC - kX0 * kX0) / (distance * distance - 2 * kX0 * distance + kC);
}

double ir_distance(double reading) {
  if (!(reading > ir_reading(kIrRange))) return kIrRange;  // also NaN: nothing seen
  if (reading >= kM) return 0;
  // x^2 - 2 x0 x + c - m (c - x0^2) / v = 0, the larger root.
  const double disc = kX0 * kX0 - kC + kM * (kC - kX0 * kX0) / reading;
  if (disc <= 0) return 0;
  const double x = kX0 + std::sqrt(disc);
  return x < 0 ? 0 : (x > kIrRange ? kIrRange : x);
}

}  // namespace symb::robot::thymio
