// mEDEA with 20 robots (issue 7, "must show"): the swarm world of scenarios/swarm.yaml (300 x 300
// cm, four walls) with 20 Thymios at seed-chosen places, each with a sim::RadioTask over one shared
// sim::LocalRadio (range 35 cm) and an evo::MedeaTask that runs a random 7-2 tanh perceptron at
// first. There is no fitness: a genome survives by being heard. Measured per 2-minute window of
// virtual time: the share of active robots (sampled every second) and the mean distance travelled
// per robot. Both must rise: genomes that drive (and so meet others) spread, robots that hear
// nobody go inactive and stand still.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/medea/medea_task.hpp"
#include "symb/io/bytes.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/local_radio.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/tsan_skip.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

// --- the radio medium alone ------------------------------------------------------------------

// Keeps what its radio sends on: the text and the sender index.
class Listener : public os::Task {
 public:
  std::vector<std::pair<float, std::string>> heard;

 protected:
  void on_message(const os::Message& m) override {
    const io::Bytes* b = io::bytes_of(m);
    heard.emplace_back(m.numbers().empty() ? -1.0f : m.numbers()[0], b ? std::string(b->text()) : "");
  }
};

// Sends the bytes it is told to, from a task (as a hooked genome source would).
class Talker : public os::Task {
 public:
  std::vector<std::string> to_say;

 protected:
  void on_tick() override {
    for (const std::string& t : to_say) send(0, io::text_payload(t));
    to_say.clear();
  }
};

StepRecord positions(std::initializer_list<std::pair<double, double>> xy) {
  StepRecord r;
  for (const auto& p : xy) {
    RobotStep s;
    s.state.pose = {p.first, p.second, 0};
    r.robots.push_back(s);
  }
  return r;
}

TEST(LocalRadio, DeliversAtTheNextStepToTheOtherRobotsInRange) {
  auto radio = LocalRadio::create(4, {.range = 50});
  ASSERT_TRUE(radio.ok());
  EXPECT_FALSE(LocalRadio::create(4, {.range = -1}).ok());
  EXPECT_FALSE(LocalRadio::create(0).ok());
  kernel::VirtualTimeExecutor ex;
  std::vector<std::unique_ptr<os::Node>> nodes;
  std::vector<Listener*> listeners;
  std::vector<Talker*> talkers;
  for (std::size_t i = 0; i < 4; ++i) {
    nodes.push_back(std::make_unique<os::Node>(ex, os::NodeConfig{.name = "r" + std::to_string(i)}));
    os::Node& n = *nodes.back();
    const auto r = (*radio)->add_to(n, i);
    ASSERT_TRUE(r.ok());
    auto l = std::make_unique<Listener>();
    listeners.push_back(l.get());
    auto t = std::make_unique<Talker>();
    talkers.push_back(t.get());
    const auto lid = *n.create("listener", std::move(l));
    const auto tid = *n.create("talker", std::move(t), {.period = 1s});
    ASSERT_TRUE(n.hook(*r, lid).ok());
    ASSERT_TRUE(n.hook(tid, *r).ok());
  }
  EXPECT_FALSE((*radio)->add_to(*nodes[0], 9).ok());
  ex.run_for(10ms);  // the tasks start
  // Robot 0 at the origin, 1 at 30 cm, 2 at exactly 50 cm, 3 at 80 cm.
  const StepRecord where = positions({{0, 0}, {30, 0}, {0, 50}, {80, 0}});
  talkers[0]->to_say = {"old", "new"};  // one message per step: "new" replaces "old"
  talkers[3]->to_say = {"far"};
  ex.run_for(1s);
  EXPECT_TRUE(listeners[1]->heard.empty());  // nothing before the step
  (*radio)->step(where);
  ex.run_for(1ms);
  ASSERT_EQ(listeners[1]->heard.size(), 2u);  // from 0, then from 3 (80 - 30 = 50 cm)
  EXPECT_EQ(listeners[1]->heard[0], (std::pair<float, std::string>{0.0f, "new"}));
  EXPECT_EQ(listeners[1]->heard[1], (std::pair<float, std::string>{3.0f, "far"}));
  ASSERT_EQ(listeners[2]->heard.size(), 1u);
  EXPECT_EQ(listeners[2]->heard[0].second, "new");
  EXPECT_TRUE(listeners[0]->heard.empty());  // 3 is 80 cm away; no one hears itself
  EXPECT_TRUE(listeners[3]->heard.empty());  // 0 is 80 cm away
  const RadioCounts c = (*radio)->counts();
  EXPECT_EQ(c.transmitted, 2u);
  EXPECT_EQ(c.overwritten, 1u);
  EXPECT_EQ(c.delivered, 3u);
  EXPECT_EQ(c.out_of_range, 3u);  // 0 -> 3, 3 -> 0, 3 -> 2
  EXPECT_EQ(c.dropped, 0u);
  EXPECT_EQ((*radio)->received_by(1), 2u);
  (*radio)->step(where);  // nothing pending: nothing on air
  EXPECT_EQ((*radio)->counts().transmitted, 2u);
  // A removed radio task no longer receives (counted as dropped).
  ASSERT_TRUE(nodes[1]->remove(*nodes[1]->find("radio")).ok());
  ex.run_for(1ms);
  talkers[0]->to_say = {"again"};
  ex.run_for(1s);
  (*radio)->step(where);
  EXPECT_EQ((*radio)->counts().dropped, 1u);
  EXPECT_EQ((*radio)->counts().delivered, 4u);
  for (auto& n : nodes) n->clear();
}

