#include "symb/apps/view/live_view.hpp"

#include <algorithm>
#include <charconv>
#include <string_view>

#include "symb/io/loopback_stream.hpp"
#include "symb/shell/shell_task.hpp"

namespace symb::apps::view {

LiveViewOptions live_view_options(const ViewRequest& request, std::string robot) {
  LiveViewOptions o;
  o.server.host = request.host;
  o.server.port = request.port;
  o.server.token = request.token;
  o.robot = request.robot.empty() ? std::move(robot) : request.robot;
  return o;
}

namespace {

using namespace std::chrono_literals;

constexpr std::size_t kMaxSpikesPerFrame = 4000;  // per detail frame, all spiking tasks together
constexpr std::size_t kMaxSpikingTasks = 8;       // of the robot shown
// Channels of an evolution task that are its fitness (one_plus_one, mu_plus_one).
constexpr std::string_view kFitnessChannels[] = {"fitness", "champion_fitness", "best_fitness", "mean_fitness"};
constexpr std::size_t kMaxLogLines = 200;    // per frame; the rest in the next
constexpr std::size_t kLogBacklog = 50;      // lines shown from before a robot was chosen
constexpr std::size_t kMaxLineBytes = 4096;  // a shell line from the page
// finish(): how long the last frames may take in all, and how long a client may take none of them
// before it counts as stalled (ViewServer::flush).
constexpr kernel::Duration kFlushLimit = 10s;
constexpr kernel::Duration kFlushStall = 2s;

double view_seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

// A page's shell session on one robot: the page's end of a loopback stream, and the tasks the
// session made on the node (known once the injected attach ran).
struct LiveView::ShellLink {
  struct Tasks {
    std::mutex mu;
    bool cancelled = false;
    bool attached = false;
    os::TaskId io, shell;
  };
  std::size_t robot = 0;
  std::unique_ptr<io::IOStream> ours;
  std::shared_ptr<Tasks> tasks = std::make_shared<Tasks>();
};

ViewTarget scenario_view_target(sim::ScenarioSession& session, std::size_t max_pose_robots) {
  ViewTarget t;
  for (std::size_t i = 0; i < session.robot_count(); ++i) {
    t.robots.push_back(session.robot(i).name());
    t.nodes.push_back(&session.robot(i).node());
  }
  t.world = &session.world().spec();
  auto states = std::make_shared<std::vector<sim::RobotState>>();
  t.poses = [&session, states, max_pose_robots] {
    std::uint64_t step = 0;
    double seconds = 0;
    session.runner().with_world([&](sim::World& w) {
      states->resize(w.robot_count());
      for (std::size_t i = 0; i < states->size(); ++i) (*states)[i] = w.state(i);
      step = w.steps();
      seconds = w.time();
    });
    return step_json(step, seconds, *states, max_pose_robots);
  };
  t.seconds = [&session] { return session.runner().with_world([](sim::World& w) { return w.time(); }); };
  return t;
}

ViewTarget nodes_view_target(std::vector<std::string> robots, std::vector<os::Node*> nodes) {
  ViewTarget t;
  t.robots = std::move(robots);
  t.nodes = std::move(nodes);
  if (!t.nodes.empty()) t.seconds = [n = t.nodes.front()] { return view_seconds(n->now()); };
  return t;
}

kernel::Result<std::unique_ptr<LiveView>> LiveView::start(sim::ScenarioSession& session, std::string scenario_name,
                                                          double duration_seconds, run::RunControl* control,
                                                          LiveViewOptions options) {
  ViewTarget target = scenario_view_target(session, options.max_pose_robots);
  return start(std::move(target), std::move(scenario_name), duration_seconds, control, std::move(options));
}

kernel::Result<std::unique_ptr<LiveView>> LiveView::start(ViewTarget target, std::string scenario_name,
                                                          double duration_seconds, run::RunControl* control,
                                                          LiveViewOptions options) {
  if (target.robots.empty() || target.robots.size() != target.nodes.size())
    return kernel::Error{"--view: the run has no robot to show"};
  std::size_t selected = 0;
  if (!options.robot.empty()) {
    const auto it = std::find(target.robots.begin(), target.robots.end(), options.robot);
    if (it == target.robots.end())
      return kernel::Error{"--view-robot: the scenario has no robot '" + options.robot + "'"};
    selected = static_cast<std::size_t>(it - target.robots.begin());
  }
  if (!options.fitness_robot.empty() &&
      std::find(target.robots.begin(), target.robots.end(), options.fitness_robot) == target.robots.end())
    return kernel::Error{"--view: the scenario has no robot '" + options.fitness_robot + "' to follow the fitness of"};
  auto view = std::unique_ptr<LiveView>(
      new LiveView(std::move(target), std::move(scenario_name), duration_seconds, control, std::move(options)));
  view->selected_ = selected;
  LiveView* v = view.get();
  ViewServerHandlers handlers;
  handlers.on_open = [v](ClientId c) { v->on_open(c); };
  handlers.on_message = [v](ClientId c, std::string_view text) { v->on_message(c, text); };
  handlers.on_close = [v](ClientId c) { v->on_close(c); };
  handlers.poll = [v](ClientId c) { return v->poll(c); };
  auto server = ViewServer::start(view->options_.server, std::move(handlers));
  if (!server) return kernel::Error{server.error()};
  view->server_ = std::move(server).value();
  view->handlers_server_.store(view->server_.get(), std::memory_order_release);
  return view;
}

LiveView::LiveView(ViewTarget target, std::string scenario, double duration, run::RunControl* control,
                   LiveViewOptions options)
    : target_(std::move(target)),
      scenario_(std::move(scenario)),
      duration_(duration),
      control_(control),
      options_(std::move(options)),
      fitness_(ProbeHistoryOptions{.capacity = 512, .width = 1, .max_series = 4, .max_latest = 1}) {
  for (std::size_t i = 0; i < target_.nodes.size(); ++i) {
    nodes_.push_back(target_.nodes[i]->name());
    if (target_.robots[i] == options_.fitness_robot) fitness_node_ = nodes_.back();
  }
}

LiveView::~LiveView() {
  handlers_server_.store(nullptr, std::memory_order_release);
  server_.reset();  // no handler runs after this
  std::lock_guard lock(shells_mu_);
  for (auto& [client, link] : shells_) close_shell(*link);
  shells_.clear();
}

void LiveView::send(ClientId client, std::string frame) {
  if (ViewServer* s = handlers_server_.load(std::memory_order_acquire)) s->send(client, std::move(frame));
}

std::string LiveView::hello() const {
  HelloInfo h;
  h.scenario = scenario_;
  h.world = target_.world;
  h.organism = target_.organism.empty() ? nullptr : &target_.organism;
  h.robots = target_.robots;
  h.selected = selected_.load();
  h.virtual_time = control_ != nullptr;
  h.paused = control_ && control_->paused();
  h.speed = control_ ? control_->speed() : 1.0;
  h.duration_seconds = duration_;
  return hello_json(h);
}

void LiveView::on_open(ClientId client) {
  send(client, hello());
  {
    std::lock_guard lock(probes_mu_);
    send_all_ = true;  // the kept points, once more for every page (this one needs them)
  }
  selection_changed_ = true;  // the next details go to every client, this one included
}

void LiveView::on_message(ClientId client, std::string_view text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.remove_suffix(1);
  const auto space = text.find(' ');
  const std::string_view word = text.substr(0, space);
  const std::string_view rest = space == std::string_view::npos ? std::string_view() : text.substr(space + 1);
  const auto refuse = [&](const std::string& why) { send(client, shell_json("view: " + why + "\n")); };
  if (word == "shell") return shell_line(client, rest);
  if (word == "robot") {
    const auto it = std::find(target_.robots.begin(), target_.robots.end(), rest);
    if (it == target_.robots.end()) return refuse("no robot '" + std::string(rest.substr(0, 64)) + "'");
    selected_ = static_cast<std::size_t>(it - target_.robots.begin());
    selection_changed_ = true;
    return;
  }
  if (word == "pause" || word == "resume" || word == "step" || word == "speed") {
    if (!control_) return refuse("a --realtime run cannot be paused, stepped or sped up");
    if (word == "pause") control_->pause();
    if (word == "resume") control_->resume();
    if (word == "step") control_->step();
    if (word == "speed") {
      double s = -1;
      const auto r = std::from_chars(rest.data(), rest.data() + rest.size(), s);
      if (r.ec != std::errc() || r.ptr != rest.data() + rest.size() || !(s >= 0) || s > 1e6)
        return refuse("speed: expected a number from 0 (as fast as possible) to 1000000, not '" +
                      std::string(rest.substr(0, 32)) + "'");
      control_->set_speed(s);
    }
    selection_changed_ = true;  // a status frame at once
    return;
  }
  refuse("unknown command '" + std::string(word.substr(0, 32)) + "' (shell, robot, pause, resume, step, speed)");
}

void LiveView::shell_line(ClientId client, std::string_view line) {
  if (line.size() > kMaxLineBytes) {
    send(client, shell_json("error: line longer than 4096 bytes\n"));
    return;
  }
  std::lock_guard lock(shells_mu_);
  auto& link = shells_[client];
  const std::size_t robot = selected_.load();
  if (link && (link->robot != robot || !link->ours->is_open())) {
    close_shell(*link);
    link.reset();
  }
  if (!link) {
    link = std::make_unique<ShellLink>();
    link->robot = robot;
    const std::string name = "view" + std::to_string(++shells_opened_);
    auto [ours, theirs] = io::make_loopback_pair(name);
    link->ours = std::move(ours);
    std::shared_ptr<io::IOStream> stream = std::move(theirs);
    os::Node* node = target_.nodes[robot];
    // As the TCP shell opens its sessions: on the node's own context, where node calls are made.
    node->inject([node, stream, tasks = link->tasks, name] {
      std::lock_guard tl(tasks->mu);
      if (tasks->cancelled) return;
      std::string free_name = name;
      for (int k = 2; k < 100 && (node->find(free_name) || node->find(free_name + ".io")); ++k)
        free_name = name + "-" + std::to_string(k);
      shell::ShellOptions so;
      so.close_on_exit = true;
      auto r = shell::attach_shell(*node, stream, std::move(so), free_name);
      if (!r) {
        node->log().warn("view", "cannot open a shell session: " + r.error());
        stream->close();
        return;
      }
      tasks->io = r->io;
      tasks->shell = r->shell;
      tasks->attached = true;
    });
  }
  std::string text(line);
  text += '\n';
  (void)link->ours->write_all(std::as_bytes(std::span(text.data(), text.size())));
}

void LiveView::close_shell(ShellLink& link) {
  link.ours->close();
  std::lock_guard tl(link.tasks->mu);
  link.tasks->cancelled = true;
  if (!link.tasks->attached) return;
  os::Node* node = target_.nodes[link.robot];
  node->inject([node, io = link.tasks->io, shell = link.tasks->shell] {
    (void)node->remove(shell);
    (void)node->remove(io);
  });
}

void LiveView::on_close(ClientId client) {
  std::lock_guard lock(shells_mu_);
  const auto it = shells_.find(client);
  if (it == shells_.end()) return;
  if (it->second) close_shell(*it->second);
  shells_.erase(it);
}

std::optional<std::string> LiveView::poll(ClientId client) {
  std::lock_guard lock(shells_mu_);
  const auto it = shells_.find(client);
  if (it == shells_.end() || !it->second || !it->second->ours->is_open()) return std::nullopt;
  std::byte buf[4096];
  auto n = it->second->ours->read_some(buf, kernel::Duration{0});
  if (!n || *n == 0) return std::nullopt;
  return shell_json(std::string_view(reinterpret_cast<const char*>(buf), *n));
}

void LiveView::on_probe(const os::ProbeSample& s) {
  const bool fitness =
      !fitness_node_.empty() && s.node == fitness_node_ && s.task == options_.fitness_task &&
      std::find(std::begin(kFitnessChannels), std::end(kFitnessChannels), s.channel) != std::end(kFitnessChannels);
  const std::size_t sel = selected_.load();
  const bool shown = sel < nodes_.size() && s.node == nodes_[sel];
  if (!fitness && !shown) return;
  const double t = view_seconds(s.time);
  std::lock_guard lock(probes_mu_);
  if (fitness) fitness_.record(s.task, s.channel, t, s.values);
  if (!shown || s.channel == "layout") return;  // a grown network's layout is no series
  if (s.channel != "spikes") {
    probes_.record(s.task, s.channel, t, s.values);
    return;
  }
  // Spikes are passed on, not kept: none while no page looks.
  const ViewServer* server = handlers_server_.load(std::memory_order_acquire);
  if (!server || server->client_count() == 0) return;
  auto it = std::find_if(spikes_.begin(), spikes_.end(), [&](const auto& p) { return p.first == s.task; });
  if (it == spikes_.end()) {
    if (spikes_.size() >= kMaxSpikingTasks) return;
    it = spikes_.insert(spikes_.end(), {std::string(s.task), {}});
  }
  // (time ms, neuron) pairs; passed on as (time s, neuron).
  for (std::size_t i = 0; i + 1 < s.values.size(); i += 2) {
    if (spikes_pending_ >= kMaxSpikesPerFrame) {
      spikes_dropped_ += (s.values.size() - i) / 2;
      break;
    }
    it->second.push_back(s.values[i] / 1000.0f);
    it->second.push_back(s.values[i + 1]);
    ++spikes_pending_;
  }
}

std::uint64_t LiveView::spikes_dropped() const {
  std::lock_guard lock(probes_mu_);
  return spikes_dropped_;
}

void LiveView::between_slices() {
  if (server_->client_count() == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (target_.poses && now - last_pose_ >= options_.pose_every) {
    last_pose_ = now;
    server_->broadcast(target_.poses());
  }
  if (now - last_detail_ >= options_.detail_every || selection_changed_.load()) {
    last_detail_ = now;
    send_details(false);
  }
}

void LiveView::send_details(bool finished) {
  const std::size_t sel = selected_.load();
  bool all = false;
  if (sel != shown_) {
    shown_ = sel;
    const std::uint64_t last = node(sel).log().last_seq();
    log_seq_ = last > kLogBacklog ? last - kLogBacklog : 0;
    std::lock_guard lock(probes_mu_);
    probes_.clear();
    spikes_.clear();
    spikes_pending_ = 0;
    all = true;
  }
  selection_changed_ = false;
  os::Node& n = node(sel);
  const std::string& robot = target_.robots[sel];
  const auto tasks = n.tasks();
  const auto hooks = n.hooks();
  server_->broadcast(graph_json(robot, tasks, hooks, n.now()));
  const auto entries = n.log().since(log_seq_, kMaxLogLines);
  if (!entries.empty()) {
    log_seq_ = entries.back().seq;
    server_->broadcast(log_json(robot, entries));
  }
  std::vector<ProbeSeriesView> probes, fitness;
  std::vector<std::pair<std::string, std::vector<float>>> spikes;
  std::uint64_t spikes_dropped = 0;
  {
    std::lock_guard lock(probes_mu_);
    all = all || send_all_;
    send_all_ = false;
    probes = probes_.take(all);
    fitness = fitness_.take(all);
    spikes.swap(spikes_);
    for (auto& [task, dots] : spikes) spikes_.emplace_back(task, std::vector<float>{});
    spikes_pending_ = 0;
    spikes_dropped = spikes_dropped_;
  }
  if (!probes.empty() || all) server_->broadcast(probes_json(robot, probes, all));
  for (const auto& [task, dots] : spikes)
    if (!dots.empty()) server_->broadcast(spikes_json(robot, task, dots, spikes_dropped));
  if (!fitness.empty()) server_->broadcast(fitness_json(options_.fitness_robot, options_.fitness_task, fitness, all));
  StatusInfo st;
  st.virtual_time = control_ != nullptr;
  st.paused = control_ && control_->paused();
  st.speed = control_ ? control_->speed() : 1.0;
  st.seconds = target_.seconds ? target_.seconds() : view_seconds(n.now());
  st.frames_dropped = server_->stats().frames.dropped;
  st.finished = finished;
  server_->broadcast(status_json(st));
}

void LiveView::finish() {
  if (server_->client_count() == 0) return;
  send_details(true);
  // The last frames are worth a moment: the page then says the run is over.
  (void)server_->flush(kFlushStall, kFlushLimit);
}

}  // namespace symb::apps::view
