#include "symb/sim/hil_split_robot.hpp"

#include <algorithm>
#include <atomic>

#include "symb/io/bytes.hpp"
#include "symb/io/plugin_library.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/hil_split_protocol.hpp"
#include "symb/sim/hil_split_world.hpp"
#include "symb/sim/periodic_runner.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

namespace {

// The wheels whose hardware is the stream: set() keeps the conditioned output (Actuator::output()),
// which the answer carries; the world sets its SimWheels to it, conditioning it alike.
class SplitLinkWheels final : public robot::Actuator {
 public:
  SplitLinkWheels() : robot::Actuator("wheels", SimWheels::channel_specs()) {}

 protected:
  kernel::Status apply(std::span<const float>) override { return {}; }
};

}  // namespace

struct HilSplitRobot::Shared {
  std::shared_ptr<SimIrSensor> ir = std::make_shared<SimIrSensor>("ir");
  std::shared_ptr<robot::Actuator> wheels = std::make_shared<SplitLinkWheels>();
  std::shared_ptr<SimPoseSensor> pose;
  std::shared_ptr<SimGroundSensor> ground = std::make_shared<SimGroundSensor>("ground");
  std::optional<HilSplitSensors> pending;  // the newest sensor frame, for its tick
  // World.radio: the robot's medium and index; what the world's radio delivered, by radio frames
  // not yet followed by their sensor frame (incoming), and those of the pending frame (heard).
  struct Heard {
    std::uint32_t seq = 0;
    std::uint32_t sender = 0;
    std::shared_ptr<const os::Blob> bytes;
  };
  LocalRadio* radio = nullptr;
  std::size_t robot = 0;
  std::vector<Heard> incoming;
  std::vector<Heard> heard;
  std::atomic<std::uint64_t> radio_in{0}, radio_dropped{0};
};

// Where the world runner stands in process: its period and priority; tick k publishes sensor
// frame k's readings as the runner publishes step k's.
class HilSplitRobot::Clock final : public PeriodicRunner {
 public:
  Clock(kernel::Executor& executor, std::shared_ptr<Shared> shared, PeriodicRunner::Options options)
      : PeriodicRunner(executor, std::move(options)), shared_(std::move(shared)) {}
  ~Clock() override { halt(); }

 private:
  kernel::Status step_once(kernel::Time now) override {
    ++tick_;
    if (!shared_->pending || shared_->pending->seq != tick_) return {};
    const HilSplitSensors f = *shared_->pending;
    shared_->pending.reset();
    // The world's radio posts in phase A of the step's sync instant, before the robot's lane
    // publishes the readings at the start of its window.
    for (const Shared::Heard& h : shared_->heard)
      ++(shared_->radio->deliver(shared_->robot, h.sender, h.bytes) ? shared_->radio_in : shared_->radio_dropped);
    shared_->heard.clear();
    shared_->ir->publish_readings(f.ir, now);
    if (shared_->pose->has_listener()) shared_->pose->publish_pose(Pose{f.pose[0], f.pose[1], f.pose[2]}, now);
    if (shared_->ground->has_listener()) shared_->ground->publish_readings(f.ground, now);
    return {};
  }

  std::shared_ptr<Shared> shared_;
  std::uint64_t tick_ = 0;
};

std::string describe(const HilSplitRobotBoardStats& s) {
  return "frames " + std::to_string(s.frames) + " (" + std::to_string(s.missed) + " missed, " +
         std::to_string(s.out_of_order) + " out of order), hellos " + std::to_string(s.hellos) + ", bad " +
         std::to_string(s.bad_frames()) + " (crc " + std::to_string(s.decoder.crc_errors) + ", framing " +
         std::to_string(s.decoder.dropped() - s.decoder.crc_errors) + ", malformed " + std::to_string(s.malformed) +
         "); answers " + std::to_string(s.answers) + " (" + std::to_string(s.write_errors) + " not taken); radio " +
         std::to_string(s.radio_in) + " in (" + std::to_string(s.radio_dropped) + " dropped, " +
         std::to_string(s.radio_stale) + " stale), " + std::to_string(s.radio_out) + " out";
}

HilSplitRobot::HilSplitRobot(Scenario scenario, std::size_t index, std::shared_ptr<io::IOStream> port,
                             HilSplitRobotOptions options)
    : scenario_(std::move(scenario)),
      index_(index),
      port_(std::move(port)),
      options_(std::move(options)),
      shared_(std::make_shared<Shared>()),
      // A radio frame holds a whole message: the decoder takes the longest the radio sends.
      decoder_(scenario_.world.radio
                   ? std::max<std::size_t>(1024, kHilRadioHeader + scenario_.world.radio->max_message_bytes)
                   : std::size_t{1024}),
      buf_(4096) {
  shared_->pose = std::make_shared<SimPoseSensor>("pose", scenario_.world.width, scenario_.world.height);
}

HilSplitRobot::~HilSplitRobot() {
  clock_.reset();
  system_.reset();
}

