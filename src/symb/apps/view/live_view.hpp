// LiveView: a 2D scenario run seen and driven from a browser (`symb run --view`). It owns the
// ViewServer and turns the run into frames (view_json.hpp) and the page's commands into actions:
//   robot NAME     choose the robot whose task graph, probes, SysLog and shell the page shows
//   shell LINE     run LINE in this page's shell session on that robot
//   pause | resume | step | speed X   (virtual time only; X = 0 as fast as possible)
//
// Frames are made on the run's thread between two slices (between_slices(), where no robot's node
// runs), at most 20 poses frames and 5 detail frames (graph, log, probes, status) a second, and
// only while a client is connected; the server's queues then carry them to the browsers without
// the run waiting (view_server.hpp). The page's shell is a real shell session on the robot's node
// (shell::attach_shell over a loopback stream), the same commands as `symb shell`, run on the
// node's own context (injected work) as the TCP shell's are.
#pragma once

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/apps/run/run_control.hpp"
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
};

// The options a --view request asks for; `robot` is shown first when the request names none.
LiveViewOptions live_view_options(const ViewRequest& request, std::string robot = {});

class LiveView {
 public:
  // `control` is null for a --realtime run (no pause, step or speed). The session, the scenario
  // name and the control must outlive the view.
  static kernel::Result<std::unique_ptr<LiveView>> start(sim::ScenarioSession& session, std::string scenario_name,
                                                         double duration_seconds, run::RunControl* control,
                                                         LiveViewOptions options);
  // Closes the page's shell sessions and the server.
  ~LiveView();

  std::string url() const { return server_->url(); }
  const ViewServer& server() const { return *server_; }
  const std::string& robot_name(std::size_t i) const { return robots_.at(i); }

  // On the run's thread, between slices (run::RunLoop::between_slices).
  void between_slices();
  // Every probe sample of the run (on the thread that hands it over).
  void on_probe(const os::ProbeSample& s);
  // The run is over: a last status frame says so.
  void finish();

 private:
  struct ShellLink;
  LiveView(sim::ScenarioSession& session, std::string scenario, double duration, run::RunControl* control,
           LiveViewOptions options);
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

  sim::ScenarioSession& session_;
  const std::string scenario_;
  const double duration_;
  run::RunControl* const control_;
  const LiveViewOptions options_;
  std::vector<std::string> robots_;
  std::vector<std::string> nodes_;  // robot i's node name, as probe samples carry it
  std::unique_ptr<ViewServer> server_;
  std::atomic<ViewServer*> handlers_server_{nullptr};  // server_ once it is there, for the handlers

  std::atomic<std::size_t> selected_{0};
  std::atomic<bool> selection_changed_{true};
  std::size_t shown_ = SIZE_MAX;  // the run thread's: whose log is followed
  std::uint64_t log_seq_ = 0;
  std::chrono::steady_clock::time_point last_pose_{}, last_detail_{};
  std::vector<sim::RobotState> states_;

  std::mutex probes_mu_;
  std::vector<ProbeValue> probes_;  // the selected robot's, latest per (task, channel)

  std::mutex shells_mu_;
  std::map<ClientId, std::unique_ptr<ShellLink>> shells_;
  std::uint64_t shells_opened_ = 0;
};

}  // namespace symb::apps::view
