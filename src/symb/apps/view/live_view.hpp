// LiveView: a run seen and driven from a browser (`symb run --view`, `symb evolve --view`,
// `symb board --view`). What it shows is a ViewTarget: the run's robots (name and node) and its
// world, 2D (arena, walls, robots), 3D (an organism's modules and how they are docked) or none (a
// board, whose world is elsewhere). It owns the ViewServer and turns the run into frames
// (view_json.hpp) and the page's commands into actions:
//   robot NAME     choose the robot whose task graph, probes, SysLog and shell the page shows
//   shell LINE     run LINE in this page's shell session on that robot
//   pause | resume | step | speed X   (virtual time only; X = 0 as fast as possible)
//
// Frames are made on the run's thread between two slices (between_slices(), where no robot's node
// runs), at most 20 poses frames and 5 detail frames (graph, log, probes, spikes, fitness,
// status) a second, and only while a client is connected; the server's queues then carry them to
// the browsers without the run waiting (view_server.hpp).
//
// Over time: the probes of the robot shown are kept from the moment it was chosen in a
// ProbeHistory (bounded: the page plots each series from then on), spikes (the "spikes" channel
// of spiking networks) are passed on as they come, at most kMaxSpikesPerFrame per detail frame
// (the rest counted), and an evolution's fitness series (LiveViewOptions::fitness_task) are kept
// for the whole run whichever robot is shown. A page that opens gets every kept point once. The page's shell is a real
// shell session on the robot's node (shell::attach_shell over a loopback stream), the same commands as `symb shell`,
// run on the node's own context (injected work) as the TCP shell's are.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/apps/run/run_control.hpp"
#include "symb/apps/view/probe_history.hpp"
#include "symb/apps/view/view_json.hpp"
#include "symb/apps/view/view_request.hpp"
#include "symb/apps/view/view_server.hpp"
#include "symb/io/stream.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::apps::view {

struct LiveViewOptions {
  ViewServerOptions server;
  std::string robot;                   // shown first; empty: the first robot
  std::size_t max_pose_robots = 2000;  // per poses frame (every k-th robot beyond)
  kernel::Duration pose_every = std::chrono::milliseconds(50);
  kernel::Duration detail_every = std::chrono::milliseconds(200);
  // An evolution run: the robot and task whose fitness series are plotted for the whole run.
  std::string fitness_robot, fitness_task;
};

// What a LiveView shows. `nodes[i]` is robot i's node (named robots[i]); they, and what the
// functions reach, must outlive the view. poses() and seconds() are called on the run's thread
// between slices.
struct ViewTarget {
  std::vector<std::string> robots;
  std::vector<os::Node*> nodes;
  const sim::WorldSpec* world = nullptr;  // a 2D world
  std::vector<ModuleShape> organism;      // a 3D one (empty: none)
  std::function<std::string()> poses;     // a step or organism frame of the world now; empty: no world
  std::function<double()> seconds;        // the run's time now, s
};

// A 2D scenario run's target: its robots, arena and poses (at most `max_pose_robots` a frame).
ViewTarget scenario_view_target(sim::ScenarioSession& session, std::size_t max_pose_robots);
// Robots without a world (a board): their time is the first node's clock.
ViewTarget nodes_view_target(std::vector<std::string> robots, std::vector<os::Node*> nodes);

// The options a --view request asks for; `robot` is shown first when the request names none.
LiveViewOptions live_view_options(const ViewRequest& request, std::string robot = {});

class LiveView {
 public:
  // `control` is null for a --realtime run (no pause, step or speed). The session, the scenario
  // name and the control must outlive the view.
  static kernel::Result<std::unique_ptr<LiveView>> start(ViewTarget target, std::string scenario_name,
                                                         double duration_seconds, run::RunControl* control,
                                                         LiveViewOptions options);
  // A 2D scenario run (scenario_view_target).
  static kernel::Result<std::unique_ptr<LiveView>> start(sim::ScenarioSession& session, std::string scenario_name,
                                                         double duration_seconds, run::RunControl* control,
                                                         LiveViewOptions options);
  // Closes the page's shell sessions and the server.
  ~LiveView();

  std::string url() const { return server_->url(); }
  const ViewServer& server() const { return *server_; }
  const std::string& robot_name(std::size_t i) const { return target_.robots.at(i); }
  // Spikes not passed on (more than kMaxSpikesPerFrame in one detail frame's time).
  std::uint64_t spikes_dropped() const;

  // On the run's thread, between slices (run::RunLoop::between_slices).
  void between_slices();
  // Every probe sample of the run (on the thread that hands it over).
  void on_probe(const os::ProbeSample& s);
  // The run is over: a last status frame says so.
  void finish();

 private:
  struct ShellLink;
  LiveView(ViewTarget target, std::string scenario, double duration, run::RunControl* control, LiveViewOptions options);
  void on_open(ClientId client);
  void on_message(ClientId client, std::string_view text);
  void on_close(ClientId client);
  std::optional<std::string> poll(ClientId client);
  void shell_line(ClientId client, std::string_view line);
  void close_shell(ShellLink& link);
  // To one client from a handler: a browser may connect before start() has the server in hand.
  void send(ClientId client, std::string frame);
  std::string hello() const;
  void send_details(bool finished);
  os::Node& node(std::size_t robot) { return *target_.nodes[robot]; }

  const ViewTarget target_;
  const std::string scenario_;
  const double duration_;
  run::RunControl* const control_;
  const LiveViewOptions options_;
  std::vector<std::string> nodes_;  // robot i's node name, as probe samples carry it
  std::string fitness_node_;        // the node whose fitness_task is followed; empty: none
  std::unique_ptr<ViewServer> server_;
  std::atomic<ViewServer*> handlers_server_{nullptr};  // server_ once it is there, for the handlers

  std::atomic<std::size_t> selected_{0};
  std::atomic<bool> selection_changed_{true};
  std::size_t shown_ = SIZE_MAX;  // the run thread's: whose log is followed
  std::uint64_t log_seq_ = 0;
  std::chrono::steady_clock::time_point last_pose_{}, last_detail_{};

  mutable std::mutex probes_mu_;                                    // what follows, up to shells_mu_
  ProbeHistory probes_;                                             // the selected robot's
  ProbeHistory fitness_;                                            // the evolution's, whatever is selected
  std::vector<std::pair<std::string, std::vector<float>>> spikes_;  // per spiking task: (s, neuron) pairs
  std::size_t spikes_pending_ = 0;
  std::uint64_t spikes_dropped_ = 0;
  bool send_all_ = true;  // a page opened: every kept point goes in the next frames

  std::mutex shells_mu_;
  std::map<ClientId, std::unique_ptr<ShellLink>> shells_;
  std::uint64_t shells_opened_ = 0;
};

}  // namespace symb::apps::view
