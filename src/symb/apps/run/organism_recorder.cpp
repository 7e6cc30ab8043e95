#include "symb/apps/run/organism_recorder.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numeric>
#include <set>
#include <sstream>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/text_file.hpp"

namespace symb::apps::run {

namespace fs = std::filesystem;
using sim::mujoco::DockChange;
using sim::mujoco::DockEvent;
using sim::mujoco::kNoIndex;
using sim::mujoco::MujocoWorld;
using sim::mujoco::Vec3;

struct OrganismRecorder::State {
  std::shared_ptr<sim::mujoco::WorldAccess> access;
  OrganismRecorderOptions options;
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> connectors;  // per module, the kind's connector names
  std::vector<Vec3> box_size;
  std::vector<Vec3> hinge_axis;
  std::string mjcf;

  mutable std::mutex mu;  // everything below
  std::vector<OrganismSample> kept;
  std::uint64_t stride = 1;  // ticks between kept samples
  std::uint64_t ticks = 0;
  OrganismSample first, last;  // the poses at the start and at the last tick
  std::vector<Vec3> previous;  // each module's position at the previous tick
  std::vector<double> module_distance;
  double centre_distance = 0;
  std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a offset basis
  std::size_t cursor = 0;                      // docking-log entries taken
  std::vector<DockEvent> events;
  std::set<DockedPair> pairs;
  std::vector<TopologyRow> topology;

  std::string connector_text(std::size_t m, std::size_t c) const {
    if (m >= names.size()) return {};
    return names[m] + "." + (c < connectors[m].size() ? connectors[m][c] : std::to_string(c));
  }

  std::vector<std::size_t> components() const {
    std::vector<std::size_t> parent(names.size());
    std::iota(parent.begin(), parent.end(), std::size_t{0});
    const auto root = [&](std::size_t m) {
      while (parent[m] != m) m = parent[m] = parent[parent[m]];
      return m;
    };
    for (const DockedPair& p : pairs) {
      const std::size_t a = root(p.a), b = root(p.b);
      parent[std::max(a, b)] = std::min(a, b);  // the smaller index is the root: a group's first module
    }
    std::vector<std::size_t> out(names.size());
    for (std::size_t m = 0; m < names.size(); ++m) out[m] = root(m);
    return out;
  }

  void push_topology(double time, std::uint64_t step, std::string event) {
    topology.push_back(
        {time, step, std::move(event), std::vector<DockedPair>(pairs.begin(), pairs.end()), components()});
  }

  static DockedPair pair_of(const DockEvent& e) {
    if (std::tie(e.module, e.connector) < std::tie(e.other_module, e.other_connector))
      return {e.module, e.connector, e.other_module, e.other_connector};
    return {e.other_module, e.other_connector, e.module, e.connector};
  }

  // Under the world's lock (with_world); takes mu.
  void catch_up(const MujocoWorld& world) {
    const auto& log = world.docking_log();
    std::lock_guard lock(mu);
    for (; cursor < log.size(); ++cursor) {
      const DockEvent& e = log[cursor];
      events.push_back(e);
      if (e.change == DockChange::kRefused || e.other_module == kNoIndex) continue;
      if (e.change == DockChange::kLatched)
        pairs.insert(pair_of(e));
      else
        pairs.erase(pair_of(e));
      push_topology(e.time, e.step,
                    std::string(sim::mujoco::change_name(e.change)) + " " + connector_text(e.module, e.connector) +
                        " " + connector_text(e.other_module, e.other_connector));
    }
  }

  void mix(double value) {
    const auto word = std::bit_cast<std::uint64_t>(value);
    for (int b = 0; b < 8; ++b) {
      hash ^= (word >> (8 * b)) & 0xff;
      hash *= 0x100000001b3ULL;
    }
  }

  static Vec3 centre(const std::vector<Vec3>& positions) {
    Vec3 c{};
    for (const Vec3& p : positions)
      for (int k = 0; k < 3; ++k) c[k] += p[k];
    for (double& v : c) v /= static_cast<double>(std::max<std::size_t>(1, positions.size()));
    return c;
  }

