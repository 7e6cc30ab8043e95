#include "symb/apps/view/view_json.hpp"

#include <charconv>
#include <cmath>

#include "symb/shell/json_writer.hpp"

namespace symb::apps::view {

namespace {

using shell::JsonWriter;

double json_seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

// Fixed-point with `decimals` digits, shortest form ("12.5", "3", "-0.1"); non-finite as 0 (a
// pose is never NaN; the page must still parse the list).
void append_number(std::string& out, double v, int decimals) {
  if (!std::isfinite(v)) v = 0;
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  std::string_view s(buf, static_cast<std::size_t>(r.ptr - buf));
  if (s.find('.') != std::string_view::npos) {
    while (s.back() == '0') s.remove_suffix(1);
    if (s.back() == '.') s.remove_suffix(1);
  }
  if (s == "-0") s = "0";
  out += s;
}

}  // namespace

std::string hello_json(const HelloInfo& h) {
  JsonWriter j;
  j.begin_object().field("type", "hello").field("scenario", h.scenario);
  j.key("world");
  if (h.world) {
    j.begin_object().field("width", h.world->width).field("height", h.world->height).key("walls").begin_array();
    for (const sim::WallSpec& w : h.world->walls)
      j.begin_array().value(w.x1).value(w.y1).value(w.x2).value(w.y2).value(w.thickness).end_array();
    j.end_array().key("zones").begin_array();
    for (const sim::ZoneSpec& z : h.world->zones) {
      j.begin_object().field("ground", z.ground).field("name", z.name);
      if (z.shape == sim::ZoneSpec::Shape::kRect)
        j.field("x1", z.x1).field("y1", z.y1).field("x2", z.x2).field("y2", z.y2);
      else
        j.field("cx", z.cx).field("cy", z.cy).field("r", z.radius);
      j.end_object();
    }
    j.end_array().end_object();
  } else if (h.organism) {
    j.begin_object().field("kind", "organism").key("modules").begin_array();
    for (const ModuleShape& m : *h.organism) {
      j.begin_object().field("name", m.name).key("size").begin_array();
      for (double v : m.size) j.value(v);
      j.end_array().key("hinge").begin_array();
      for (double v : m.hinge_axis) j.value(v);
      j.end_array().field("wheels", m.wheels).key("connectors").begin_array();
      for (const auto& [name, p] : m.connectors)
        j.begin_array().value(name).value(p[0]).value(p[1]).value(p[2]).end_array();
      j.end_array().end_object();
    }
    j.end_array().end_object();
  } else {
    j.null();
  }
  j.key("robots").begin_array();
  for (const auto& r : h.robots) j.value(r);
  j.end_array()
      .field("selected", static_cast<std::uint64_t>(h.selected))
      .field("virtual", h.virtual_time)
      .field("paused", h.paused)
      .field("speed", h.speed)
      .field("duration", h.duration_seconds)
      .end_object();
  return j.str();
}

std::string step_json(std::uint64_t step, double seconds, std::span<const sim::RobotState> robots,
                      std::size_t max_robots) {
  const std::size_t n = robots.size();
  const std::size_t stride = max_robots == 0 || n <= max_robots ? 1 : (n + max_robots - 1) / max_robots;
  std::string out;
  out.reserve(64 + (n / stride) * 18);
  out += R"({"type":"step","step":)";
  out += std::to_string(step);
  out += ",\"t\":";
  append_number(out, seconds, 3);
  out += ",\"n\":";
  out += std::to_string(n);
  out += ",\"stride\":";
  out += std::to_string(stride);
  out += ",\"xy\":[";
  for (std::size_t i = 0; i < n; i += stride) {
    if (i) out += ',';
    const sim::Pose& p = robots[i].pose;
    append_number(out, p.x, 1);
    out += ',';
    append_number(out, p.y, 1);
    out += ',';
    append_number(out, p.theta * 180.0 / std::numbers::pi, 0);
  }
  out += "]}\n";
  return out;
}

std::string graph_json(std::string_view robot, std::span<const os::TaskInfo> tasks, std::span<const os::HookInfo> hooks,
                       kernel::Time now) {
  JsonWriter j;
  j.begin_object()
      .field("type", "graph")
      .field("robot", robot)
      .field("t", json_seconds(now))
      .key("tasks")
      .begin_array();
  for (const os::TaskInfo& i : tasks) {
    j.begin_object()
        .field("name", i.name)
        .field("type", i.type)
        .field("state", os::to_string(i.state))
        .field("priority", i.priority)
        .field("period", json_seconds(i.period))
        .field("queue", static_cast<std::uint64_t>(i.queue_depth))
        .field("capacity", static_cast<std::uint64_t>(i.queue_capacity))
        .field("in", i.traffic.delivered)
        .field("out", i.sent)
        .field("dropped", i.traffic.dropped())
        .end_object();
  }
  j.end_array().key("hooks").begin_array();
  for (const os::HookInfo& h : hooks) {
    const os::HookTraffic& a = h.accounting;
    j.begin_object()
        .field("hook", static_cast<std::uint64_t>(h.id.serial))
        .field("sender", h.sender_name)
        .field("receiver", h.receiver_name)
        .field("priority", h.options.priority)
        .field("policy", os::to_string(h.options.policy))
        .field("suppress", json_seconds(h.options.suppress_window))
        .field("enabled", h.options.enabled)
        .field("inhibited", h.inhibited_until > now)
        .field("sent", a.sent)
        .field("delivered", a.traffic.delivered)
        .field("dropped", a.traffic.dropped())
        .field("suppressed", a.traffic.suppressed)
        .field("queued", a.queued)
        .end_object();
  }
  j.end_array().end_object();
  return j.str();
}

std::string log_json(std::string_view robot, std::span<const os::LogEntry> entries) {
  JsonWriter j;
  j.begin_object().field("type", "log").field("robot", robot).key("lines").begin_array();
  for (const os::LogEntry& e : entries) j.value(os::format_log_entry(e));
  j.end_array().end_object();
  return j.str();
}

std::string organism_json(std::uint64_t step, double seconds, std::span<const ModulePose> modules,
                          std::span<const DockedPair> docked) {
  std::string out;
  out.reserve(96 + modules.size() * 64 + docked.size() * 16);
  out += R"({"type":"organism","step":)";
  out += std::to_string(step);
  out += ",\"t\":";
  append_number(out, seconds, 3);
  out += ",\"m\":[";
  bool first = true;
  const auto put = [&](double v, int decimals) {
    if (!first) out += ',';
    first = false;
    append_number(out, v, decimals);
  };
  for (const ModulePose& m : modules) {
    for (double v : m.position) put(v, 4);  // 0.1 mm
    for (double v : m.quaternion) put(v, 4);
    put(m.hinge, 3);
  }
  out += "],\"docked\":[";
  for (std::size_t i = 0; i < docked.size(); ++i) {
    if (i) out += ',';
    out += '[';
    for (std::size_t k = 0; k < 4; ++k) {
      if (k) out += ',';
      out += std::to_string(docked[i][k]);
    }
    out += ']';
  }
  out += "]}\n";
  return out;
}

namespace {

// A probe's value with a float's precision ("0.3", not 0.30000001192092896): the shortest text of
// the float, read back as a double, has a short text of its own.
double short_value(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, static_cast<float>(v));
  double d = v;
  (void)std::from_chars(buf, r.ptr, d);
  return d;
}

// Flat (time, width values) per point: times to the millisecond, values to a float's precision.
void series_points(JsonWriter& j, const ProbeSeriesView& p) {
  j.key("points").begin_array();
  const std::size_t row = p.width + 1;
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    const double v = p.points[i];
    j.value(i % row == 0 ? std::round(v * 1000) / 1000 : std::isfinite(v) ? short_value(v) : v);
  }
  j.end_array();
}

}  // namespace

