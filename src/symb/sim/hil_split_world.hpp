// HilSplitWorld: the world's side of a split world (docs/bus.md, "A world split over processes";
// issue 19): a 2D ScenarioSession runs the world and every robot's node in process except the
// remote ones, whose nodes run in other processes (HilSplitRobot, `symb serve --scenario`) and
// talk to the world over a stream each (a DdsFrameStream; any io::IOStream) in the
// hardware-in-the-loop frames (hil_split_protocol.hpp), in lockstep:
//
//   hello       [0, seed, index, count, digest] every period until every remote robot answered; the
//               answer's wheels (what the node set before the first step) go to its SimWheels
//   each world step k (a runner observer, after the step, on the runner's context):
//     1. [k, the readings the runner published for step k] to every remote robot;
//     2. wait for every remote robot's answer to k (up to answer_wait of wall time), reading
//        whatever comes; set each one's wheels (the runner's SimWheels) from its answer, which the
//        world's step k + 1 applies, as it applies the command an in-process node gave in step
//        k's window.
//
// In a world with a radio (world.radio), the radio crosses in radio frames: what the world's radio
// delivers to a remote robot at step k (a LocalRadio relay) goes before sensor frame k, and what
// the robot's radio task sent in its window comes before its answer, which puts it on air for the
// world's step k + 1 (LocalRadio::transmit), as an in-process robot's radio task does. The radio
// observes the runner before this does (the session attached it first), so step k's deliveries are
// all there when frame k goes.
//
// A remote robot runs its node on a virtual-time executor whose clock these frames drive
// (HilSplitRobot), so the robot computes what its node computes in process, and the run is the
// in-process one bit for bit: the same trajectory hash (tests/apps/split_world_test.cpp).
//
// A remote robot that does not answer step k within answer_wait, or whose stream ends (its
// process killed: DDS liveliness; or it left), is gone: it is reported once (on_event), its wheels
// stop for the rest of the run, the world stops waiting for it and goes on; stats() says when and
// why. Garbage on a robot's stream is counted (CRC and framing by the decoder, malformed payloads)
// and dropped; answers to older steps are counted stale.
//
// Limits (check() says so at the scenario's place): 2D worlds; no remote robot that scenario
// events name.
//
// Threads: the observer runs on the runner's context; wait_for_robots() on the caller's, before
// the session starts; stats() from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim {

struct HilSplitWorldOptions {
  // How long a step waits for a remote robot's answer (wall time) before it is declared gone.
  kernel::Duration answer_wait = std::chrono::seconds(2);
  std::function<void(const std::string&)> on_event;  // "robot r2: ..." for the person
};

struct HilSplitRobotStats {
  std::string robot;
  std::size_t index = 0;
  std::uint64_t frames_sent = 0;     // hello and sensor frames the stream took
  std::uint64_t write_errors = 0;    // frames it refused
  std::uint64_t received = 0;        // good wheel frames
  std::uint64_t malformed = 0;       // good frames that are no wheel frame nor a good radio frame
  std::uint64_t radio_sent = 0;      // radio frames sent: messages the world's radio delivered to it
  std::uint64_t radio_received = 0;  // radio frames put on air
  bool radio = false;                // the world has a radio
  io::FrameStats decoder;            // dropped(): bad frames (CRC, framing)
  std::uint64_t applied = 0;         // steps that took the answer to that step
  std::uint64_t stale = 0;           // answers to an older step (a hello repeated, a late one)
  double waited_s = 0;               // wall time the steps spent waiting for this robot's answers
  bool answered = false;             // the hello was answered
  bool gone = false;                 // no longer followed: its wheels stopped
  std::uint64_t gone_at = 0;         // the step it was declared gone at
  std::string why;                   // ... and why

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "robot r2: sent 168 (0 not taken), received 167 good, 0 bad; applied 166, 0 stale; waited 41 ms"
std::string describe(const HilSplitRobotStats& s);

class HilSplitWorld {
 public:
  struct Remote {
    std::size_t robot = 0;  // index in the session
    std::shared_ptr<io::IOStream> port;
  };

  // Whether robot `robot` of `scenario` can run in another process: a 2D world, and no event of the scenario names it.
  // An error at its place in the file.
  static kernel::Status check(const Scenario& scenario, std::size_t robot);
  // `session` is created and not started. Empties the remote robots' nodes (their devices answer
  // to the streams now) and observes the runner. Fails on check(), a robot out of range or named
  // twice, a missing port.
  static kernel::Result<std::unique_ptr<HilSplitWorld>> create(ScenarioSession& session, std::vector<Remote> remotes,
                                                               HilSplitWorldOptions options = {});
  ~HilSplitWorld();
  HilSplitWorld(const HilSplitWorld&) = delete;
  HilSplitWorld& operator=(const HilSplitWorld&) = delete;

  // The hello, once per control period, until every remote robot answered or `timeout` of wall
  // time: then fails naming those that did not. `stopped` (polled each period) ends it early.
  kernel::Status wait_for_robots(kernel::Duration timeout, const std::function<bool()>& stopped = {});

  // Tells every remote robot not gone that the run ended after `steps` steps (the bye frame).
  void say_bye(std::uint64_t steps);

  std::vector<HilSplitRobotStats> stats() const;
  // Remote robots declared gone so far.
  std::size_t gone() const;

 private:
  struct Robot;
  HilSplitWorld(ScenarioSession& session, HilSplitWorldOptions options);
  void on_step(const StepRecord& record);
  // Sends `payload` after the radio frames of robot r's messages heard at step `step` (if any).
  void send(Robot& r, const std::vector<std::byte>& payload, std::uint32_t step = 0);
  // Reads what robot r sent for up to `wait`; applies an answer to `step` (returns true then).
  bool read(Robot& r, kernel::Duration wait, std::uint32_t step);
  void lose(Robot& r, std::uint64_t step, const std::string& why);
  void event(const std::string& text);

  ScenarioSession& session_;
  HilSplitWorldOptions options_;
  std::vector<std::unique_ptr<Robot>> robots_;
  std::vector<std::byte> frame_;
  std::vector<std::byte> radio_payload_;
  std::vector<std::byte> buf_;
  mutable std::mutex stats_mu_;
};

}  // namespace symb::sim