constexpr std::size_t kRobots = 20;

// swarm.yaml with `count` robots and no controller: only the device tasks.
Scenario bare_swarm(std::size_t count) {
  auto text = file_program_reader(SYMB_SCENARIO_DIR)("swarm.yaml");
  EXPECT_TRUE(text.ok());
  std::string yaml = text ? *text : std::string();
  const auto at = yaml.find("count: 12");
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) yaml.replace(at, 9, "count: " + std::to_string(count));
  auto s = parse_scenario(yaml, "swarm.yaml");
  EXPECT_TRUE(s.ok()) << (s ? "" : s.error());
  if (!s) return {};
  Scenario scenario = *s;
  for (RobotSpec& r : scenario.robots) {
    r.tasks.clear();
    r.hooks.clear();
  }
  return scenario;
}

struct Window {
  double active_share = 0;  // mean over the window's one-second samples
  double distance = 0;      // cm per robot
};

struct SwarmRun {
  std::vector<Window> windows;
  RadioCounts radio;
  std::uint64_t lifetimes = 0, malformed = 0, controllers = 0;
  std::vector<double> final_genes;  // robot 0's genome, for the determinism check
};

SwarmRun run_swarm(std::uint64_t seed, kernel::Duration duration, kernel::Duration window) {
  SwarmRun out;
  auto radio = LocalRadio::create(kRobots, {.range = 35});
  EXPECT_TRUE(radio.ok());
  if (!radio) return out;
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto made_session = ScenarioSession::create(bare_swarm(kRobots), executor, options);
  EXPECT_TRUE(made_session.ok()) << (made_session ? "" : made_session.error());
  if (!made_session) return out;
  std::unique_ptr<ScenarioSession> session = std::move(made_session).value();  // after the radio: dies first
  ScenarioSession& s = *session;
  EXPECT_EQ(s.robot_count(), kRobots);
  (*radio)->attach(s.runner());
  std::vector<evo::MedeaTask*> medea;
  for (std::size_t i = 0; i < s.robot_count(); ++i) {
    os::Node& node = s.robot(i).node();
    EXPECT_TRUE((*radio)->add_to(node, i).ok());
    evo::MedeaTaskOptions o;  // lifetime 12 s, sigma 0.2, genes in [-4, 4], a 7-2 tanh perceptron
    auto made = evo::MedeaTask::create(o);
    EXPECT_TRUE(made.ok());
    medea.push_back(made->get());
    EXPECT_TRUE(
        node.create("medea", std::move(made).value(), {.priority = 1, .period = 300ms, .queue_capacity = 64}).ok());
  }
  s.start();
  const auto seconds = static_cast<int>(std::chrono::duration_cast<std::chrono::seconds>(window).count());
  std::vector<double> distance_before(kRobots, 0.0);
  for (kernel::Duration t{0}; t < duration; t += window) {
    Window w;
    for (int k = 0; k < seconds; ++k) {
      executor.run_for(1s);
      std::size_t active = 0;
      for (const evo::MedeaTask* m : medea) active += m->active() ? 1 : 0;
      w.active_share += static_cast<double>(active) / kRobots;
    }
    w.active_share /= seconds;
    for (std::size_t i = 0; i < kRobots; ++i) {
      const double d = s.world().state(i).distance;
      w.distance += d - distance_before[i];
      distance_before[i] = d;
    }
    w.distance /= kRobots;
    out.windows.push_back(w);
  }
  s.stop();
  for (const evo::MedeaTask* m : medea) {
    EXPECT_EQ(m->state(), evo::EvolutionState::kRunning) << m->error();
    out.lifetimes += m->counts().lifetimes;
    out.malformed += m->counts().malformed;
    out.controllers += m->controllers_created();
  }
  out.radio = (*radio)->counts();
  out.final_genes = medea[0]->genome().values;
  session.reset();  // empties the nodes while the radio still exists
  return out;
}

