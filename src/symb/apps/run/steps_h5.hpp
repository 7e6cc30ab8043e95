// StepsH5: a 2D run's recorded steps as an HDF5 file (steps.h5), compact and read in a line by
// h5py, pandas, MATLAB, Julia or h5dump. One array per quantity, steps along the first axis,
// robots along the second (T recorded steps, R recorded robots):
//   /step      T        uint64   the world's step count (1 for the first step)
//   /time_s    T        float64  simulated time of the step
//   /pose      T x R x 3 float64 x_cm, y_cm, heading_rad (exactly the run's values)
//   /ir        T x R x 7 float32 the seven IR readings published to the robot, rounded to 0.1 as
//                                in steps.csv (noisy float digits do not deflate)
//   /wheels    T x R x 2 float64 left_cm_s, right_cm_s (the speeds used during the step)
//   /contact   T x R    uint8    1 while touching a wall or a robot
//   /robots    R        string   the recorded robots' names (UTF-8)
//   /robot_index R      uint32   their indices in the scenario's robot order
// Each array has a `columns` attribute naming its last axis. The file's root has the run's
// metadata as attributes: format, scenario, scenario_file, seed, control_period_s, record_every,
// robot_count (the whole world's), and, once closed, steps (T), simulated_s and interrupted.
//
// Appending: steps are gathered in memory a block at a time (the chunk's length along the step
// axis) and each full block is written as whole chunks (shuffled, deflated) and flushed, so a
// chunk is compressed once and a process killed outright loses at most the block in memory.
// close() writes the last partial block and the closing attributes: a run stopped with Ctrl-C
// closes it on its way out, with every step so far. The serial HDF5 library is not thread-safe:
// one writer per process at a time, on one thread (the world's stepping context).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::apps::run {

struct StepsH5Meta {
  std::string scenario;
  std::string scenario_file;
  std::uint64_t seed = 0;
  double control_period_s = 0;
  std::uint32_t record_every = 1;
  std::size_t robot_count = 0;             // in the world
  std::vector<std::string> robots;         // the recorded ones' names
  std::vector<std::size_t> robot_indices;  // and their indices in the world
};

class StepsH5 {
 public:
  // Creates (or truncates) `path` with empty, extensible arrays and the metadata.
  static kernel::Result<std::unique_ptr<StepsH5>> create(const std::filesystem::path& path, const StepsH5Meta& meta);
  ~StepsH5();  // closes (the result of close() is then lost: call it first)
  StepsH5(const StepsH5&) = delete;
  StepsH5& operator=(const StepsH5&) = delete;

  // Appends one step: the recorded robots' entries of `record` (meta.robot_indices). A write
  // error is kept and returned by close(); later appends are then ignored.
  void append(const sim::StepRecord& record, double time_s);
  // Writes what is gathered, the closing attributes, and closes the file. Idempotent.
  kernel::Status close(double simulated_s, bool interrupted);

  std::uint64_t steps() const { return steps_; }
  std::uint32_t block_steps() const { return block_; }

 private:
  struct Handles;
  StepsH5(std::unique_ptr<Handles> h, std::filesystem::path path, std::vector<std::size_t> robots, std::uint32_t block);
  void write_block();

  std::unique_ptr<Handles> h_;
  std::filesystem::path path_;
  std::vector<std::size_t> robots_;
  std::uint32_t block_;
  std::uint64_t steps_ = 0;    // appended
  std::uint64_t written_ = 0;  // in the file
  std::string error_;
  // The block in memory, row-major as in the file.
  std::vector<std::uint64_t> step_;
  std::vector<double> time_;
  std::vector<double> pose_;
  std::vector<float> ir_;
  std::vector<double> wheels_;
  std::vector<std::uint8_t> contact_;
};

}  // namespace symb::apps::run
