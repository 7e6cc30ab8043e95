// The hormone controller's tasks in nodes under virtual time: the whole network in one task and
// one task per compartment (plus the mixer) give the same levels step by step and the same wheel
// commands; two nodes (two robots) whose compartments diffuse into each other through a bridge
// task on each node give the levels of the joined network in one task; the task types, their
// parameters and located creation errors; bad messages are ignored.
#include "symb/control/ahhs/ahhs_task.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

#include <gtest/gtest.h>

#include "symb/control/ahhs/ahhs_compartment_task.hpp"
#include "symb/control/ahhs/ahhs_task_types.hpp"
#include "symb/control/ahhs/parser.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;

// Four compartments in a ring with a chord, three hormones, every kind of rule.
constexpr const char* kNetwork = R"(compartments 4
link 0 1
link 1 2
link 2 3
link 3 0
link 0 2
hormone a base 0.01 decay 0.05 diffusion 0.2
hormone b base 0 decay 0.1 diffusion 0.05 min -1 max 1
hormone c base 0.02 decay 0.01 diffusion 0
sensor 0 in 0
sensor 1 in 1
sensor 2 in 3
actuator 0 in 2
actuator 1 in 3
rule sensor 0 -> a centre 1 width 1 fixed 0.3
rule sensor 1 -> b centre 0.5 width 0.5 fixed 0.1 dependent -0.5
rule sensor 2 -> c centre 0 width 1 fixed 0.05 dependent 0.2
rule hormone a -> b centre 0.5 width 0.5 fixed 0.05 dependent 0.3
rule nonlinear b -> c centre 0 width 1 dependent 0.7 in 1
rule hormone c -> a centre 1 width 1 fixed -0.1
rule actuator a -> 0 centre 1 width 1 fixed 1 dependent -0.5
rule actuator b -> 1 centre 0 width 1 fixed 0.5 dependent 1
rule actuator c -> 1 centre 1 width 1 fixed -1
)";

// Sensor vectors that depend only on the tick count: the same on every node.
class Sensor : public os::Task {
 protected:
  void on_tick() override {
    const float t = static_cast<float>(++n_);
    send(0, {std::fmod(0.37f * t, 1.0f) * 4505, std::fmod(0.11f * t + 0.5f, 1.0f) * 4505,
             std::fmod(0.73f * t, 1.0f) * 4505});
  }

 private:
  int n_ = 0;
};

class AhhsRecorder : public os::Task {
 public:
  std::vector<std::vector<float>> got;

 protected:
  void on_message(const os::Message& m) override { got.emplace_back(m.numbers().begin(), m.numbers().end()); }
};

// Carries compartment level messages (port 1) between two nodes: what a local compartment sends
// is posted to the peer bridge on the other node; what the peer posts is sent to the local
// compartments. (On robots, the same two halves sit on each side of the robot-to-robot link.)
class Bridge : public os::Task {
 public:
  void connect(os::Node* other, os::TaskId peer) {
    other_ = other;
    peer_ = peer;
  }
  int carried = 0;

 protected:
  void on_message(const os::Message& m) override {
    if (m.source.valid()) {
      os::Message out = m;
      out.source = {};
      if (other_->post(peer_, out, os::QueuePolicy::kKeepNewest)) ++carried;
    } else {
      send(kAhhsLevelsPort, m.payload);
    }
  }

 private:
  os::Node* other_ = nullptr;
  os::TaskId peer_;
};

// Probe samples per task and channel, in order.
struct Probes {
  std::mutex mu;
  std::map<std::string, std::map<std::string, std::vector<std::vector<float>>>> by_task;
  os::ProbeSink sink() {
    return [this](const os::ProbeSample& s) {
      std::lock_guard lock(mu);
      by_task[std::string(s.task)][std::string(s.channel)].emplace_back(s.values.begin(), s.values.end());
    };
  }
};

