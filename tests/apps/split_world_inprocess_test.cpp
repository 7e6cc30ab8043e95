// The split world's pieces in one process (docs/bus.md "A world split over processes"), so the
// sanitizer builds check them too: HilSplitWorld and HilSplitRobot over a loopback stream give the
// in-process swarm bit for bit, and the in-process mEDEA swarm with the world's radio carried; a robot that stops
// answering is gone after the answer wait and its wheels stop while the run goes on; the split frames refuse what is
// not theirs; DdsFrameStream carries bytes both ways between two ends of one process and tells a peer that left from
// one that is alive, a foreign writer that came and went not ending the stream for good.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/io/frame_codec.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/lockstep_executor.hpp"
#include "symb/sim/hil_split_protocol.hpp"
#include "symb/sim/hil_split_robot.hpp"
#include "symb/sim/hil_split_world.hpp"
#include "symb/sim/scenario_session.hpp"

namespace {
namespace split_inprocess {

using namespace std::chrono_literals;
using namespace symb;

const std::string kSwarm = std::string(SYMB_SCENARIO_DIR) + "/swarm.yaml";
constexpr std::uint64_t kSteps = 60;
// How long a step waits for an answer in the silent-robot test: every answering robot's step must
// come within it, on a box whose cores the other tests (and a sanitizer) share; only the silent
// robot's one step waits it out.
constexpr auto kAnswerWait = 2000ms;

struct Pose3 {
  double x, y, theta;
  bool operator==(const Pose3&) const = default;
};
using Trajectory = std::vector<std::vector<Pose3>>;  // per step, per robot

sim::Scenario swarm() {
  auto sc = sim::load_scenario(kSwarm);
  EXPECT_TRUE(sc.ok()) << sc.error();
  return std::move(sc).value();
}

void record(sim::ScenarioSession& s, Trajectory& out) {
  s.runner().add_observer([&out](const sim::StepRecord& r) {
    std::vector<Pose3> poses;
    for (const sim::RobotStep& x : r.robots) poses.push_back({x.state.pose.x, x.state.pose.y, x.state.pose.theta});
    out.push_back(std::move(poses));
  });
}

kernel::LockstepExecutor::Options lockstep(const sim::Scenario& sc) {
  return {.threads = 1, .quantum = sc.control_period};
}

Trajectory in_process(const sim::Scenario& sc, std::uint64_t steps = kSteps, sim::RadioCounts* radio = nullptr) {
  kernel::LockstepExecutor ex(lockstep(sc));
  auto s = sim::ScenarioSession::create(sc, ex);
  EXPECT_TRUE(s.ok()) << s.error();
  Trajectory t;
  record(**s, t);
  (*s)->start();
  ex.run_until(sc.control_period * static_cast<std::int64_t>(steps) + 1ms);
  (*s)->stop();
  if (radio != nullptr && (*s)->radio() != nullptr) *radio = (*s)->radio()->counts();
  return t;
}

// A robot's process, as a thread: serves until the world's bye, or until it is told to go silent.
class RobotThread {
 public:
  RobotThread(const sim::Scenario& sc, const std::string& name, std::shared_ptr<io::IOStream> port,
              std::uint32_t silent_after = 0)
      : silent_after_(silent_after) {
    auto r = sim::HilSplitRobot::create(sc, name, std::move(port));
    EXPECT_TRUE(r.ok()) << r.error();
    if (!r.ok()) return;
    robot_ = std::move(r).value();
    thread_ = std::thread([this] {
      while (!stop_.load() && !robot_->ended()) {
        if (silent_after_ > 0 && robot_->stats().last_seq >= silent_after_) {
          std::this_thread::sleep_for(1ms);
          continue;
        }
        if (!robot_->serve(20ms).ok()) break;
      }
      done_.store(true);
    });
  }
  ~RobotThread() { join(); }
  void join() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  // After the world's bye: the robot reads it and ends on its own (a sanitizer's box may take a
  // while); stopped only if it has not within `within`.
  void finish(std::chrono::milliseconds within) {
    const auto deadline = std::chrono::steady_clock::now() + within;
    while (!done_.load() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
    join();
  }
  sim::HilSplitRobot& robot() { return *robot_; }

 private:
  std::uint32_t silent_after_;
  std::unique_ptr<sim::HilSplitRobot> robot_;
  std::atomic<bool> stop_{false}, done_{false};
  std::thread thread_;
};

// The world of `sc` in this process with the robots of `remote` (indices) each served by a
// RobotThread over a loopback stream, run for `steps` steps in lockstep, then told bye.
struct SplitRun {
  SplitRun(const sim::Scenario& sc, std::initializer_list<std::size_t> remote, std::uint64_t steps) : ex(lockstep(sc)) {
    auto made = sim::ScenarioSession::create(sc, ex);
    EXPECT_TRUE(made.ok()) << made.error();
    if (!made.ok()) return;
    session = std::move(made).value();
    record(*session, trajectory);
    std::vector<sim::HilSplitWorld::Remote> remotes;
    for (std::size_t i : remote) {
      auto [a, b] = io::make_loopback_pair("split" + std::to_string(i));
      remotes.push_back({i, std::shared_ptr<io::IOStream>(std::move(a))});
      robots.push_back(
          std::make_unique<RobotThread>(sc, sc.robots[i].name, std::shared_ptr<io::IOStream>(std::move(b))));
    }
    auto w = sim::HilSplitWorld::create(*session, std::move(remotes), {.answer_wait = 10s, .on_event = {}});
    EXPECT_TRUE(w.ok()) << w.error();
    if (!w.ok()) return;
    world = std::move(w).value();
    EXPECT_TRUE(world->wait_for_robots(10s).ok());
    session->start();
    ex.run_until(sc.control_period * static_cast<std::int64_t>(steps) + 1ms);
    session->stop();
    world->say_bye(steps);
    for (auto& r : robots) r->finish(10s);
  }
  kernel::LockstepExecutor ex;
  std::unique_ptr<sim::ScenarioSession> session;
  Trajectory trajectory;
  std::vector<std::unique_ptr<RobotThread>> robots;
  std::unique_ptr<sim::HilSplitWorld> world;
};

TEST(HilSplit, RemoteRobotsOverStreamsRunTheSwarmBitForBit) {
  const sim::Scenario sc = swarm();
  const Trajectory reference = in_process(sc);
  ASSERT_EQ(reference.size(), kSteps);

  SplitRun run(sc, {1, 6}, kSteps);
  ASSERT_NE(run.world, nullptr);
  const Trajectory& split = run.trajectory;
  ASSERT_EQ(split.size(), kSteps);
  EXPECT_TRUE(split == reference) << "the split swarm must be the in-process one";
  for (const auto& st : run.world->stats()) {
    EXPECT_FALSE(st.gone) << st.why;
    EXPECT_EQ(st.applied, kSteps);
    EXPECT_EQ(st.bad_frames(), 0u);
  }
  for (auto& r : run.robots) {
    EXPECT_EQ(r->robot().stats().frames, kSteps);
    EXPECT_EQ(r->robot().ended(), std::optional<std::uint32_t>(kSteps));
    EXPECT_EQ(r->robot().seed(), std::optional<std::uint64_t>(sc.seed));
  }
}

// mEDEA over the world's radio, its lifetime cut to 1.5 s: by step 100 (3 s) every robot has
// twice picked its next genome among those it heard, so the trajectories depend on what the radio
// carried both ways between the world and the two remote robots.
TEST(HilSplit, RemoteRobotsCarryTheWorldsRadioBitForBit) {
  auto loaded = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  sim::Scenario sc = std::move(loaded).value();
  ASSERT_TRUE(sc.world.radio.has_value());
  for (sim::RobotSpec& r : sc.robots)
    for (sim::TaskSpec& t : r.tasks)
      for (os::ParamAssignment& p : t.params)
        if (p.name == "lifetime") p.value = "1.5s";
  constexpr std::uint64_t kRadioSteps = 100;
  sim::RadioCounts reference_radio;
  const Trajectory reference = in_process(sc, kRadioSteps, &reference_radio);
  ASSERT_EQ(reference.size(), kRadioSteps);
  EXPECT_GT(reference_radio.delivered, 50u) << "the robots meet over the radio";

  SplitRun run(sc, {4, 13}, kRadioSteps);
  ASSERT_NE(run.world, nullptr);
  const Trajectory& split = run.trajectory;
  ASSERT_EQ(split.size(), kRadioSteps);
  EXPECT_TRUE(split == reference) << "the split mEDEA swarm must be the in-process one";
  const sim::RadioCounts radio = run.session->radio()->counts();
  EXPECT_EQ(radio.transmitted, reference_radio.transmitted);
  EXPECT_EQ(radio.delivered, reference_radio.delivered);
  EXPECT_EQ(radio.dropped, reference_radio.dropped);
  EXPECT_EQ(radio.out_of_range, reference_radio.out_of_range);
  for (const auto& st : run.world->stats()) {
    EXPECT_FALSE(st.gone) << st.why;
    EXPECT_EQ(st.applied, kRadioSteps);
    EXPECT_EQ(st.bad_frames(), 0u);
    EXPECT_GT(st.radio_received, 5u) << st.robot << ": its genome went on air";
    EXPECT_EQ(run.session->radio()->received_by(st.index), st.radio_sent) << st.robot;
    EXPECT_NE(sim::describe(st).find("; radio: "), std::string::npos) << sim::describe(st);
  }
  std::uint64_t heard = 0;
  for (auto& r : run.robots) {
    const auto st = r->robot().stats();
    EXPECT_EQ(st.frames, kRadioSteps);
    EXPECT_EQ(st.bad_frames(), 0u);
    EXPECT_EQ(st.radio_stale + st.radio_dropped, 0u);
    heard += st.radio_in;
  }
  EXPECT_GT(heard, 0u) << "the remote robots heard others";
  std::uint64_t to_remote = 0;
  for (const auto& st : run.world->stats()) to_remote += st.radio_sent;
  EXPECT_EQ(heard, to_remote) << "every message the world's radio delivered to them was posted";
}

TEST(HilSplit, ARobotThatStopsAnsweringIsGoneItsWheelsStopAndTheRunGoesOn) {
  const sim::Scenario sc = swarm();
  kernel::LockstepExecutor ex(lockstep(sc));
  auto s = sim::ScenarioSession::create(sc, ex);
  ASSERT_TRUE(s.ok()) << s.error();
  Trajectory t;
  record(**s, t);
  auto [a, b] = io::make_loopback_pair("silent");
  RobotThread robot(sc, "thymio3", std::shared_ptr<io::IOStream>(std::move(b)), 10);
  std::vector<std::string> events;
  auto world = sim::HilSplitWorld::create(
      **s, {{3, std::shared_ptr<io::IOStream>(std::move(a))}},
      {.answer_wait = kAnswerWait, .on_event = [&events](const std::string& e) { events.push_back(e); }});
  ASSERT_TRUE(world.ok()) << world.error();
  ASSERT_TRUE((*world)->wait_for_robots(10s).ok());
  (*s)->start();
  ex.run_until(sc.control_period * static_cast<std::int64_t>(kSteps) + 1ms);
  (*s)->stop();
  robot.join();
  ASSERT_EQ(t.size(), kSteps);
  const auto st = (*world)->stats().at(0);
  EXPECT_TRUE(st.gone);
  EXPECT_EQ(st.gone_at, 11u);  // it answered steps 1 to 10
  EXPECT_EQ(st.applied, 10u);
  EXPECT_NE(st.why.find("no answer to step 11 within " + std::to_string(kAnswerWait.count()) + " ms"),
            std::string::npos)
      << st.why;
  EXPECT_EQ((*world)->gone(), 1u);
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.back().find("robot thymio3: gone at step 11"), std::string::npos) << events.back();
  // From step 12 on its wheels are at rest: it stands where it stood.
  for (std::uint64_t k = 12; k < kSteps; ++k) EXPECT_TRUE(t[k][3] == t[11][3]) << "step " << k + 1;
  EXPECT_FALSE(t[5][3] == t[0][3]) << "it drove while it answered";
}

TEST(HilSplit, TheFramesRefuseWhatIsNotTheirs) {
  const sim::HilSplitHello h{0x0123'4567'89AB'CDEFull, 4, 12, 0xDEAD'BEEF};
  const auto back = sim::decode_hello_payload(sim::encode_hello_payload(h));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->seed, h.seed);
  EXPECT_EQ(back->robot, 4u);
  EXPECT_EQ(back->robots, 12u);
  EXPECT_EQ(back->digest, 0xDEAD'BEEFu);
  const auto numbers = [](std::vector<float> v) { return io::encode_numbers(v); };
  EXPECT_FALSE(sim::decode_hello_payload(numbers({0, 1, 2, 3, 65536, 0, 2, 0, 0})).ok())
      << "a seed piece above 16 bits";
  EXPECT_FALSE(sim::decode_hello_payload(numbers({0, 1, 2, 3, 4, 2, 2, 0, 0})).ok()) << "robot 2 of 2";
  EXPECT_FALSE(sim::decode_hello_payload(numbers({1, 1, 2, 3, 4, 0, 2, 0, 0})).ok()) << "a hello's seq is 0";
  sim::HilSplitSensors f;
  f.seq = 7;
  f.ir[2] = 1234.5f;
  f.pose[2] = -3.1f;
  f.ground[1] = 0.25f;
  const auto g = sim::decode_split_sensors_payload(sim::encode_split_sensors_payload(f));
  ASSERT_TRUE(g.ok()) << g.error();
  EXPECT_EQ(g->seq, 7u);
  EXPECT_EQ(g->ir[2], 1234.5f);
  EXPECT_EQ(g->pose[2], -3.1f);
  EXPECT_EQ(g->ground[1], 0.25f);
  f.seq = 0;
  EXPECT_FALSE(sim::decode_split_sensors_payload(sim::encode_split_sensors_payload(f)).ok()) << "seq 0 is the hello's";
  f.seq = 8;
  f.pose[0] = std::nanf("");
  EXPECT_FALSE(sim::decode_split_sensors_payload(sim::encode_split_sensors_payload(f)).ok()) << "NaN";
  EXPECT_FALSE(sim::decode_split_sensors_payload(numbers({1, 2, 3})).ok()) << "a count of 3";
  EXPECT_EQ(sim::decode_bye_payload(sim::encode_bye_payload(166)), std::optional<std::uint32_t>(166));
  EXPECT_FALSE(sim::decode_bye_payload(numbers({1, 166})).has_value());

  const std::vector<std::byte> message{std::byte{0}, std::byte{'R'}, std::byte{0xFF}};
  std::vector<std::byte> radio;
  sim::encode_radio_payload(0x00AB'CDEF, 19, message, radio);
  ASSERT_TRUE(sim::is_radio_payload(radio));
  const auto r = sim::decode_radio_payload(radio);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->seq, 0x00AB'CDEFu);
  EXPECT_EQ(r->robot, 19u);
  EXPECT_TRUE(std::equal(r->bytes.begin(), r->bytes.end(), message.begin(), message.end()));
  EXPECT_FALSE(sim::is_radio_payload(numbers({1, 2, 3}))) << "a number frame";
  sim::encode_radio_payload(4, 1, {}, radio);
  EXPECT_FALSE(sim::decode_radio_payload(radio).ok()) << "no message";
  sim::encode_radio_payload(4, 1, message, radio);
  EXPECT_FALSE(sim::decode_radio_payload(std::span<const std::byte>(radio).first(6)).ok()) << "a header cut short";
  sim::encode_radio_payload(sim::kHilMaxSequence + 1, 1, message, radio);
  EXPECT_FALSE(sim::decode_radio_payload(radio).ok()) << "beyond the sequence numbers";
}

// The world's side of the radio, fed by hand: a remote robot's answer to the hello puts its radio
// message on air once; radio frames that are not its own, or empty, are malformed, a second one
// for the same answer stale.
TEST(HilSplit, TheWorldPutsARemoteRobotsRadioMessageOnAirOnceAndCountsTheRest) {
  auto medea = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml");
  ASSERT_TRUE(medea.ok()) << medea.error();
  kernel::LockstepExecutor ex(lockstep(*medea));
  auto s = sim::ScenarioSession::create(*medea, ex);
  ASSERT_TRUE(s.ok()) << s.error();
  auto [a, robot] = io::make_loopback_pair("radio_world");
  auto world = sim::HilSplitWorld::create(**s, {{7, std::shared_ptr<io::IOStream>(std::move(a))}},
                                          {.answer_wait = 1s, .on_event = {}});
  ASSERT_TRUE(world.ok()) << world.error();
  std::vector<std::byte> frames, payload;
  const auto add = [&frames](const std::vector<std::byte>& p) { io::encode_frame(p, frames); };
  const std::string hi = "genome of 7", other = "another";
  const auto bytes = [](const std::string& t) {
    return std::span<const std::byte>(reinterpret_cast<const std::byte*>(t.data()), t.size());
  };
  sim::encode_radio_payload(0, 6, bytes(hi), payload);  // robot 6's, not its own
  add(payload);
  sim::encode_radio_payload(0, 7, {}, payload);  // empty
  add(payload);
  sim::encode_radio_payload(0, 7, bytes(hi), payload);
  add(payload);
  sim::encode_radio_payload(0, 7, bytes(other), payload);  // a second one for the same answer
  add(payload);
  add(sim::encode_wheel_payload({0, 0.0f, 0.0f}));
  ASSERT_TRUE(robot->write_all(frames).ok());
  ASSERT_TRUE((*world)->wait_for_robots(5s).ok());
  const auto st = (*world)->stats().at(0);
  EXPECT_EQ(st.malformed, 2u);
  EXPECT_EQ(st.stale, 1u);
  EXPECT_EQ(st.radio_received, 1u);
  EXPECT_TRUE(st.answered);
  const auto on_air = (*s)->radio()->take_pending(7);
  ASSERT_NE(on_air, nullptr) << "on air at the world's first step";
  const io::Bytes* got = os::blob_as<io::Bytes>(on_air.get());
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->text(), hi);
}

// The robot's side: radio frames come before the sensor frame of their step and are posted into
// its radio task at that tick; what is not a message of another robot of the world is malformed,
// what no sensor frame of its own followed is stale.
TEST(HilSplit, ARobotTakesTheRadioFramesOfItsNextSensorFrameAndCountsTheRest) {
  auto medea = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml");
  ASSERT_TRUE(medea.ok()) << medea.error();
  auto [world, end] = io::make_loopback_pair("radio_robot");
  auto robot = sim::HilSplitRobot::create(*medea, "thymio3", std::shared_ptr<io::IOStream>(std::move(end)));
  ASSERT_TRUE(robot.ok()) << robot.error();
  std::vector<std::byte> frames, payload;
  const auto add = [&frames](const std::vector<std::byte>& p) { io::encode_frame(p, frames); };
  const std::vector<std::byte> msg{std::byte{1}, std::byte{2}, std::byte{3}};
  sim::encode_radio_payload(1, 5, msg, payload);  // before the hello: nothing to post it to
  add(payload);
  add(sim::encode_hello_payload({1, 3, 20, sim::robot_digest(*medea, 3)}));
  for (const auto& [seq, sender] :
       std::vector<std::pair<std::uint32_t, std::uint32_t>>{{1, 3},     // its own
                                                            {1, 20},    // no such robot
                                                            {0, 5},     // the hello's
                                                            {1, 5},     // good
                                                            {1, 12},    // good
                                                            {3, 8}}) {  // for a frame that does not come next
    sim::encode_radio_payload(seq, sender, msg, payload);
    add(payload);
  }
  add({std::byte{'R'}, std::byte{1}});  // cut short
  sim::HilSplitSensors f;
  f.seq = 1;
  add(sim::encode_split_sensors_payload(f));
  sim::encode_radio_payload(1, 9, msg, payload);  // after its frame
  add(payload);
  f.seq = 2;
  add(sim::encode_split_sensors_payload(f));
  ASSERT_TRUE(world->write_all(frames).ok());
  for (int k = 0; k < 3 && (*robot)->stats().frames < 2; ++k) ASSERT_TRUE((*robot)->serve(200ms).ok());
  const auto st = (*robot)->stats();
  EXPECT_EQ(st.frames, 2u);
  EXPECT_EQ(st.malformed, 5u);
  EXPECT_EQ(st.radio_stale, 2u);
  EXPECT_EQ(st.radio_in, 2u) << "robots 5 and 12's messages, posted at tick 1";
  EXPECT_EQ(st.radio_dropped, 0u);
  EXPECT_NE(sim::describe(st).find("radio 2 in (0 dropped, 2 stale)"), std::string::npos) << sim::describe(st);
}

TEST(HilSplit, WhatCannotRunApartIsRefusedAtItsPlace) {
  auto medea = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml");
  ASSERT_TRUE(medea.ok()) << medea.error();
  EXPECT_TRUE(sim::HilSplitWorld::check(*medea, 2).ok()) << "the world's radio is carried";
  sim::Scenario evented = swarm();
  sim::EventSpec e;
  e.robot = 5;
  e.where = {evented.file, 40, 7};
  evented.events.push_back(e);
  const auto named = sim::HilSplitWorld::check(evented, 5);
  ASSERT_FALSE(named.ok());
  EXPECT_NE(named.error().find("robot thymio5 runs in another process: its events belong to that process's shell"),
            std::string::npos)
      << named.error();
  EXPECT_NE(named.error().find("swarm.yaml:40:7"), std::string::npos) << "at its place: " << named.error();
  EXPECT_TRUE(sim::HilSplitWorld::check(evented, 4).ok());
  auto [a, b] = io::make_loopback_pair("refused");
  const auto unknown = sim::HilSplitRobot::create(swarm(), "thymio12", std::shared_ptr<io::IOStream>(std::move(b)));
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("no robot named 'thymio12' (its robots: thymio0, thymio1"), std::string::npos)
      << unknown.error();
}

// The robot's side fed frame by frame: what it refuses, and why.
TEST(HilSplit, ARobotRefusesAnotherScenariosHelloAndASecondRun) {
  const sim::Scenario sc = swarm();
  const auto send = [](io::IOStream& to, const std::vector<std::byte>& payload) {
    std::vector<std::byte> frame;
    io::encode_frame(payload, frame);
    ASSERT_TRUE(to.write_all(frame).ok());
  };
  {
    auto [world, end] = io::make_loopback_pair("other");
    auto robot = sim::HilSplitRobot::create(sc, "thymio4", std::shared_ptr<io::IOStream>(std::move(end)));
    ASSERT_TRUE(robot.ok()) << robot.error();
    sim::HilSplitSensors early;
    early.seq = 1;
    send(*world, sim::encode_split_sensors_payload(early));  // before any hello: nothing to run it on
    send(*world, sim::encode_hello_payload({7, 4, 13, 0}));  // a world of 13 robots
    const auto served = (*robot)->serve(1s);
    ASSERT_FALSE(served.ok());
    EXPECT_NE(served.error().find("the world's scenario has 13 robots and asks for robot 4"), std::string::npos)
        << served.error();
    EXPECT_NE(served.error().find("do both read the same scenario?"), std::string::npos) << served.error();
    EXPECT_EQ((*robot)->stats().malformed, 1u);
    EXPECT_EQ((*robot)->system(), nullptr) << "nothing built";
  }
  {
    // The same count and index, but another control period: the digest tells.
    sim::Scenario other = sc;
    other.control_period = sc.control_period * 2;
    auto [world, end] = io::make_loopback_pair("digest");
    auto robot = sim::HilSplitRobot::create(sc, "thymio4", std::shared_ptr<io::IOStream>(std::move(end)));
    ASSERT_TRUE(robot.ok()) << robot.error();
    send(*world, sim::encode_hello_payload({7, 4, 12, sim::robot_digest(other, 4)}));
    const auto served = (*robot)->serve(1s);
    ASSERT_FALSE(served.ok());
    EXPECT_NE(served.error().find("the world's robot thymio4 is not"), std::string::npos) << served.error();
    EXPECT_NE(sim::robot_digest(sc, 4), sim::robot_digest(sc, 5)) << "robots differ by name at least";
  }
  auto [world, end] = io::make_loopback_pair("again");
  auto robot = sim::HilSplitRobot::create(sc, "thymio4", std::shared_ptr<io::IOStream>(std::move(end)));
  ASSERT_TRUE(robot.ok()) << robot.error();
  send(*world, sim::encode_hello_payload({99, 4, 12, sim::robot_digest(sc, 4)}));
  ASSERT_TRUE((*robot)->serve(1s).ok());
  EXPECT_EQ((*robot)->seed(), std::optional<std::uint64_t>(99)) << "built with the world's seed, not the file's";
  ASSERT_NE((*robot)->system(), nullptr);
  for (std::uint32_t k : {1u, 2u, 2u, 5u}) {  // a repeated frame and two lost ones
    sim::HilSplitSensors f;
    f.seq = k;
    send(*world, sim::encode_split_sensors_payload(f));
  }
  for (int k = 0; k < 4; ++k) ASSERT_TRUE((*robot)->serve(100ms).ok());
  auto st = (*robot)->stats();
  EXPECT_EQ(st.frames, 3u);
  EXPECT_EQ(st.out_of_order, 1u);
  EXPECT_EQ(st.missed, 2u);
  EXPECT_EQ((*robot)->now(), sc.control_period * 6 - kernel::Duration{1}) << "run up to just before tick 6";
  send(*world, sim::encode_hello_payload({99, 4, 12, sim::robot_digest(sc, 4)}));
  const auto again = (*robot)->serve(1s);
  ASSERT_FALSE(again.ok());
  EXPECT_NE(again.error().find("the world started a new run: this process serves one run"), std::string::npos)
      << again.error();
}

TEST(DdsFrameStream, CarriesBytesBothWaysAndTellsAPeerThatLeft) {
  const std::uint32_t domain = 10 + static_cast<std::uint32_t>(::getpid() % 200);
  auto links = io::DdsFrameLinks::create({domain, "frames_" + std::to_string(::getpid()), 300ms});
  ASSERT_TRUE(links.ok()) << links.error();
  auto world = (*links)->stream("r1", "down", "up");
  auto robot = (*links)->stream("r1", "up", "down");
  ASSERT_TRUE(world.ok() && robot.ok());
  EXPECT_EQ((*world)->write_topic(), "rt/frames_" + std::to_string(::getpid()) + "/r1/down");
  ASSERT_TRUE((*world)->wait_matched(10s));
  ASSERT_TRUE((*robot)->wait_matched(10s));
  const std::vector<std::byte> hello{std::byte{0}, std::byte{1}, std::byte{2}, std::byte{0}};
  ASSERT_TRUE((*world)->write_all(hello).ok());
  ASSERT_TRUE((*robot)->write_all(std::vector<std::byte>{std::byte{9}}).ok());
  const auto read_all = [](io::DdsFrameStream& s, std::size_t n) {
    std::vector<std::byte> got, buf(16);
    const auto until = std::chrono::steady_clock::now() + 5s;
    while (got.size() < n && std::chrono::steady_clock::now() < until) {
      auto r = s.read_some(buf, 100ms);
      if (!r.ok()) break;
      got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*r));
    }
    return got;
  };
  EXPECT_EQ(read_all(**robot, 4), hello);
  EXPECT_EQ(read_all(**world, 1), std::vector<std::byte>{std::byte{9}});
  EXPECT_EQ((*robot)->peer(), io::DdsPeerState::kAlive);
  {
    // A foreign writer on the robot's input comes and goes: the world's writer is still there.
    auto foreign = (*links)->stream("r1", "down", "nowhere");
    ASSERT_TRUE(foreign.ok());
    ASSERT_TRUE((*foreign)->write_all(hello).ok());
    EXPECT_TRUE((*foreign)->flush(2s));
  }
  EXPECT_EQ(read_all(**robot, 4), hello);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ((*robot)->peer(), io::DdsPeerState::kAlive);
  EXPECT_TRUE((*robot)->is_open());
  // The world finishes: what it wrote is read first, then the stream ends.
  ASSERT_TRUE((*world)->write_all(hello).ok());
  EXPECT_TRUE((*world)->flush(2s));
  (*world)->finish_sending();
  EXPECT_FALSE((*world)->write_all(hello).ok()) << "this end finished sending";
  EXPECT_EQ(read_all(**robot, 4), hello);
  std::vector<std::byte> buf(16);
  kernel::Result<std::size_t> end = std::size_t{0};
  for (int k = 0; k < 50 && end.ok(); ++k) end = (*robot)->read_some(buf, 100ms);
  ASSERT_FALSE(end.ok());
  EXPECT_NE(end.error().find("left"), std::string::npos) << end.error();
  EXPECT_FALSE((*robot)->is_open());
  EXPECT_EQ((*robot)->counts().chunks_read, 3u);
  EXPECT_EQ((*world)->counts().chunks_written, 2u);
}

}  // namespace split_inprocess
}  // namespace
