// Self-assembly: the docking beacon's geometry against positions computed here, and the shipped
// scenarios/self_assembly.yaml over five seeds (the seekers' starts drawn from the seed, as the
// exploration in docs/organism.md did): three free modules dock into one chain within the stated
// time in at least 4 of 5 seeds, and the organism then crawls forward. The figures beside the
// bounds were measured once with this file (release build); SYMB_SELF_ASSEMBLY_PRINT=1 prints them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/mujoco/mujoco_devices.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/mujoco/world_access.hpp"
#include "symb/sim/scenario.hpp"

#include "support/measured.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;
constexpr double kSaPi = std::numbers::pi;

double sa_wrap(double a) { return std::remainder(a, 2 * kSaPi); }

// The connector's centre, horizontal, from the module's start pose and its kind (straight hinge,
// at rest: what the world shows before any step).
std::array<double, 2> sa_connector_at(const ModuleSpec& m, std::size_t c) {
  const auto& p = m.kind.connectors[c].position;
  return {m.start.x + std::cos(m.start.yaw) * p[0] - std::sin(m.start.yaw) * p[1],
          m.start.y + std::sin(m.start.yaw) * p[0] + std::cos(m.start.yaw) * p[1]};
}

TEST(SelfAssemblyBeacon, AFrontSeesTheNearestOpenBackWithTheBearingAndHeadingComputedFromThePoses) {
  const ModuleKind kind = standard_kind();
  // m1 behind m0 (which faces +x), looking roughly at m0's back; m2 further away, also in view.
  std::vector<ModuleSpec> specs = {
      {"m0", kind, {0, 0, 0}}, {"m1", kind, {-0.4, 0.1, 0.2}}, {"m2", kind, {0.3, 0.5, -2.0}}};
  auto made = MujocoWorld::make(specs, {});
  ASSERT_TRUE(made.ok()) << made.error();
  MujocoWorld& w = made.value();
  const std::size_t front = *w.find_connector(1, "front"), back = *w.find_connector(0, "back");
  const auto from = sa_connector_at(specs[1], front), to = sa_connector_at(specs[0], back);
  const double d = std::hypot(to[0] - from[0], to[1] - from[1]);
  const double bearing = sa_wrap(std::atan2(to[1] - from[1], to[0] - from[0]) - 0.2);
  const double heading = sa_wrap(0.0 - 0.2);  // m0's back faces -x; reversed, +x
  const auto b = w.beacon(1, front);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->module, 0u);
  EXPECT_EQ(b->connector, back);
  EXPECT_NEAR(b->distance, d, 1e-4);
  EXPECT_NEAR(b->bearing, bearing, 1e-4);
  EXPECT_NEAR(b->heading, heading, 1e-4);
  // Closed: m0's back is no target; m2's back is not in m1's view (behind m1's face cone).
  w.set_open(0, back, false);
  const auto b2 = w.beacon(1, front);
  if (b2) {
    EXPECT_EQ(b2->module, 2u);
    const auto at = sa_connector_at(specs[2], back);
    EXPECT_NEAR(b2->distance, std::hypot(at[0] - from[0], at[1] - from[1]), 1e-4);
  }
  // A back never sees another back, and nothing sees its own module.
  w.set_open(0, back, true);
  const auto bb = w.beacon(1, back);
  if (bb) {
    EXPECT_NE(w.module(bb->module).kind.connectors[bb->connector].face, Face::kBack);
  }
}

TEST(SelfAssemblyBeacon, NothingBeyondTheRangeOrOutsideEitherCone) {
  const ModuleKind kind = standard_kind();
  const auto seen = [&](StartPose seeker) {
    auto made = MujocoWorld::make({{"m0", kind, {0, 0, 0}}, {"m1", kind, seeker}}, {});
    EXPECT_TRUE(made.ok()) << made.error();
    return made.ok() && made.value().beacon(1, *made.value().find_connector(1, "front")).has_value();
  };
  EXPECT_TRUE(seen({-0.9, 0, 0}));              // 0.9 - 0.1 = 0.8 m, straight behind
  EXPECT_FALSE(seen({-1.2, 0, 0}));             // 1.1 m: beyond kBeaconRange
  EXPECT_TRUE(seen({-0.4, 0, 1.7}));            // target 97 deg off my normal: inside 108
  EXPECT_FALSE(seen({-0.4, 0, 2.0}));           // 115 deg off: outside kBeaconCone
  EXPECT_TRUE(seen({-0.2, 0.9 * 0.15, -0.6}));  // within 81 deg of the target's normal
  EXPECT_FALSE(seen({-0.08, 0.4, -1.4}));       // about 83 deg off the target's normal
}