ControlResources inline_networks() {
  ControlResources r;
  r.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
    if (ref == "ring") return std::string(kNetwork);
    if (ref == "chain") return std::string(kNetwork) + "";
    if (ref == "broken")
      return std::string("compartments 2\nhormone h\nlink 0 1\nrule hormone h -> x centre 0 width 1\n");
    if (ref == "two_hormone") {
      std::ifstream f(std::string(SYMB_SHIPPED_SCENARIO_DIR) + "/ahhs/two_hormone.ahhs");
      std::stringstream s;
      s << f.rdbuf();
      return s.str();
    }
    return kernel::Error{"no such network"};
  };
  return r;
}

kernel::Result<os::TaskId> create(os::Node& node, std::string_view type, std::string name, std::string_view params) {
  auto a = os::parse_param_assignments(params);
  if (!a) return kernel::Error{a.error()};
  return node.create(type, std::move(name), *a);
}

struct AhhsRig {
  os::TaskTypeRegistry registry;
  kernel::VirtualTimeExecutor ex;
  AhhsRig() { EXPECT_TRUE(register_control_task_types(registry, inline_networks())); }
};

TEST(AhhsTasks, OneTaskAndOneTaskPerCompartmentGiveTheSameLevelsAndCommands) {
  AhhsRig rig;
  os::Node node(rig.ex, {.name = "bot", .types = &rig.registry});
  Probes probes;
  node.set_probe_sink(probes.sink());
  auto sensor = *node.create("ir", std::make_unique<Sensor>(), {.priority = 1, .period = 30ms});
  auto whole_rec = std::make_unique<AhhsRecorder>();
  auto split_rec = std::make_unique<AhhsRecorder>();
  AhhsRecorder* whole_out = whole_rec.get();
  AhhsRecorder* split_out = split_rec.get();
  auto w_rec = *node.create("whole_wheels", std::move(whole_rec), {.queue_capacity = 64});
  auto s_rec = *node.create("split_wheels", std::move(split_rec), {.queue_capacity = 64});

  auto whole = create(node, "ahhs", "whole", "network=ring actuator_scale=250");
  ASSERT_TRUE(whole) << whole.error();
  ASSERT_TRUE(node.hook(sensor, *whole));
  ASSERT_TRUE(node.hook(*whole, w_rec));

  auto mixer = create(node, "ahhs_mixer", "mixer", "actuators=2 actuator_scale=250");
  ASSERT_TRUE(mixer) << mixer.error();
  ASSERT_TRUE(node.hook(*mixer, s_rec));
  std::vector<os::TaskId> comps;
  for (int c = 0; c < 4; ++c) {
    auto id =
        create(node, "ahhs_compartment", "c" + std::to_string(c), "network=ring compartment=" + std::to_string(c));
    ASSERT_TRUE(id) << id.error();
    comps.push_back(*id);
    ASSERT_TRUE(node.hook(sensor, *id, {.port = 0}));
    ASSERT_TRUE(node.hook(*id, *mixer, {.port = 2}));
  }
  for (auto [a, b] : {std::pair{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}}) {
    ASSERT_TRUE(node.hook(comps[a], comps[b], {.port = 1}));
    ASSERT_TRUE(node.hook(comps[b], comps[a], {.port = 1}));
  }
  rig.ex.run_for(3s);  // 100 steps

  for (int c = 0; c < 4; ++c) {
    const std::string ch = "hormones/c" + std::to_string(c);
    const auto& one = probes.by_task["whole"][ch];
    const auto& own = probes.by_task["c" + std::to_string(c)][ch];
    ASSERT_EQ(one.size(), 100u) << ch;
    ASSERT_EQ(own.size(), one.size()) << ch;
    for (std::size_t t = 0; t < one.size(); ++t) ASSERT_EQ(own[t], one[t]) << ch << " step " << t;
  }
  // The levels really moved (not a trivially equal pair of constant runs).
  EXPECT_NE(probes.by_task["whole"]["hormones/c1"].front(), probes.by_task["whole"]["hormones/c1"].back());
  ASSERT_EQ(whole_out->got.size(), 100u);
  ASSERT_EQ(split_out->got.size(), whole_out->got.size());
  for (std::size_t t = 0; t < whole_out->got.size(); ++t) ASSERT_EQ(split_out->got[t], whole_out->got[t]) << t;
  for (const auto& cmd : whole_out->got)
    for (float v : cmd) EXPECT_LE(std::abs(v), 250.0f);
  EXPECT_EQ(probes.by_task["whole"]["actuators"].size(), 100u);
  node.clear();
}

