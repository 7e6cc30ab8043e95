// Thymio II's 7 horizontal IR proximity sensors: where each looks (in the robot frame: x forward,
// y left, angles counter-clockwise from x), the response curve of one ray (Enki's Thymio2 model:
// F(x) = m (c - x0^2) / (x^2 - 2 x0 x + c), x in cm, m = 4505, x0 = 0.03, c = 73, 0 beyond 14 cm)
// and its inverse, the distance a reading stands for. The numbers are the robot's: the
// simulator's IrModel computes readings with them and controllers (motor schemas) read distances
// back, so both live here, in the robot layer, once.
#pragma once

#include <array>
#include <cstddef>
#include <numbers>

namespace symb::robot::thymio {

inline constexpr std::size_t kIrCount = 7;  // 0 far left .. 4 far right, 5 back left, 6 back right
inline constexpr double kIrMax = 4505;      // the reading at contact
inline constexpr double kIrRange = 14;      // cm: nothing farther is seen

struct IrMount {
  double x, y, angle;  // cm, cm, rad (robot frame)
};
inline constexpr std::array<IrMount, kIrCount> kIrMounts = {{
    {6.2, 4.85, 0.69813},
    {7.5, 2.55, 0.34906},
    {7.95, 0.0, 0.0},
    {7.5, -2.55, -0.34906},
    {6.2, -4.85, -0.69813},
    {-2.95, 2.95, -std::numbers::pi},
    {-2.95, -2.95, -std::numbers::pi},
}};

// The distance (cm, from the sensor) a reading stands for: kIrRange for a reading <= the response
// at kIrRange (nothing seen, or at the edge), 0 at kIrMax and above. Monotone decreasing.
double ir_distance(double reading);
// The reading an obstacle at `distance` cm gives (the forward curve; for tests and thresholds).
double ir_reading(double distance);

}  // namespace symb::robot::thymio