double mean_share(const std::vector<Window>& w, std::size_t from, std::size_t to) {
  double sum = 0;
  for (std::size_t i = from; i < to; ++i) sum += w[i].active_share;
  return sum / static_cast<double>(to - from);
}
double mean_distance(const std::vector<Window>& w, std::size_t from, std::size_t to) {
  double sum = 0;
  for (std::size_t i = from; i < to; ++i) sum += w[i].distance;
  return sum / static_cast<double>(to - from);
}

// Early: the first two windows (0-4 min); late: the last five (30-40 min). Measured (range 35 cm,
// lifetime 12 s, sigma 0.2), active share and cm per robot per 2 min, early -> late:
//   seed 1: 0.69 -> 0.91,  582 -> 1373     seed 4: 0.77 -> 0.94,  859 -> 1506
//   seed 2: 0.87 -> 0.98, 1130 -> 1723     seed 5: 0.81 -> 0.96,  997 -> 1531
//   seed 3: 0.77 -> 0.83,  772 ->  846     seed 6: 0.68 -> 0.92,  659 -> 1411
// Over seeds 1-3: share 0.78 -> 0.91, distance 828 -> 1314 cm. Asserted: every seed rises in both,
// and over the three seeds the share rises by at least 0.06 and the distance by at least 25%.
// (Range 25 cm is harsher: with sigma 0.2 one seed of six died out, every robot inactive for good,
// which mEDEA without a restart allows: nobody left to broadcast. Range 50 cm: nearly everyone
// hears someone from the start, share 0.9+ throughout, the rise is lost in the noise.)
TEST(MedeaScenario, ActiveShareAndDistanceRiseOverTime) {
  SYMB_SKIP_UNDER_TSAN();
#ifdef SYMB_SANITIZER
  // The sanitizer builds look for memory errors and undefined behaviour: one seed for 8 minutes
  // runs every path of the 40 (each robot lives 40 lifetimes, broadcasts, adopts and mutates
  // genomes), and its counts are checked. The rise over time, a claim about the whole 40 minutes,
  // is the release build's to check.
  constexpr int kSeeds = 1;
  constexpr auto kRun = 8min;
#else
  constexpr int kSeeds = 3;
  constexpr auto kRun = 40min;
#endif
  constexpr bool kWholeRun = kRun == 40min;
  double share_early = 0, share_late = 0, dist_early = 0, dist_late = 0;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const SwarmRun r = run_swarm(seed, kRun, 2min);
    ASSERT_EQ(r.windows.size(), static_cast<std::size_t>(kRun / 2min));
    std::printf("seed %llu: windows (active share, cm per robot):", static_cast<unsigned long long>(seed));
    for (const Window& w : r.windows) std::printf(" (%.2f, %.0f)", w.active_share, w.distance);
    std::printf(
        "\n  radio: %llu transmitted, %llu delivered, %llu out of range, %llu dropped; %llu lifetimes, %llu "
        "controllers\n",
        static_cast<unsigned long long>(r.radio.transmitted), static_cast<unsigned long long>(r.radio.delivered),
        static_cast<unsigned long long>(r.radio.out_of_range), static_cast<unsigned long long>(r.radio.dropped),
        static_cast<unsigned long long>(r.lifetimes), static_cast<unsigned long long>(r.controllers));
    EXPECT_EQ(r.malformed, 0u);
    EXPECT_GT(r.radio.delivered, 0u);
    EXPECT_EQ(r.radio.dropped, 0u);
    EXPECT_EQ(r.lifetimes, kRobots * static_cast<std::uint64_t>(kRun / 12s));  // 12 s each
    if (!kWholeRun) continue;
    const double se = mean_share(r.windows, 0, 2), sl = mean_share(r.windows, 15, 20);
    const double de = mean_distance(r.windows, 0, 2), dl = mean_distance(r.windows, 15, 20);
    std::printf("  active share %.2f -> %.2f, distance %.0f -> %.0f cm per robot per 2 min\n", se, sl, de, dl);
    EXPECT_GT(sl, se);
    EXPECT_GT(dl, de);
    share_early += se / kSeeds, share_late += sl / kSeeds;
    dist_early += de / kSeeds, dist_late += dl / kSeeds;
  }
  if (!kWholeRun) return;
  std::printf("over the seeds: active share %.2f -> %.2f, distance %.0f -> %.0f cm\n", share_early, share_late,
              dist_early, dist_late);
  EXPECT_GE(share_late, share_early + 0.06);
  EXPECT_GE(dist_late, 1.25 * dist_early);
}