kernel::Result<std::unique_ptr<HilSplitRobot>> HilSplitRobot::create(const Scenario& scenario, std::string_view robot,
                                                                     std::shared_ptr<io::IOStream> port,
                                                                     HilSplitRobotOptions options) {
  if (scenario.world_kind != WorldKind::kEnki)
    return kernel::Error{scenario.file +
                         ": a 3D world's modules do not run as remote robots (one module can run in another "
                         "process: symb board --robot NAME --dds, docs/hil.md)"};
  std::size_t index = scenario.robots.size();
  for (std::size_t i = 0; i < scenario.robots.size(); ++i)
    if (scenario.robots[i].name == robot) index = i;
  if (index == scenario.robots.size()) {
    std::string names;
    for (std::size_t i = 0; i < scenario.robots.size() && i < 8; ++i)
      names += (i > 0 ? ", " : "") + scenario.robots[i].name;
    if (scenario.robots.size() > 8) names += ", ...";
    return kernel::Error{scenario.file + ": no robot named '" + std::string(robot) + "' (its robots: " + names + ")"};
  }
  if (auto st = HilSplitWorld::check(scenario, index); !st) return kernel::Error{st.error()};
  if (!port) return kernel::Error{"no stream for robot " + std::string(robot)};
  std::unique_ptr<HilSplitRobot> r(new HilSplitRobot(scenario, index, std::move(port), std::move(options)));
  // The types a session registers: the caller's, then the scenario's plugins.
  r->extra_types_ = r->options_.task_types;
  for (const PluginRef& p : scenario.plugins) {
    auto lib = io::PluginLibrary::open(p.path);
    if (!lib) return kernel::Error{p.where.str() + ": " + lib.error()};
    r->extra_types_.emplace_back(
        [lib = std::move(lib).value()](os::TaskTypeRegistry& reg) { return lib->register_into(reg); });
  }
  {
    os::TaskTypeRegistry schemas;
    if (auto st = register_scenario_task_types(schemas, {}, file_program_reader(scenario.base_dir)); !st)
      return kernel::Error{st.error()};
    for (const RegisterTaskTypes& add : r->extra_types_)
      if (auto st = add(schemas); !st) return kernel::Error{scenario.file + ": " + st.error()};
    if (auto st = check_scenario(scenario, schemas); !st) return kernel::Error{st.error()};
  }
  if (!r->port_->is_open())
    if (auto st = r->port_->open(); !st) return kernel::Error{"cannot open the stream: " + st.error()};
  return r;
}

void HilSplitRobot::event(const std::string& text) {
  if (options_.on_event) options_.on_event(text);
}

kernel::Status HilSplitRobot::build(std::uint64_t seed) {
  const ProgramReader read = file_program_reader(scenario_.base_dir);
  const auto extra = [this](os::TaskTypeRegistry& reg) -> kernel::Status {
    for (const RegisterTaskTypes& add : extra_types_)
      if (auto st = add(reg); !st) return st;
    return {};
  };
  auto shared_types = shared_scenario_task_types(read, extra);
  if (!shared_types) return kernel::Error{scenario_.file + ": " + shared_types.error()};
  RobotSystemOptions ro;
  ro.shared_types = shared_types.value();
  ro.control_period = scenario_.control_period;
  ro.seed = robot_node_seed(seed, index_);
  ro.log_capacity = options_.log_capacity;
  ro.read_program = read;
  if (const auto& spec = scenario_.world.radio) {
    auto radio = LocalRadio::create(scenario_.robots.size(), {spec->range, spec->max_message_bytes});
    if (!radio) return kernel::Error{scenario_.file + ": radio: " + radio.error()};
    radio_ = std::move(radio).value();
    shared_->radio = radio_.get();
    shared_->robot = index_;
  }
  auto built = RobotSystem::build(
      executor_, scenario_.robots[index_],
      RobotDevices{shared_->ir, shared_->wheels, shared_->pose, shared_->ground, radio_.get(), index_, std::nullopt},
      std::move(ro));
  if (!built) return kernel::Error{built.error()};
  system_ = std::move(built).value();
  PeriodicRunner::Options co;  // the world runner's priority and name
  co.period = scenario_.control_period;
  clock_ = std::make_unique<Clock>(executor_, shared_, co);
  if (auto st = clock_->start(); !st) return st;
  seed_ = seed;
  return {};
}

void HilSplitRobot::answer(std::uint32_t seq) {
  const std::vector<float> out = shared_->wheels->output();
  frame_.clear();
  // What its radio task sent since the last answer: on air at the world's next step.
  std::uint64_t radio = 0;
  if (radio_)
    if (const auto blob = radio_->take_pending(index_))
      if (const auto* bytes = os::blob_as<io::Bytes>(blob.get())) {
        encode_radio_payload(seq, static_cast<std::uint32_t>(index_), bytes->data, radio_payload_);
        io::encode_frame(radio_payload_, frame_);
        radio = 1;
      }
  io::encode_frame(encode_wheel_payload({seq, out.at(0), out.at(1)}), frame_);
  const bool ok = port_->write_all(frame_).ok();
  std::lock_guard lock(stats_mu_);
  ++(ok ? stats_.answers : stats_.write_errors);
  if (ok) stats_.radio_out += radio;
}

