// PhaseOscillator: one unit of a central pattern generator (CPG), the coupled phase oscillators
// with which Ijspeert's salamander robot and many modular robots (M-TRAN, YaMoR, Roombots) make a
// travelling wave along a chain of joints. Oscillator i of a chain has a phase theta_i and drives
// its joint to  offset + amplitude * sin(theta_i).  Its phase advances at its own frequency and is
// pulled towards a fixed lag behind its neighbours:
//
//   d theta_i / dt = 2 pi nu + sum over neighbours j of  w * sin(theta_j - theta_i - (i - j) * lag)
//
// At the fixed point theta_i - theta_j = (j - i) * lag: each oscillator trails the one before it by
// `lag`, so a wave runs from the chain's id 0 end to its other end. Only chain neighbours
// (|i - j| == 1) couple; a phase heard from anyone else is ignored. A neighbour's phase is
// carried forward from when it was sent at the nominal frequency (so a link's latency costs no
// phase error) and forgotten when older than `neighbour_timeout`: a module that was undocked, or
// whose messages stopped, no longer pulls. Pure state, no clock and no allocation in step();
// deterministic.
#pragma once

#include <array>
#include <cstdint>
#include <numbers>
#include <optional>

namespace symb::control::cpg {

struct OscillatorParams {
  std::int32_t id = 0;                // position in the chain
  double frequency = 0.5;             // Hz
  double amplitude = 0.5;             // rad
  double offset = 0;                  // rad
  double coupling = 4.0;              // w, rad/s
  double lag = std::numbers::pi / 2;  // rad that each oscillator trails the one before it
  double neighbour_timeout = 0.5;     // s
  double initial_phase = 0;           // rad
};

// An integration step no longer than this keeps Euler's error small at every tested coupling.
inline constexpr double kMaxOscillatorStep = 0.005;  // s

class PhaseOscillator {
 public:
  explicit PhaseOscillator(const OscillatorParams& params) : p_(params), phase_(wrap(params.initial_phase)) {}

  // Records neighbour `id`'s phase as sent at time `sent` (s, the same clock as step()'s). A
  // false return: not a chain neighbour, or not a finite phase; nothing changed.
  bool hear(std::int32_t id, double phase, double sent);
  // Advances from the time of the previous step (the first step only sets the time) to `now`, in
  // steps of at most kMaxOscillatorStep.
  void step(double now);

  double phase() const { return phase_; }  // [0, 2 pi)
  double output() const;                   // the joint target, rad
  // How many neighbours pulled in the last step (0, 1 or 2).
  int coupled() const { return coupled_; }
  const OscillatorParams& params() const { return p_; }
  // Takes new parameters (not the phase or what was heard).
  void set_params(const OscillatorParams& params) { p_ = params; }
  void set_phase(double phase) { phase_ = wrap(phase); }

  static double wrap(double angle);  // to [0, 2 pi)

 private:
  struct Heard {
    double phase = 0;
    double sent = 0;
  };
  double rate(double t) const;  // d theta / dt at time t

  OscillatorParams p_;
  double phase_ = 0;
  std::optional<double> time_;
  std::array<std::optional<Heard>, 2> heard_{};  // [0]: id - 1, [1]: id + 1
  int coupled_ = 0;
};

}  // namespace symb::control::cpg
