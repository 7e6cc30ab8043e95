#include "symb/sim/hil_split_world.hpp"

#include <algorithm>
#include <array>
#include <optional>
#include <thread>
#include <utility>

#include "symb/io/bytes.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/hil_split_protocol.hpp"
#include "symb/sim/local_radio.hpp"

namespace symb::sim {

namespace {

using Wall = std::chrono::steady_clock;

std::string count_text(std::uint64_t v) { return std::to_string(v); }

std::string ms_text(kernel::Duration d) {
  return count_text(static_cast<std::uint64_t>(kernel::to_milliseconds(d))) + " ms";
}

}  // namespace

struct HilSplitWorld::Robot {
  explicit Robot(std::size_t max_payload) : decoder(max_payload) {}
  std::shared_ptr<io::IOStream> port;
  io::FrameDecoder decoder;
  HilSplitRobotStats stats;
  // What the world's radio delivered to it at the step under way (its relay): sender, bytes.
  std::vector<std::pair<std::uint32_t, std::shared_ptr<const os::Blob>>> heard;
  std::optional<std::uint32_t> radio_seq;  // the answer whose radio message went on air last
};

std::string describe(const HilSplitRobotStats& s) {
  std::string text = "robot " + s.robot + ": sent " + count_text(s.frames_sent) + " (" + count_text(s.write_errors) +
                     " not taken), received " + count_text(s.received) + " good, " + count_text(s.bad_frames()) +
                     " bad; applied " + count_text(s.applied) + ", " + count_text(s.stale) + " stale; waited " +
                     count_text(static_cast<std::uint64_t>(s.waited_s * 1000)) + " ms";
  if (s.radio)
    text += "; radio: " + count_text(s.radio_sent) + " messages to it, " + count_text(s.radio_received) + " from it";
  if (s.gone) text += "; GONE at step " + count_text(s.gone_at) + ": " + s.why;
  return text;
}

kernel::Status HilSplitWorld::check(const Scenario& sc, std::size_t robot) {
  if (sc.world_kind != WorldKind::kEnki)
    return kernel::Error{sc.file +
                         ": a 3D world's modules do not run as remote robots (one module can run in another "
                         "process: symb sim --board NAME --dds, docs/hil.md)"};
  if (robot >= sc.robots.size()) return kernel::Error{sc.file + ": no robot " + count_text(robot)};
  const RobotSpec& spec = sc.robots[robot];
  for (const EventSpec& e : sc.events)
    if (e.robot == robot)
      return kernel::Error{e.where.str() + ": robot " + spec.name +
                           " runs in another process: its events belong to that process's shell"};
  return {};
}

HilSplitWorld::HilSplitWorld(ScenarioSession& session, HilSplitWorldOptions options)
    : session_(session), options_(std::move(options)), buf_(4096) {}

HilSplitWorld::~HilSplitWorld() {
  if (LocalRadio* radio = session_.radio())
    for (const auto& r : robots_) radio->relay(r->stats.index, {});
}

kernel::Result<std::unique_ptr<HilSplitWorld>> HilSplitWorld::create(ScenarioSession& session,
                                                                     std::vector<Remote> remotes,
                                                                     HilSplitWorldOptions options) {
  if (options.answer_wait <= kernel::Duration{0}) return kernel::Error{"the answer wait must be positive"};
  std::unique_ptr<HilSplitWorld> w(new HilSplitWorld(session, std::move(options)));
  std::vector<bool> taken(session.robot_count(), false);
  for (Remote& r : remotes) {
    if (r.robot >= session.robot_count()) return kernel::Error{"no robot " + count_text(r.robot) + " in the session"};
    if (auto st = check(session.scenario(), r.robot); !st) return kernel::Error{st.error()};
    if (taken[r.robot]) return kernel::Error{"robot " + session.robot(r.robot).name() + " is remote twice"};
    if (!r.port) return kernel::Error{"robot " + session.robot(r.robot).name() + ": no stream"};
    taken[r.robot] = true;
    // A radio frame holds a whole message: the decoder takes the longest the radio sends.
    const auto& radio = session.scenario().world.radio;
    auto robot = std::make_unique<Robot>(radio ? std::max<std::size_t>(256, kHilRadioHeader + radio->max_message_bytes)
                                               : std::size_t{256});
    robot->stats.radio = radio.has_value();
    robot->port = std::move(r.port);
    robot->stats.robot = session.robot(r.robot).name();
    robot->stats.index = r.robot;
    if (!robot->port->is_open())
      if (auto st = robot->port->open(); !st)
        return kernel::Error{"robot " + robot->stats.robot + ": cannot open its stream: " + st.error()};
    w->robots_.push_back(std::move(robot));
  }
  // In robot order, so the steps read the answers in one order whatever the command line's.
  std::sort(w->robots_.begin(), w->robots_.end(),
            [](const auto& a, const auto& b) { return a->stats.index < b->stats.index; });
  for (const auto& r : w->robots_) {
    // Its node runs in the other process; here its devices answer to the stream.
    session.robot(r->stats.index).node().clear();
    (void)session.runner().wheels(r->stats.index)->open();
    if (LocalRadio* radio = session.radio())
      radio->relay(r->stats.index, [raw = r.get()](std::size_t sender, const std::shared_ptr<const os::Blob>& blob) {
        if (raw->stats.gone) return false;
        raw->heard.emplace_back(static_cast<std::uint32_t>(sender), blob);
        return true;
      });
  }
  session.runner().add_observer([raw = w.get()](const StepRecord& record) { raw->on_step(record); });
  return w;
}

void HilSplitWorld::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

void HilSplitWorld::send(Robot& r, const std::vector<std::byte>& payload, std::uint32_t step) {
  frame_.clear();
  std::uint64_t radio = 0;
  for (const auto& [sender, blob] : r.heard) {
    const auto* bytes = os::blob_as<io::Bytes>(blob.get());
    if (bytes == nullptr) continue;  // the radio puts none such on air
    encode_radio_payload(step, sender, bytes->data, radio_payload_);
    io::encode_frame(radio_payload_, frame_);
    ++radio;
  }
  r.heard.clear();
  io::encode_frame(payload, frame_);
  const bool ok = r.port->write_all(frame_).ok();
  std::lock_guard lock(stats_mu_);
  ++(ok ? r.stats.frames_sent : r.stats.write_errors);
  if (ok) r.stats.radio_sent += radio;
}

void HilSplitWorld::lose(Robot& r, std::uint64_t step, const std::string& why) {
  (void)session_.runner().wheels(r.stats.index)->set(std::array<float, 2>{0.0f, 0.0f});
  r.heard.clear();
  {
    std::lock_guard lock(stats_mu_);
    if (r.stats.gone) return;
    r.stats.gone = true;
    r.stats.gone_at = step;
    r.stats.why = why;
  }
  event("robot " + r.stats.robot + ": gone at step " + count_text(step) + ": " + why +
        "; its wheels are stopped, the run goes on");
}

bool HilSplitWorld::read(Robot& r, kernel::Duration wait, std::uint32_t step) {
  auto got = r.port->read_some(buf_, wait);
  if (!got && step == 0) {
    // Before the hello's answer a stream that ends is not the robot's process (a foreign writer
    // that came and went): wait on for the robot.
    std::this_thread::sleep_for(std::min<kernel::Duration>(wait, std::chrono::milliseconds(1)));
    return false;
  }
  if (!got) {
    lose(r, step, "its stream ended (" + got.error() + ")");
    return false;
  }
  bool answered = false;
  std::uint64_t received = 0, malformed = 0, stale = 0, on_air = 0;
  bool hello = false;
  std::array<float, 2> wheels{};
  LocalRadio* radio = session_.radio();
  r.decoder.feed(std::span<const std::byte>(buf_.data(), *got), [&](std::span<const std::byte> payload) {
    if (is_radio_payload(payload)) {
      auto m = decode_radio_payload(payload);
      if (!m || radio == nullptr || m->robot != r.stats.index) {
        ++malformed;
        return;
      }
      // What its radio task sent before its answer to this step (the hello's: seq 0), once: on air
      // at the world's next step, as an in-process radio task's message.
      if (m->seq != step || answered || r.radio_seq == step) {
        ++stale;
        return;
      }
      r.radio_seq = step;
      radio->transmit(r.stats.index, std::make_shared<const io::Bytes>(m->bytes));
      ++on_air;
      return;
    }
    auto f = decode_wheel_payload(payload);
    if (!f) {
      ++malformed;
      return;
    }
    ++received;
    if (f->seq == 0 && step == 0) {
      hello = true;
      wheels = {f->left, f->right};
    } else if (f->seq != step || step == 0 || answered) {
      ++stale;
    } else {
      answered = true;
      wheels = {f->left, f->right};
    }
  });
  // The world's step k + 1 applies this, as it applies what an in-process node set in step k's window.
  // The hello's answer is what the node set before the world's first step, which step 1 applies.
  if (answered || hello) (void)session_.runner().wheels(r.stats.index)->set(wheels);
  std::lock_guard lock(stats_mu_);
  r.stats.received += received;
  r.stats.malformed += malformed;
  r.stats.stale += stale;
  r.stats.radio_received += on_air;
  r.stats.applied += answered ? 1 : 0;
  r.stats.decoder = r.decoder.stats();
  if (hello) r.stats.answered = true;
  return answered || hello;
}

kernel::Status HilSplitWorld::wait_for_robots(kernel::Duration timeout, const std::function<bool()>& stopped) {
  const auto deadline = Wall::now() + timeout;
  const kernel::Duration period = session_.scenario().control_period;
  for (;;) {
    const auto until = Wall::now() + period;
    for (auto& r : robots_)
      if (!r->stats.answered && !r->stats.gone)
        send(*r, encode_hello_payload({session_.seed(), static_cast<std::uint32_t>(r->stats.index),
                                       static_cast<std::uint32_t>(session_.robot_count()),
                                       robot_digest(session_.scenario(), r->stats.index)}));
    for (;;) {
      bool pending = false;
      for (auto& r : robots_) {
        if (r->stats.answered || r->stats.gone) continue;
        const auto left = until - Wall::now();
        if (left <= Wall::duration{0}) {
          pending = true;
          continue;
        }
        if (read(*r,
                 std::min<kernel::Duration>(std::chrono::duration_cast<kernel::Duration>(left),
                                            std::chrono::milliseconds(2)),
                 0) &&
            r->stats.answered)
          event("robot " + r->stats.robot + ": its process answered");
        pending = pending || (!r->stats.answered && !r->stats.gone);
      }
      if (!pending || Wall::now() >= until) break;
    }
    std::string missing, dead;
    for (const auto& r : robots_) {
      if (r->stats.gone) dead += (dead.empty() ? "" : "; ") + r->stats.robot + ": " + r->stats.why;
      if (!r->stats.answered && !r->stats.gone) missing += (missing.empty() ? "" : ", ") + r->stats.robot;
    }
    if (!dead.empty()) return kernel::Error{"remote robot " + dead};
    if (missing.empty()) return {};
    if (stopped && stopped()) return kernel::Error{"stopped while waiting for remote robot " + missing};
    if (Wall::now() >= deadline)
      return kernel::Error{"no answer from the process of remote robot " + missing + " within " + ms_text(timeout) +
                           " (is `symb serve --scenario ... --robot NAME` running for it, on the same DDS domain and "
                           "prefix?)"};
  }
}

void HilSplitWorld::on_step(const StepRecord& record) {
  const std::uint64_t k = record.step;
  for (auto& r : robots_) {
    if (r->stats.gone) continue;
    if (k > kHilMaxSequence) {
      lose(*r, k, "the sequence numbers are used up (" + count_text(kHilMaxSequence) + " steps)");
      continue;
    }
    const RobotStep& s = record.robots[r->stats.index];
    HilSplitSensors f;
    f.seq = static_cast<std::uint32_t>(k);
    f.ir = s.ir;
    // As SimPoseSensor::publish_pose makes them.
    f.pose[0] = static_cast<float>(s.state.pose.x);
    f.pose[1] = static_cast<float>(s.state.pose.y);
    f.pose[2] = static_cast<float>(s.state.pose.theta);
    f.ground = s.ground;
    send(*r, encode_split_sensors_payload(f), f.seq);
  }
  const auto start = Wall::now();
  const auto deadline = start + options_.answer_wait;
  for (auto& r : robots_) {
    if (r->stats.gone) continue;
    const auto began = Wall::now();
    for (;;) {
      const auto left = deadline - Wall::now();
      if (left <= Wall::duration{0}) {
        lose(*r, k, "no answer to step " + count_text(k) + " within " + ms_text(options_.answer_wait));
        break;
      }
      if (read(*r,
               std::min<kernel::Duration>(std::chrono::duration_cast<kernel::Duration>(left),
                                          std::chrono::milliseconds(5)),
               static_cast<std::uint32_t>(k)))
        break;
      if (r->stats.gone) break;
    }
    std::lock_guard lock(stats_mu_);
    r->stats.waited_s += std::chrono::duration<double>(Wall::now() - began).count();
  }
}

void HilSplitWorld::say_bye(std::uint64_t steps) {
  for (auto& r : robots_)
    if (!r->stats.gone)
      send(*r, encode_bye_payload(static_cast<std::uint32_t>(std::min<std::uint64_t>(steps, kHilMaxSequence))));
}

std::vector<HilSplitRobotStats> HilSplitWorld::stats() const {
  std::lock_guard lock(stats_mu_);
  std::vector<HilSplitRobotStats> out;
  for (const auto& r : robots_) out.push_back(r->stats);
  return out;
}

std::size_t HilSplitWorld::gone() const {
  std::lock_guard lock(stats_mu_);
  return static_cast<std::size_t>(
      std::count_if(robots_.begin(), robots_.end(), [](const auto& r) { return r->stats.gone; }));
}

}  // namespace symb::sim