kernel::Status HilSplitRobot::handle(std::span<const std::byte> payload, std::size_t& handled) {
  const std::string& name = scenario_.robots[index_].name;
  if (is_radio_payload(payload)) {
    auto m = decode_radio_payload(payload);
    std::lock_guard lock(stats_mu_);
    // A message from another robot of the world, for a sensor frame still to come; at most one per
    // other robot and step.
    if (!m || !radio_ || !system_ || m->robot >= scenario_.robots.size() || m->robot == index_ || m->seq == 0 ||
        shared_->incoming.size() >= scenario_.robots.size()) {
      ++stats_.malformed;
      return {};
    }
    if (m->seq <= stats_.last_seq) {
      ++stats_.radio_stale;
      return {};
    }
    shared_->incoming.push_back({m->seq, m->robot, std::make_shared<const io::Bytes>(m->bytes)});
    return {};
  }
  if (auto h = decode_hello_payload(payload)) {
    std::uint32_t last = 0;
    {
      std::lock_guard lock(stats_mu_);
      last = stats_.last_seq;
    }
    if (last > 0)
      return kernel::Error{
          "the world started a new run: this process serves one run (its node's time cannot go "
          "back); start it again"};
    if (h->robots != scenario_.robots.size() || h->robot != index_)
      return kernel::Error{"the world's scenario has " + std::to_string(h->robots) + " robots and asks for robot " +
                           std::to_string(h->robot) + "; " + scenario_.file + " has " +
                           std::to_string(scenario_.robots.size()) + ", robot " + name + " being robot " +
                           std::to_string(index_) + ": do both read the same scenario?"};
    if (h->digest != robot_digest(scenario_, index_))
      return kernel::Error{"the world's robot " + name + " is not " + scenario_.file +
                           "'s (another control period, arena, task, parameter or hook): do both read the same "
                           "scenario?"};
    if (!system_) {
      if (auto st = build(h->seed); !st) return st;
      event("robot " + name + ": built with the world's seed " + std::to_string(h->seed));
      // What the node does before the world's first step (its tasks' first ticks at time 0): the
      // world applies the answer's wheels in step 1, as in process.
      executor_.run_until(scenario_.control_period - kernel::Duration{1});
    } else if (h->seed != *seed_) {
      return kernel::Error{"a hello with seed " + std::to_string(h->seed) + " after one with seed " +
                           std::to_string(*seed_) + ": two worlds on one stream?"};
    }
    {
      std::lock_guard lock(stats_mu_);
      ++stats_.hellos;
    }
    answer(0);
    return {};
  }
  if (auto bye = decode_bye_payload(payload)) {
    ended_ = *bye;
    return {};
  }
  auto f = decode_split_sensors_payload(payload);
  {
    std::lock_guard lock(stats_mu_);
    if (!f || !system_) {  // garbage, or a sensor frame before any hello (nothing to run it on)
      ++stats_.malformed;
      return {};
    }
    if (f->seq <= stats_.last_seq) {
      ++stats_.out_of_order;
      return {};
    }
    stats_.missed += f->seq - stats_.last_seq - 1;
    stats_.last_seq = f->seq;
    // Its radio frames came just before it; others are of frames that never came.
    shared_->heard.clear();
    for (Shared::Heard& h : shared_->incoming) {
      if (h.seq == f->seq)
        shared_->heard.push_back(std::move(h));
      else
        ++stats_.radio_stale;
    }
    shared_->incoming.clear();
  }
  shared_->pending = *f;
  // Everything the node does before the world's next step: up to just before tick seq + 1.
  executor_.run_until(scenario_.control_period * (static_cast<std::int64_t>(f->seq) + 1) - kernel::Duration{1});
  answer(f->seq);
  ++handled;
  std::lock_guard lock(stats_mu_);
  ++stats_.frames;
  return {};
}

kernel::Result<std::size_t> HilSplitRobot::serve(kernel::Duration timeout) {
  std::size_t handled = 0;
  auto got = port_->read_some(buf_, timeout);
  if (!got) return kernel::Error{got.error()};
  kernel::Status failed;
  decoder_.feed(std::span<const std::byte>(buf_.data(), *got), [&](std::span<const std::byte> payload) {
    if (!failed) return;  // refused already: the rest is not served
    failed = handle(payload, handled);
  });
  {
    std::lock_guard lock(stats_mu_);
    stats_.decoder = decoder_.stats();
  }
  if (!failed) return kernel::Error{failed.error()};
  return handled;
}

HilSplitRobotBoardStats HilSplitRobot::stats() const {
  std::lock_guard lock(stats_mu_);
  HilSplitRobotBoardStats s = stats_;
  s.radio_in = shared_->radio_in.load();
  s.radio_dropped = shared_->radio_dropped.load();
  return s;
}

}  // namespace symb::sim