TEST(MedeaScenario, SameSeedSameRun) {
  SYMB_SKIP_UNDER_TSAN();
  const SwarmRun a = run_swarm(4, 4min, 2min), b = run_swarm(4, 4min, 2min), c = run_swarm(5, 4min, 2min);
  ASSERT_EQ(a.windows.size(), 2u);
  for (std::size_t i = 0; i < a.windows.size(); ++i) {
    EXPECT_EQ(a.windows[i].active_share, b.windows[i].active_share);
    EXPECT_EQ(a.windows[i].distance, b.windows[i].distance);
  }
  EXPECT_EQ(a.final_genes, b.final_genes);
  EXPECT_EQ(a.radio.delivered, b.radio.delivered);
  EXPECT_NE(a.final_genes, c.final_genes);
}

// --- the same swarm declared in a scenario file ------------------------------------------------

struct FileRun {
  std::vector<std::vector<float>> active;  // per robot: the "active" probe of each lifetime
  std::size_t radio_tasks = 0;
  RadioCounts radio;
  std::vector<double> distance;  // cm per robot
};

// scenarios/medea_swarm.yaml as `symb run` runs it: world.radio gives every robot a `radio`
// device task, the `medea` task finds it by name.
FileRun run_file(std::uint64_t seed, kernel::Duration duration) {
  FileRun out;
  auto scenario = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml");
  EXPECT_TRUE(scenario.ok()) << (scenario ? "" : scenario.error());
  if (!scenario) return out;
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto session = ScenarioSession::create(*scenario, executor, options);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return out;
  ScenarioSession& s = **session;
  EXPECT_NE(s.radio(), nullptr);
  out.active.resize(s.robot_count());
  for (std::size_t i = 0; i < s.robot_count(); ++i) {
    os::Node& node = s.robot(i).node();
    out.radio_tasks += node.find(std::string(kRadioTaskName)) ? 1 : 0;
    std::vector<float>* mine = &out.active[i];
    node.set_probe_sink([mine](const os::ProbeSample& p) {
      if (p.channel == "active" && !p.values.empty()) mine->push_back(p.values[0]);
    });
  }
  s.start();
  executor.run_for(duration);
  s.stop();
  if (s.radio() != nullptr) out.radio = s.radio()->counts();
  for (std::size_t i = 0; i < s.robot_count(); ++i) out.distance.push_back(s.world().state(i).distance);
  return out;
}