std::string probes_json(std::string_view robot, std::span<const ProbeSeriesView> probes, bool full) {
  JsonWriter j;
  j.begin_object().field("type", "probes").field("robot", robot).field("full", full).key("probes").begin_array();
  for (const ProbeSeriesView& p : probes) {
    j.begin_object()
        .field("t", p.latest_time)
        .field("task", p.task)
        .field("channel", p.channel)
        .key("values")
        .begin_array();
    for (float v : p.latest) j.value(short_value(v));
    j.end_array().field("width", static_cast<std::uint64_t>(p.width)).field("stride", p.stride);
    series_points(j, p);
    j.end_object();
  }
  j.end_array().end_object();
  return j.str();
}

std::string spikes_json(std::string_view robot, std::string_view task, std::span<const float> dots,
                        std::uint64_t dropped) {
  JsonWriter j;
  j.begin_object()
      .field("type", "spikes")
      .field("robot", robot)
      .field("task", task)
      .field("dropped", dropped)
      .key("dots")
      .begin_array();
  for (float v : dots) j.value(short_value(v));
  j.end_array().end_object();
  return j.str();
}

std::string fitness_json(std::string_view robot, std::string_view task, std::span<const ProbeSeriesView> series,
                         bool full) {
  JsonWriter j;
  j.begin_object()
      .field("type", "fitness")
      .field("robot", robot)
      .field("task", task)
      .field("full", full)
      .key("series")
      .begin_array();
  for (const ProbeSeriesView& p : series) {
    j.begin_object().field("channel", p.channel).field("width", static_cast<std::uint64_t>(p.width));
    series_points(j, p);
    j.end_object();
  }
  j.end_array().end_object();
  return j.str();
}

std::string status_json(const StatusInfo& s) {
  JsonWriter j;
  j.begin_object()
      .field("type", "status")
      .field("virtual", s.virtual_time)
      .field("paused", s.paused)
      .field("speed", s.speed)
      .field("t", s.seconds)
      .field("dropped", s.frames_dropped)
      .field("finished", s.finished)
      .end_object();
  return j.str();
}

std::string shell_json(std::string_view text) {
  JsonWriter j;
  j.begin_object().field("type", "shell").field("text", text).end_object();
  return j.str();
}

}  // namespace symb::apps::view