TEST(AhhsTasks, TwoRobotsJoinedThroughABridgeDiffuseAsOneNetwork) {
  AhhsRig rig;
  os::Node a(rig.ex, {.name = "robot_a", .seed = 1, .types = &rig.registry});
  os::Node b(rig.ex, {.name = "robot_b", .seed = 2, .types = &rig.registry});
  os::Node ref(rig.ex, {.name = "reference", .seed = 3, .types = &rig.registry});
  Probes pa, pb, pref;
  a.set_probe_sink(pa.sink());
  b.set_probe_sink(pb.sink());
  ref.set_probe_sink(pref.sink());

  // Reference: the joined network in one task.
  auto rs = *ref.create("ir", std::make_unique<Sensor>(), {.priority = 1, .period = 30ms});
  auto whole = create(ref, "ahhs", "whole", "network=ring");
  ASSERT_TRUE(whole) << whole.error();
  ASSERT_TRUE(ref.hook(rs, *whole));

  // Robot A holds compartments 0 and 1, robot B 2 and 3; links 1-2, 3-0 and 0-2 cross robots.
  auto bridge_a_task = std::make_unique<Bridge>(), bridge_b_task = std::make_unique<Bridge>();
  Bridge* bridge_a = bridge_a_task.get();
  Bridge* bridge_b = bridge_b_task.get();
  auto ba = *a.create("bridge", std::move(bridge_a_task), {.queue_capacity = 32});
  auto bb = *b.create("bridge", std::move(bridge_b_task), {.queue_capacity = 32});
  bridge_a->connect(&b, bb);
  bridge_b->connect(&a, ba);
  std::map<int, os::TaskId> ids;
  for (auto [node, range] : {std::pair{&a, std::pair{0, 1}}, {&b, {2, 3}}}) {
    auto ir = *node->create("ir", std::make_unique<Sensor>(), {.priority = 1, .period = 30ms});
    const os::TaskId bridge = node == &a ? ba : bb;
    for (int c = range.first; c <= range.second; ++c) {
      auto id =
          create(*node, "ahhs_compartment", "c" + std::to_string(c), "network=ring compartment=" + std::to_string(c));
      ASSERT_TRUE(id) << id.error();
      ids[c] = *id;
      ASSERT_TRUE(node->hook(ir, *id, {.port = 0}));
      ASSERT_TRUE(node->hook(*id, bridge, {.port = 1}));
      ASSERT_TRUE(node->hook(bridge, *id, {.port = 1}));
    }
    // Neighbours on the same robot talk directly.
    const int lo = range.first, hi = range.second;
    ASSERT_TRUE(node->hook(ids[lo], ids[hi], {.port = 1}));
    ASSERT_TRUE(node->hook(ids[hi], ids[lo], {.port = 1}));
  }
  rig.ex.run_for(3s);

  EXPECT_GT(bridge_a->carried, 100);
  EXPECT_GT(bridge_b->carried, 100);
  for (int c = 0; c < 4; ++c) {
    const std::string ch = "hormones/c" + std::to_string(c);
    auto& robot = c < 2 ? pa : pb;
    const auto& got = robot.by_task["c" + std::to_string(c)][ch];
    const auto& want = pref.by_task["whole"][ch];
    ASSERT_EQ(want.size(), 100u);
    ASSERT_EQ(got.size(), want.size()) << ch;
    for (std::size_t t = 0; t < want.size(); ++t) ASSERT_EQ(got[t], want[t]) << ch << " step " << t;
  }
  a.clear();
  b.clear();
  ref.clear();
}