  void on_record(const sim::mujoco::MujocoStepRecord& r) {
    std::lock_guard lock(mu);
    OrganismSample sample{r.step, std::chrono::duration<double>(r.time).count(), r.modules};
    std::vector<Vec3> now(r.modules.size());
    for (std::size_t m = 0; m < r.modules.size(); ++m) now[m] = r.modules[m].pose.position;
    if (previous.size() == now.size()) {
      const Vec3 a = centre(previous), b = centre(now);
      centre_distance += std::hypot(b[0] - a[0], b[1] - a[1]);
      for (std::size_t m = 0; m < now.size(); ++m)
        module_distance[m] += std::hypot(now[m][0] - previous[m][0], now[m][1] - previous[m][1]);
    }
    previous = std::move(now);
    for (const sim::mujoco::ModuleStep& m : r.modules) {
      for (double v : m.pose.position) mix(v);
      for (double v : m.pose.quaternion) mix(v);
      for (double v : {m.hinge_angle, m.hinge_speed, m.hinge_target, m.wheels[0], m.wheels[1]}) mix(v);
    }
    if (ticks++ % stride == 0) {
      kept.push_back(sample);
      if (kept.size() >= options.max_samples) {
        std::size_t w = 0;
        for (std::size_t i = 0; i < kept.size(); i += 2, ++w)
          if (w != i) kept[w] = std::move(kept[i]);
        kept.resize(w);
        stride *= 2;
      }
    }
    last = std::move(sample);
  }

  // The kept samples, and the last tick when it was not kept.
  std::vector<OrganismSample> rows() const {
    std::vector<OrganismSample> out = kept;
    if (ticks > 0 && (out.empty() || out.back().step != last.step)) out.push_back(last);
    return out;
  }