TEST(MedeaScenario, RunsFromTheScenarioFileWithARadioPerRobot) {
  SYMB_SKIP_UNDER_TSAN();
  const FileRun a = run_file(1, 4min), b = run_file(1, 4min), c = run_file(2, 4min);
  ASSERT_EQ(a.active.size(), kRobots);
  EXPECT_EQ(a.radio_tasks, kRobots);
  std::size_t lifetimes = 0;
  double active = 0;
  for (const auto& r : a.active) {
    lifetimes += r.size();
    for (float v : r) active += v;
  }
  EXPECT_EQ(lifetimes, kRobots * 20);  // 4 min / 12 s
  // Genomes travelled: the radio delivered, some robots stayed active, and they drove.
  EXPECT_GT(a.radio.delivered, 1000u);
  EXPECT_EQ(a.radio.dropped, 0u);
  EXPECT_GT(active, 0.5 * static_cast<double>(lifetimes));
  double travelled = 0;
  for (double d : a.distance) travelled += d;
  EXPECT_GT(travelled / kRobots, 100.0);
  // Same seed, same run; another seed, another.
  EXPECT_EQ(a.active, b.active);
  EXPECT_EQ(a.distance, b.distance);
  EXPECT_EQ(a.radio.delivered, b.radio.delivered);
  EXPECT_NE(a.distance, c.distance);
}

// world.radio is checked where it is written; a hook to `radio` needs it.
TEST(MedeaScenario, RadioMistakesAreReportedWhereTheyAre) {
  const std::string head = "name: t\nworld:\n  arena: {width: 100, height: 100}\n";
  const std::string robot = "robots:\n  - name: r\n    start: {x: 50, y: 50, heading: 0}\n";
  const auto fails = [](const std::string& yaml, const std::string& where, const std::string& what) {
    auto sc = parse_scenario(yaml, "t.yaml");
    ASSERT_FALSE(sc.ok()) << yaml;
    EXPECT_EQ(sc.error().rfind("t.yaml:" + where + ": ", 0), 0u) << sc.error();
    EXPECT_NE(sc.error().find(what), std::string::npos) << sc.error();
  };
  fails(head + "  radio: {range: -3}\n" + robot, "4:18", "radio range");
  fails(head + "  radio: {range: 30, power: 2}\n" + robot, "4:22", "power");
  fails(head + "  radio: 30\n" + robot, "4:10", "radio is {range: CM");
  fails(head + robot + "    hooks: [radio -> wheels]\n", "7:13", "only in a world that declares one");
  fails(head + "  radio: {range: 30}\n" + robot + "    tasks:\n      - {name: radio, type: mlp}\n", "9:9", "is taken");
  auto ok = parse_scenario(head + "  radio: {range: 30, max_message_bytes: 256}\n" + robot +
                               "    tasks:\n      - {name: echo, type: mlp}\n    hooks: [radio -> echo]\n",
                           "t.yaml");
  ASSERT_TRUE(ok.ok()) << ok.error();
  ASSERT_TRUE(ok->world.radio.has_value());
  EXPECT_EQ(ok->world.radio->range, 30);
  EXPECT_EQ(ok->world.radio->max_message_bytes, 256u);
}

}  // namespace
}  // namespace symb::sim