TEST(AhhsTasks, ACompartmentWhoseNeighboursNeverAnswerStillSteps) {
  auto n = ahhs::parse_network(kNetwork);
  ASSERT_TRUE(n.ok()) << n.error();
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot"});
  Probes probes;
  node.set_probe_sink(probes.sink());
  auto ir = *node.create("ir", std::make_unique<Sensor>(), {.priority = 1, .period = 30ms});
  auto task = AhhsCompartmentTask::create(*n, 0);
  ASSERT_TRUE(task.ok()) << task.error();
  AhhsCompartmentTask* c0 = task.value().get();
  ASSERT_TRUE(node.hook(ir, *node.create("c0", std::move(task).value())));
  ex.run_for(300ms);  // 10 sensor vectors; neighbours 1, 2 and 3 are not there
  const AhhsCompartmentStats s = c0->stats();
  EXPECT_EQ(s.steps, 10u);
  EXPECT_EQ(s.exchanges, 0u);
  EXPECT_EQ(s.missed_exchanges, 27u) << "steps 1 to 9 were finished by the next vector, 3 neighbours each";
  EXPECT_EQ(probes.by_task["c0"]["hormones/c0"].size(), 9u);
  EXPECT_EQ(c0->levels(), probes.by_task["c0"]["hormones/c0"].back());
  node.clear();
}

TEST(AhhsTasks, TypesSchemasAndLocatedCreationErrors) {
  AhhsRig rig;
  for (const char* name : {"ahhs", "ahhs_compartment", "ahhs_mixer"}) {
    const os::TaskType* t = rig.registry.find(name);
    ASSERT_NE(t, nullptr) << name;
    EXPECT_FALSE(t->doc.empty());
    EXPECT_EQ(t->defaults.priority, 2);
  }
  EXPECT_NE(rig.registry.find("ahhs")->param("network"), nullptr);
  EXPECT_NE(rig.registry.find("ahhs")->param("description"), nullptr);
  EXPECT_NE(rig.registry.find("ahhs_compartment")->param("compartment"), nullptr);
  EXPECT_EQ(std::get<double>(rig.registry.find("ahhs")->param("sensor_range")->default_value), 4505.0);

  os::Node node(rig.ex, {.name = "bot", .types = &rig.registry});
  auto e = create(node, "ahhs", "c", "network=broken");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("network 'broken': 4:19: no hormone named 'x'"), std::string::npos) << e.error();
  e = create(node, "ahhs", "c", "network=missing");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("network 'missing': no such network"), std::string::npos) << e.error();
  e = create(node, "ahhs", "c", "");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("exactly one"), std::string::npos) << e.error();
  e = create(node, "ahhs", "c", "network=ring actuator_scale=600");
  EXPECT_FALSE(e) << "actuator_scale is at most 500";
  e = create(node, "ahhs", "c", "network=ring sensor_range=-1");
  EXPECT_FALSE(e);
  e = create(node, "ahhs_compartment", "c", "network=ring compartment=4");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("compartment 4 is not in the network"), std::string::npos) << e.error();
  e = create(node, "ahhs_mixer", "m", "actuators=0");
  EXPECT_FALSE(e);
  std::vector<os::ParamAssignment> both = {{"network", "ring", 1}, {"description", "compartments 1; hormone h", 1}};
  e = node.create("ahhs", "c", both);
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("exactly one"), std::string::npos) << e.error();
  std::vector<os::ParamAssignment> bad_inline = {{"description", "compartments 1; hormone h decay 2", 1}};
  e = node.create("ahhs", "c", bad_inline);
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("description: 1:33: decay must be 0 to 1"), std::string::npos) << e.error();
  EXPECT_EQ(node.task_count(), 0u);

  // Inline, and runtime parameters: the scale changes, the network does not.
  std::vector<os::ParamAssignment> inline_net = {
      {"description",
       "compartments 1; hormone go base 1; actuator 0 in 0; rule actuator go -> 0 centre 1 width 1 fixed 1", 1}};
  auto ok = node.create("ahhs", "c", inline_net);
  ASSERT_TRUE(ok) << ok.error();
  auto rec_task = std::make_unique<AhhsRecorder>();
  AhhsRecorder* rec = rec_task.get();
  ASSERT_TRUE(node.hook(*ok, *node.create("rec", std::move(rec_task))));
  auto poster = [&](std::vector<float> v, os::Port port = 0) {
    os::Message m;
    m.port = port;
    m.payload.assign(v);
    return node.post(*ok, m);
  };
  ASSERT_TRUE(poster({}));
  rig.ex.run_for(1ms);
  ASSERT_TRUE(poster({}));
  rig.ex.run_for(1ms);
  ASSERT_EQ(rec->got.size(), 2u);
  EXPECT_EQ(rec->got[1], std::vector<float>{300.0f}) << "go saturates at 1, times the default scale";
  EXPECT_TRUE(node.set_parameter(*ok, "actuator_scale", "100"));
  rig.ex.run_for(1ms);
  ASSERT_TRUE(poster({}));
  rig.ex.run_for(1ms);
  EXPECT_EQ(rec->got.back(), std::vector<float>{100.0f});
  ASSERT_TRUE(node.set_parameter(*ok, "network", "ring"));
  rig.ex.run_for(1ms);
  bool refused = false;
  for (const auto& entry : node.log().since(0))
    refused = refused || entry.text.find("keeps its network") != std::string::npos;
  EXPECT_TRUE(refused);
  node.clear();
}

