// Model: a validated AHHS network compiled for stepping, with its state (hormone levels per
// compartment, actuator values). One step, synchronous over the whole network:
//   1. local update, per compartment c, from the levels at the start of the step:
//        dH[h] = base[h] - decay[h] * H[c][h] + the doses of the rules that run in c,
//      actuator rules add their doses to their actuators; H_local[c] = clamp(H[c] + dH);
//   2. diffusion, per compartment, from the local levels of c and its neighbours:
//        H[c][h] = clamp(H_local[c][h] - diffusion[h] * sum over neighbours n of (H_local[c][h] - H_local[n][h]));
//   3. actuators clamped to [-1, 1].
// Both halves are public so that a compartment can run as its own task (ahhs_compartment_task.hpp):
// local_update() needs only the compartment's own row and the sensors, diffuse() its own local row
// and its neighbours' local rows, summed in neighbour order, so a compartment task and the whole
// model give bit-identical levels. Levels are floats: they travel in messages as they are.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "symb/control/ahhs/network.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::ahhs {

class Model {
 public:
  static kernel::Result<Model> create(Network network);

  const Network& network() const { return network_; }
  std::uint32_t compartments() const { return network_.compartments; }
  std::size_t hormones() const { return network_.hormones.size(); }
  std::size_t actuator_count() const { return network_.actuators.size(); }
  std::size_t sensor_count() const { return sensor_count_; }
  const std::vector<std::uint32_t>& neighbours(std::uint32_t c) const { return neighbours_[c]; }
  // Indices of the actuators that sit in compartment c.
  const std::vector<std::uint32_t>& actuators_in(std::uint32_t c) const { return actuators_in_[c]; }

  // One step of the whole network. `sensors` are normalised to [0, 1] by the caller; a sensor
  // beyond the vector's end reads 0.
  void step(std::span<const float> sensors);
  std::span<const float> levels(std::uint32_t c) const { return {&levels_[c * stride_], stride_}; }
  std::span<float> levels(std::uint32_t c) { return {&levels_[c * stride_], stride_}; }
  std::span<const float> actuators() const { return actuators_; }
  // Total of hormone h over every compartment (conservation checks).
  double total(std::size_t h) const;
  // Back to the start levels, actuators 0.
  void reset();

  // Step 1 for compartment c: `row` its levels at the start of the step, `out` its local levels
  // (may alias neither). Actuator doses of c's actuators are added to `actuators` (full vector,
  // not clamped here).
  void local_update(std::uint32_t c, std::span<const float> row, std::span<const float> sensors, std::span<float> out,
                    std::span<float> actuators) const;
  // Step 2 for compartment c: `own` its local levels, neighbour_rows[k] the local levels of
  // neighbours(c)[k]; writes the new levels to `out` (may alias `own`).
  void diffuse(std::uint32_t c, std::span<const float> own, std::span<const float* const> neighbour_rows,
               std::span<float> out) const;

 private:
  explicit Model(Network network);
  void apply_rule(const Rule& r, const float* row, std::span<const float> sensors, float* delta,
                  std::span<float> actuators) const;

  Network network_;
  std::size_t stride_ = 0;  // hormones per compartment
  std::size_t sensor_count_ = 0;
  std::vector<std::vector<std::uint32_t>> neighbours_;
  std::vector<std::vector<std::uint32_t>> actuators_in_;
  std::vector<std::uint32_t> everywhere_;             // hormone/nonlinear rules of every compartment
  std::vector<std::vector<std::uint32_t>> rules_in_;  // rules bound to one compartment
  std::vector<float> base_, decay_, diffusion_, min_, max_;
  std::vector<float> levels_, local_, actuators_;
  std::vector<const float*> scratch_;
};

}  // namespace symb::control::ahhs