  OrganismSummary summary() const {
    OrganismSummary s;
    s.seconds = ticks > 0 ? last.time : first.time;
    s.ticks = ticks;
    s.centre_distance = centre_distance;
    s.hash = hash;
    s.module_distance = module_distance;
    const OrganismSample& end = ticks > 0 ? last : first;
    std::vector<Vec3> a, b;
    for (const auto& m : first.modules) a.push_back(m.pose.position);
    for (const auto& m : end.modules) b.push_back(m.pose.position);
    const Vec3 ca = centre(a), cb = centre(b);
    s.centre_displacement = std::hypot(cb[0] - ca[0], cb[1] - ca[1]);
    for (const DockEvent& e : events) {
      if (e.change == DockChange::kLatched) ++s.latches;
      if (e.change == DockChange::kUnlatched) ++s.unlatches;
      if (e.change == DockChange::kRefused) ++s.refusals;
    }
    return s;
  }
};

namespace {

std::string fmt(const char* format, double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string csv_quoted(std::string_view text) {
  std::string s = "\"";
  for (char c : text) {
    if (c == '"') s += '"';
    s += c == '\n' ? ' ' : c;
  }
  return s + "\"";
}

}  // namespace

OrganismRecorder::OrganismRecorder(sim::mujoco::MujocoRunner& runner, OrganismRecorderOptions options)
    : s_(std::make_shared<State>()) {
  State& s = *s_;
  s.access = runner.access();
  s.options = std::move(options);
  s.options.every = std::max<std::uint32_t>(1, s.options.every);
  s.options.max_samples = std::max<std::size_t>(2, s.options.max_samples);
  s.stride = s.options.every;
  runner.with_world([&s](MujocoWorld& world) {
    const std::size_t n = world.module_count();
    s.mjcf = world.mjcf();
    s.first.step = world.steps();
    s.first.time = world.time();
    for (std::size_t m = 0; m < n; ++m) {
      const auto& spec = world.module(m);
      s.names.push_back(spec.name);
      s.box_size.push_back(spec.kind.body.size);
      s.hinge_axis.push_back(spec.kind.hinge.axis);
      std::vector<std::string> connectors;
      for (const auto& c : spec.kind.connectors) connectors.push_back(c.name);
      s.connectors.push_back(std::move(connectors));
      sim::mujoco::ModuleStep step;
      step.pose = world.pose(m);
      step.hinge_angle = world.hinge_angle(m);
      step.hinge_speed = world.hinge_speed(m);
      s.first.modules.push_back(step);
      s.previous.push_back(step.pose.position);
    }
    s.module_distance.assign(n, 0.0);
    for (std::size_t m = 0; m < n; ++m)
      for (std::size_t c = 0; c < s.connectors[m].size(); ++c)
        if (auto other = world.docked_to(m, c)) {
          DockEvent e;
          e.module = m, e.connector = c, e.other_module = other->first, e.other_connector = other->second;
          s.pairs.insert(State::pair_of(e));
        }
    s.events = world.docking_log();
    s.cursor = s.events.size();
    s.push_topology(s.first.time, s.first.step, "start");
  });
  std::shared_ptr<State> state = s_;
  runner.add_observer([state](const sim::mujoco::MujocoStepRecord& r) {
    state->access->with_world([&](MujocoWorld& world) { state->catch_up(world); });
    state->on_record(r);
  });
}

OrganismRecorder::~OrganismRecorder() = default;

std::vector<OrganismSample> OrganismRecorder::samples() const {
  std::lock_guard lock(s_->mu);
  return s_->rows();
}

std::vector<DockEvent> OrganismRecorder::docking_log() const {
  std::lock_guard lock(s_->mu);
  return s_->events;
}

std::vector<TopologyRow> OrganismRecorder::topology() const {
  std::lock_guard lock(s_->mu);
  return s_->topology;
}

OrganismSummary OrganismRecorder::summary() const {
  std::lock_guard lock(s_->mu);
  OrganismSummary s = s_->summary();
  s.final_components = components_text(s_->topology.back().component);
  return s;
}

const std::vector<std::string>& OrganismRecorder::module_names() const { return s_->names; }

std::string OrganismRecorder::components_text(const std::vector<std::size_t>& component) const {
  std::string out;
  for (std::size_t first = 0; first < component.size(); ++first) {
    if (component[first] != first) continue;
    if (!out.empty()) out += ' ';
    bool more = false;
    for (std::size_t m = first; m < component.size(); ++m)
      if (component[m] == first) {
        out += (more ? "+" : "") + s_->names[m];
        more = true;
      }
  }
  return out;
}

kernel::Result<std::vector<fs::path>> OrganismRecorder::finish(const fs::path& dir, std::string_view summary_header) {
  State& s = *s_;
  s.access->with_world([&s](MujocoWorld& world) { s.catch_up(world); });
  std::vector<OrganismSample> rows;
  std::vector<DockEvent> events;
  std::vector<TopologyRow> topology;
  OrganismSummary summary;
  OrganismSample first;
  std::uint64_t stride = 1;
  {
    std::lock_guard lock(s.mu);
    rows = s.rows();
    events = s.events;
    topology = s.topology;
    summary = s.summary();
    first = s.first;
    stride = s.stride;
  }
  summary.final_components = components_text(topology.back().component);
  const std::size_t n = s.names.size();
  const double end_time =
      std::max({rows.empty() ? first.time : rows.back().time, events.empty() ? 0.0 : events.back().time, 1e-3});
  const std::string& caption = s.options.caption;

  std::ostringstream poses, joints, docking, topo, summary_text;
  poses << "time_s,step,module,x_m,y_m,z_m,qw,qx,qy,qz,yaw_rad,wheel_l_m_s,wheel_r_m_s\n";
  joints << "time_s,step,module,angle_rad,target_rad,speed_rad_s\n";
  ProbeSeries angles;
  angles.robot = "organism";
  angles.task = "hinge";
  angles.channel = "angle (rad)";
  angles.width = n;
  angles.labels = s.names;
  angles.samples = rows.size();
  for (const OrganismSample& r : rows) {
    angles.times.push_back(r.time);
    angles.values.emplace_back();
    for (std::size_t m = 0; m < r.modules.size() && m < n; ++m) {
      const sim::mujoco::ModuleStep& x = r.modules[m];
      const std::string head = fmt("%.3f", r.time) + "," + std::to_string(r.step) + "," + s.names[m];
      poses << head;
      for (double v : x.pose.position) poses << fmt(",%.5f", v);
      for (double v : x.pose.quaternion) poses << fmt(",%.6f", v);
      poses << fmt(",%.5f", x.pose.yaw()) << fmt(",%.4f", x.wheels[0]) << fmt(",%.4f", x.wheels[1]) << "\n";
      joints << head << fmt(",%.5f", x.hinge_angle) << fmt(",%.5f", x.hinge_target) << fmt(",%.5f", x.hinge_speed)
             << "\n";
      angles.values.back().push_back(static_cast<float>(x.hinge_angle));
    }
  }
  docking << "step,time_s,change,connector,other,distance_m,angle_rad,reason\n";
  for (const DockEvent& e : events) {
    docking << e.step << fmt(",%.3f", e.time) << "," << sim::mujoco::change_name(e.change) << ","
            << s.connector_text(e.module, e.connector) << "," << s.connector_text(e.other_module, e.other_connector)
            << "," << (e.distance >= 0 ? fmt("%.5f", e.distance) : "") << ","
            << (e.angle >= 0 ? fmt("%.5f", e.angle) : "") << "," << csv_quoted(e.reason) << "\n";
  }
  topo << "time_s,step,event,docked_pairs,components,component_count\n";
  std::vector<TopologySpan> spans;
  for (const TopologyRow& t : topology) {
    std::string pairs;
    for (const DockedPair& p : t.pairs)
      pairs += (pairs.empty() ? "" : " ") + s.connector_text(p.a, p.a_connector) + "=" +
               s.connector_text(p.b, p.b_connector);
    std::size_t groups = 0;
    for (std::size_t m = 0; m < t.component.size(); ++m) groups += t.component[m] == m ? 1 : 0;
    topo << fmt("%.3f", t.time) << "," << t.step << "," << t.event << "," << pairs << ","
         << components_text(t.component) << "," << groups << "\n";
    spans.push_back({t.time, t.component});
  }

  // The paths: the start, then every kept sample (the last tick included).
  std::vector<ModulePath> paths(n);
  for (std::size_t m = 0; m < n; ++m) {
    paths[m].name = s.names[m];
    paths[m].box_size = s.box_size[m];
    paths[m].hinge_axis = s.hinge_axis[m];
    if (m < first.modules.size()) paths[m].points.push_back(first.modules[m].pose.position);
    if (m < first.modules.size()) {
      paths[m].end = first.modules[m].pose;
      paths[m].end_hinge_angle = first.modules[m].hinge_angle;
    }
  }
  for (const OrganismSample& r : rows)
    for (std::size_t m = 0; m < r.modules.size() && m < n; ++m) {
      paths[m].points.push_back(r.modules[m].pose.position);
      paths[m].end = r.modules[m].pose;
      paths[m].end_hinge_angle = r.modules[m].hinge_angle;
    }
  const std::vector<DockedPair>& docked = topology.back().pairs;
  std::ostringstream top, side, joints_svg, topo_svg, docking_svg;
  write_path_view_svg(top, PathView::kTop, paths, docked, caption);
  write_path_view_svg(side, PathView::kSide, paths, docked, caption);
  write_probe_svg(joints_svg, angles);
  write_topology_svg(topo_svg, s.names, spans, end_time, caption);
  write_docking_svg(docking_svg, s.names, events, end_time, caption);

  summary_text << summary_header;
  if (!summary_header.empty() && summary_header.back() != '\n') summary_text << "\n";
  summary_text << "modules: " << n << "\n"
               << "control ticks: " << summary.ticks << " (" << rows.size() << " kept: one in " << stride
               << " by the end, and the last)\n"
               << "organism centre: moved " << fixed(summary.centre_distance, 3) << " m (path in x-y), "
               << fixed(summary.centre_displacement, 3) << " m from start to end\n"
               << "docking: " << summary.latches << " latched, " << summary.unlatches << " unlatched, "
               << summary.refusals << " refused\n"
               << "final topology: " << summary.final_components << "\n\n"
               << "module,distance_m,end_x_m,end_y_m,end_z_m,end_yaw_rad,hinge_rad\n";
  for (std::size_t m = 0; m < n; ++m) {
    const sim::mujoco::ModuleStep& e = rows.empty() ? first.modules[m] : rows.back().modules[m];
    summary_text << s.names[m] << "," << fixed(summary.module_distance[m], 3) << "," << fixed(e.pose.position[0], 3)
                 << "," << fixed(e.pose.position[1], 3) << "," << fixed(e.pose.position[2], 3) << ","
                 << fixed(e.pose.yaw(), 3) << "," << fixed(e.hinge_angle, 3) << "\n";
  }

  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return kernel::Error{"cannot create " + dir.string() + ": " + ec.message()};
  const std::pair<const char*, std::string> files[] = {
      {"paths_top.svg", top.str()},       {"paths_side.svg", side.str()},
      {"poses.csv", poses.str()},         {"joints.csv", joints.str()},
      {"joints.svg", joints_svg.str()},   {"docking.csv", docking.str()},
      {"docking.svg", docking_svg.str()}, {"topology.csv", topo.str()},
      {"topology.svg", topo_svg.str()},   {"world.xml", s.mjcf},
      {"summary.txt", summary_text.str()}};
  std::vector<fs::path> written;
  for (const auto& [name, text] : files) {
    if (auto st = write_file(dir / name, text); !st) return kernel::Error{st.error()};
    written.push_back(dir / name);
  }
  return written;
}

}  // namespace symb::apps::run