TEST(SelfAssemblyBeacon, TheConnectorDeviceReadsStateOpenPeerThenTheBeacon) {
  const ModuleKind kind = standard_kind();
  auto made = MujocoWorld::make({{"m0", kind, {0, 0, 0}}, {"m1", kind, {-0.5, 0, 0}}}, {});
  ASSERT_TRUE(made.ok()) << made.error();
  MujocoWorld& w = made.value();
  const std::size_t front = *w.find_connector(1, "front");
  ASSERT_EQ(MujocoConnector::channel_specs().size(), kConnectorChannels);
  auto access = std::make_shared<WorldAccess>(w);
  MujocoConnector device("connector_front", access, 1, front);
  // Straight behind, face to face: 0.5 m between the modules, 0.4 m between the connectors.
  ConnectorReading r = device.reading(w);
  EXPECT_EQ(r[0], 0.0f);
  EXPECT_EQ(r[1], 1.0f);
  EXPECT_EQ(r[2], -1.0f);
  EXPECT_NEAR(r[3], 0.4, 1e-4);
  EXPECT_NEAR(r[4], 0, 1e-6);
  EXPECT_NEAR(r[5], 0, 1e-6);
  w.set_open(0, *w.find_connector(0, "back"), false);
  r = device.reading(w);
  EXPECT_EQ(r[3], -1.0f);
  EXPECT_EQ(r[4], 0.0f);
  EXPECT_EQ(r[5], 0.0f);
  access->close();
}

struct SaRun {
  std::optional<double> assembled;  // s, virtual
  double moved = 0;                 // m the organism's centre moved along +x after assembling
  double wall = 0;                  // s
};

constexpr auto kSaLimit = 60s;  // the stated time to assemble
constexpr auto kSaSettle = 5s;  // after assembling: the heartbeats complete, the wave forms
constexpr auto kSaCrawl = 10s;  // then the crawl measured

// The seekers' starts from the seed: within the seed's beacon field (behind it, where its back
// connector's beacon can be seen once a seeker turns to it): uniform in x -0.75..-0.2 m, y
// -0.45..0.45 m, 0.2 m apart, headings uniform. (From anywhere around the seed, the search's random
// walk finds the field too seldom: docs/organism.md.)
void sa_place(Scenario& sc, std::uint64_t seed) {
  kernel::RandomStream rnd(seed);
  std::vector<std::array<double, 2>> placed = {{0, 0}};
  for (std::size_t i = 1; i < sc.robots.size(); ++i) {
    for (;;) {
      // SYMB_SELF_ASSEMBLY_ANYWHERE=1: anywhere around the seed instead (the exploration's
      // [-0.6, 0.6]^2, 0.25 m from the seed), to measure the search.
      const bool anywhere = std::getenv("SYMB_SELF_ASSEMBLY_ANYWHERE") != nullptr;
      const double x = anywhere ? rnd.uniform(-0.6, 0.6) : rnd.uniform(-0.75, -0.2);
      const double y = anywhere ? rnd.uniform(-0.6, 0.6) : rnd.uniform(-0.45, 0.45);
      bool ok = !anywhere || std::hypot(x, y) > 0.25;
      for (const auto& p : placed) ok = ok && std::hypot(x - p[0], y - p[1]) > 0.2;
      if (!ok) continue;
      const double yaw = rnd.uniform(-kSaPi, kSaPi);
      placed.push_back({x, y});
      sc.robots[i].module_start = {x, y, yaw};
      sc.robots[i].start = {x * 100, y * 100, yaw};
      break;
    }
  }
}

bool sa_one_chain(const MujocoWorld& w) {
  // Union of the docked pairs: one component holding every module.
  std::vector<std::size_t> parent(w.module_count());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i];
    return i;
  };
  for (std::size_t m = 0; m < w.module_count(); ++m)
    for (std::size_t c = 0; c < w.module(m).kind.connectors.size(); ++c)
      if (const auto to = w.docked_to(m, c)) parent[root(m)] = root(to->first);
  for (std::size_t m = 1; m < parent.size(); ++m)
    if (root(m) != root(0)) return false;
  return true;
}

double sa_centre_x(const MujocoWorld& w) {
  double x = 0;
  for (std::size_t m = 0; m < w.module_count(); ++m) x += w.pose(m).position[0];
  return x / static_cast<double>(w.module_count());
}