TEST(AhhsTasks, BadMessagesAreIgnoredAndCounted) {
  auto n = ahhs::parse_network(kNetwork);
  ASSERT_TRUE(n.ok()) << n.error();
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot"});
  auto whole_task = AhhsTask::create(*n);
  ASSERT_TRUE(whole_task.ok());
  AhhsTask* whole = whole_task.value().get();
  auto wid = *node.create("whole", std::move(whole_task).value(), {.queue_capacity = 32});
  auto comp_task = AhhsCompartmentTask::create(*n, 0);
  ASSERT_TRUE(comp_task.ok());
  AhhsCompartmentTask* comp = comp_task.value().get();
  auto cid = *node.create("c0", std::move(comp_task).value(), {.queue_capacity = 32});
  auto mixer_task = AhhsMixerTask::create(2);
  ASSERT_TRUE(mixer_task.ok());
  AhhsMixerTask* mixer = mixer_task.value().get();
  auto mid = *node.create("mixer", std::move(mixer_task).value(), {.queue_capacity = 32});
  auto rec_task = std::make_unique<AhhsRecorder>();
  AhhsRecorder* rec = rec_task.get();
  auto rid = *node.create("rec", std::move(rec_task), {.queue_capacity = 32});
  ASSERT_TRUE(node.hook(wid, rid));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto post = [&](os::TaskId to, std::vector<float> v, os::Port port) {
    os::Message m;
    m.port = port;
    m.payload.assign(v);
    ASSERT_TRUE(node.post(to, m));
  };
  post(wid, {1, 2}, 0);           // too short: the network reads 3 sensors
  post(wid, {1, nan, 3}, 0);      // not finite
  post(wid, {1, 2, 3}, 1);        // wrong port
  post(wid, {1, 2, 3, 4}, 0);     // good (longer is fine)
  post(cid, {0, 0.5f}, 1);        // wrong size for 3 hormones
  post(cid, {1.5f, 0, 0, 0}, 1);  // not a whole id
  post(cid, {0, 0, 0, nan}, 1);   // not finite
  post(cid, {9, 0, 0, 0}, 1);     // not a neighbour (4 compartments, id 9): foreign, ignored
  post(mid, {0, 0.5f, 7, 1}, 2);  // actuator 7 does not exist
  post(mid, {0, 0.5f}, 1);        // wrong port
  post(mid, {1, 2}, 2);           // ok: actuator 1 at 2 clamps to 1
  post(mid, {0, -0.5f}, 2);       // completes the round
  ex.run_for(1ms);
  EXPECT_EQ(whole->stats().ignored, 3u);
  EXPECT_EQ(whole->stats().steps, 1u);
  ASSERT_EQ(rec->got.size(), 1u);
  for (float v : rec->got[0]) EXPECT_TRUE(std::isfinite(v));
  EXPECT_EQ(comp->stats().ignored, 3u);
  EXPECT_EQ(comp->stats().foreign_levels, 1u);
  EXPECT_EQ(mixer->sent(), 1u);
  EXPECT_EQ(mixer->last(), (std::vector<float>{-0.5f, 1.0f}));
  node.clear();
}

}  // namespace
}  // namespace symb::control
