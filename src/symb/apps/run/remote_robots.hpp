// Remote robots of a `symb run` (`--bus dds --remote NAME,...`; docs/bus.md "A world split over
// processes"): the named robots' nodes run in other processes (`symb serve --scenario S --robot
// NAME`), this one runs the world and every other robot, in lockstep over Cyclone DDS. The sim
// layer's HilSplitWorld does the stepping; this puts one DdsFrameStream per remote robot under it
// (topics rt/<prefix>/<robot>/to_robot and .../to_world), waits for the robots' processes before
// the run, tells them it ended after it, and says what happened for summary.txt.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/hil_split_world.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::apps::run {

// The topic directions of a remote robot's pair of topics.
inline constexpr std::string_view kToRobot = "to_robot";
inline constexpr std::string_view kToWorld = "to_world";

struct RemoteRobotsOptions {
  std::vector<std::string> robots;  // names; empty: every robot runs in process
  io::DdsFrameOptions dds;
  kernel::Duration wait = std::chrono::seconds(10);        // for the robots' processes to answer
  kernel::Duration answer_wait = std::chrono::seconds(2);  // for each step's answer
};

class RemoteRobots {
 public:
  // Before the session starts. Fails naming a robot the scenario does not have, or one that
  // cannot run apart (HilSplitWorld::check), or when DDS cannot start.
  static kernel::Result<std::unique_ptr<RemoteRobots>> attach(sim::ScenarioSession& session,
                                                              const RemoteRobotsOptions& options,
                                                              std::function<void(const std::string&)> on_event);
  ~RemoteRobots();

  // The hello, until every robot's process answered (options.wait) or `stopped` (Ctrl-C).
  kernel::Status wait_for_robots(const std::function<bool()>& stopped);
  // After the run of `steps` steps: the bye frame to every robot not gone, acknowledged, then the
  // streams' writers go; the robots' processes end.
  void finish(std::uint64_t steps);
  // summary.txt's part: the bus, each remote robot's figures, the ones gone and why.
  std::string summary() const;
  std::size_t gone() const { return world_->gone(); }

 private:
  RemoteRobots() = default;
  RemoteRobotsOptions options_;
  std::shared_ptr<io::DdsFrameLinks> links_;
  std::vector<std::shared_ptr<io::DdsFrameStream>> streams_;
  std::unique_ptr<sim::HilSplitWorld> world_;
};

}  // namespace symb::apps::run