SaRun sa_run(std::uint64_t seed, bool place = true) {
  SaRun run;
  auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/self_assembly.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  if (!sc.ok()) return run;
  Scenario scenario = *sc;
  if (place) sa_place(scenario, seed);
  kernel::VirtualTimeExecutor ex;
  SessionOptions so;
  so.seed = seed;
  const auto t0 = std::chrono::steady_clock::now();
  auto made = OrganismSession::create(scenario, ex, so);
  EXPECT_TRUE(made.ok()) << made.error();
  if (!made.ok()) return run;
  OrganismSession& s = **made;
  s.start();
  for (auto t = 0s; t < kSaLimit && !run.assembled; t += 1s) {
    ex.run_for(1s);
    s.runner().with_world([&](MujocoWorld& w) {
      if (sa_one_chain(w)) run.assembled = w.time();
      if (std::getenv("SYMB_SELF_ASSEMBLY_DEBUG"))
        for (std::size_t m = 1; m < w.module_count(); ++m) {
          const auto p = w.pose(m);
          const auto b = w.beacon(m, 0);
          std::printf("t=%.0f m%zu at %.3f %.3f yaw %.2f z %.3f hinge %.2f beacon %s %.3f %.2f %.2f state %s\n",
                      w.time(), m, p.position[0], p.position[1], p.yaw(), p.position[2], w.hinge_angle(m),
                      b ? w.module(b->module).name.c_str() : "-", b ? b->distance : -1.0, b ? b->bearing : 0.0,
                      b ? b->heading : 0.0, state_name(w.connector_state(m, 0)));
        }
    });
  }
  if (run.assembled) {
    ex.run_for(kSaSettle);
    double x0 = 0, x1 = 0;
    s.runner().with_world([&](MujocoWorld& w) { x0 = sa_centre_x(w); });
    ex.run_for(kSaCrawl);
    s.runner().with_world([&](MujocoWorld& w) {
      x1 = sa_centre_x(w);
      EXPECT_TRUE(sa_one_chain(w)) << "the chain broke while crawling, seed " << seed;
    });
    run.moved = x1 - x0;
  }
  EXPECT_EQ(s.error(), "");
  if (std::getenv("SYMB_SELF_ASSEMBLY_LOG"))
    for (std::size_t i = 0; i < s.robot_count(); ++i)
      for (const auto& e : s.robot(i).node().log().since(0))
        std::printf("m%zu %.2f %s: %s\n", i, std::chrono::duration<double>(e.time).count(), e.source.c_str(),
                    e.text.c_str());
  run.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (std::getenv("SYMB_SELF_ASSEMBLY_PRINT"))
    for (std::size_t i = 1; i < scenario.robots.size(); ++i)
      std::printf("  %s start {x: %.1f, y: %.1f, heading: %.0f}\n", scenario.robots[i].name.c_str(),
                  scenario.robots[i].start.x, scenario.robots[i].start.y, scenario.robots[i].start.theta * 180 / kSaPi);
  if (std::getenv("SYMB_SELF_ASSEMBLY_PRINT"))
    std::printf("seed %llu: %s %.1f s, moved %.3f m in %lld s, wall %.1f s\n", static_cast<unsigned long long>(seed),
                run.assembled ? "assembled at" : "NOT assembled by",
                run.assembled ? *run.assembled : std::chrono::duration<double>(kSaLimit).count(), run.moved,
                static_cast<long long>(kSaCrawl.count()), run.wall);
  return run;
}

TEST(SelfAssembly, ThreeFreeModulesDockIntoAChainInAtLeastFourOfFiveSeedsThenCrawlForward) {
  // Measured (release build, seeds 1..5): assembled at 22, 22, 11, 16 s (seeds 2..5), seed 1 not
  // within the limit; the centre then moved 0.88, 0.91, 0.96, 0.76 m forward in 10 s.
  int assembled = 0;
  const char* only = std::getenv("SYMB_SELF_ASSEMBLY_SEED");  // to look at one seed's run
  // SYMB_SELF_ASSEMBLY_SEEDS=N measures seeds 1..N instead (the bound below is for five).
  const char* seeds = std::getenv("SYMB_SELF_ASSEMBLY_SEEDS");
  const std::uint64_t last = seeds ? std::strtoull(seeds, nullptr, 10) : 5;
  for (std::uint64_t seed = 1; seed <= last; ++seed) {
    if (only && std::strtoull(only, nullptr, 10) != seed) continue;
    const SaRun r = sa_run(seed);
    if (!r.assembled) continue;
    ++assembled;
    EXPECT_LE(*r.assembled, std::chrono::duration<double>(kSaLimit).count());
    // Forward (+x, the head's way) at about 9 cm/s, the five-module caterpillar's speed
    // (docs/cpg.md): between 0.5 and 1.2 m in the 10 s.
    EXPECT_GT(r.moved, 0.5) << "seed " << seed;
    EXPECT_LT(r.moved, 1.2) << "seed " << seed;
  }
  EXPECT_GE(assembled, 4);
}

TEST(SelfAssembly, TheShippedFileAssemblesFromItsOwnStartsAndSeed) {
  const SaRun r = sa_run(1, false);
  ASSERT_TRUE(r.assembled.has_value());
  // Measured: 22 s (to the second: the chain is checked once a second), then 0.87 m.
  EXPECT_TRUE(testing::near_measured(*r.assembled, 22.0, 10.0));
  EXPECT_GT(r.moved, 0.5);
  EXPECT_LT(r.moved, 1.2);
}

}  // namespace
}  // namespace symb::sim::mujoco
