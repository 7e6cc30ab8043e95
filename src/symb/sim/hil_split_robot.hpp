// HilSplitRobot: a robot's side of a split world (hil_split_world.hpp; `symb serve --scenario S
// --robot NAME`): the robot's node built from the scenario exactly as the in-process run builds it
// (RobotSystem, the same task types and plugins, the node seed robot_node_seed(seed, index)), over
// devices fed from and answering to a stream (a DdsFrameStream) in the split world's frames
// (hil_split_protocol.hpp).
//
// Time: the node runs on a VirtualTimeExecutor whose clock the world's frames drive, as a 3D
// board's does (mujoco/hil_module_board.hpp): a clock activity stands where the world runner
// stands in process (its period and priority, its first tick one period after the start) and its
// tick k publishes sensor frame k's readings to the robot's ir, pose and ground devices, stamped
// with the tick's node time, as the runner publishes them. When frame k arrives, serve() runs the
// executor up to just before tick k + 1 (everything the node does before the world's next step in
// process) and answers [k, left, right] with the wheels' output then. So the node computes what it
// computes in process, bit for bit.
//
// The node is built at the world's hello, which carries the run's seed (the world's --seed, or the
// scenario's) and checks the robot's index and the robot count against this scenario; the node
// then runs up to just before the world's first step, and the answer to the hello carries its
// wheels then, which the world's step 1 applies, as in process. One run per robot process: the node's time
// cannot go back, so a second hello after sensor frames is refused (finished() with the reason).
//
// In a world with a radio (world.radio) the robot's radio task is made on a LocalRadio of this
// process that never steps: what a hooked task sends it goes to the world in a radio frame before
// the next answer (LocalRadio::take_pending), and the radio frames that came before sensor frame k
// (what the world's radio delivered at step k) are posted into the radio task at tick k, before
// the readings, in the order they came (LocalRadio::deliver): where and when the world's radio
// posts them in process under the lockstep executor (at the step's sync instant, before the
// robot's window, whose first act is publishing the readings).
//
// The world's bye frame ends the run cleanly (ended()); a stream that ends without it is a world
// lost.
//
// Bad input: garbage on the stream is counted by the frame decoder (CRC, framing) and dropped;
// good frames that are neither a hello, a sensor frame nor a good radio frame (its sender another
// robot of the world) are malformed; radio frames that no sensor frame of theirs followed are
// stale; a sensor frame not newer
// than the last is out of order (dropped); skipped sequence numbers are missed.
//
// Threads: everything runs on the caller's thread (serve() drives the executor); stats() may be
// read from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/local_radio.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim {

struct HilSplitRobotOptions {
  // Task types beyond the built-in ones (`symb run --plugin` on the world's side), as
  // SessionOptions::task_types; the scenario's own plugins are loaded by create().
  std::vector<RegisterTaskTypes> task_types;
  std::size_t log_capacity = 1024;
  std::function<void(const std::string&)> on_event;  // "built with seed 7", refusals
};

struct HilSplitRobotBoardStats {
  io::FrameStats decoder;           // dropped(): frames the CRC or the framing refused
  std::uint64_t hellos = 0;         // hellos answered
  std::uint64_t frames = 0;         // sensor frames passed to the node
  std::uint64_t malformed = 0;      // good frames that are neither
  std::uint64_t out_of_order = 0;   // sequence not newer than the last one: dropped
  std::uint64_t missed = 0;         // sequence numbers skipped
  std::uint64_t answers = 0;        // wheel frames the stream took
  std::uint64_t write_errors = 0;   // ... it refused
  std::uint64_t radio_in = 0;       // radio messages from the world posted into its radio task
  std::uint64_t radio_dropped = 0;  // ... refused by it (its queue full)
  std::uint64_t radio_stale = 0;    // radio frames dropped: their sensor frame did not follow
  std::uint64_t radio_out = 0;      // radio messages its radio task sent, carried to the world
  std::uint32_t last_seq = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "frames 166 (0 missed, 0 out of order), hellos 1, bad 0 (crc 0, malformed 0); answers 167"
std::string describe(const HilSplitRobotBoardStats& s);

class HilSplitRobot {
 public:
  // Robot `robot` of a 2D `scenario` (checked as the world checks it, HilSplitWorld::check).
  // Loads the scenario's plugins and checks the scenario against the task types, as a session
  // does; builds nothing yet (the hello brings the seed).
  static kernel::Result<std::unique_ptr<HilSplitRobot>> create(const Scenario& scenario, std::string_view robot,
                                                               std::shared_ptr<io::IOStream> port,
                                                               HilSplitRobotOptions options = {});
  ~HilSplitRobot();
  HilSplitRobot(const HilSplitRobot&) = delete;
  HilSplitRobot& operator=(const HilSplitRobot&) = delete;

  // Reads the stream for up to `timeout` of wall time and handles every frame that came. Returns
  // the sensor frames handled; fails when the stream ends (the world left, or was lost) or when a
  // hello could not be served (another scenario, a second run); the robot is then finished.
  kernel::Result<std::size_t> serve(kernel::Duration timeout);

  // The world said the run ended (its bye frame), after that many steps.
  std::optional<std::uint32_t> ended() const { return ended_; }
  // The node, once the hello built it (null before).
  RobotSystem* system() { return system_.get(); }
  std::size_t index() const { return index_; }
  std::optional<std::uint64_t> seed() const { return seed_; }
  // Node time (the world's step times).
  kernel::Time now() const { return executor_.now(); }
  HilSplitRobotBoardStats stats() const;

  struct Shared;  // the state the devices and the clock share (public so the .cpp can name it)

 private:
  class Clock;
  HilSplitRobot(Scenario scenario, std::size_t index, std::shared_ptr<io::IOStream> port, HilSplitRobotOptions options);
  kernel::Status handle(std::span<const std::byte> payload, std::size_t& handled);
  kernel::Status build(std::uint64_t seed);
  void answer(std::uint32_t seq);
  void event(const std::string& text);

  Scenario scenario_;
  std::size_t index_;
  std::unique_ptr<LocalRadio> radio_;  // world.radio: its radio task's medium; outlives system_
  std::shared_ptr<io::IOStream> port_;
  HilSplitRobotOptions options_;
  std::vector<RegisterTaskTypes> extra_types_;  // options' and the scenario's plugins
  kernel::VirtualTimeExecutor executor_;
  std::shared_ptr<Shared> shared_;
  std::unique_ptr<RobotSystem> system_;  // after shared_ (its tasks hold the devices)
  std::unique_ptr<Clock> clock_;         // after system_: stopped first
  std::optional<std::uint64_t> seed_;
  std::optional<std::uint32_t> ended_;
  io::FrameDecoder decoder_{1024};
  std::vector<std::byte> buf_;
  std::vector<std::byte> frame_;
  std::vector<std::byte> radio_payload_;
  mutable std::mutex stats_mu_;
  HilSplitRobotBoardStats stats_;
};

}  // namespace symb::sim
