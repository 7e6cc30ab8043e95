// The network task types in a node under virtual time: a scripted sensor task feeds input vectors,
// a recording task keeps what the network sends. Checks wheel commands against hand-computed
// values, clamping and bad input, runtime genomes (inline and weight files), parameters and
// descriptions rejected with located errors, probes, a two-network circuit, and replacing the
// network while inputs keep coming.
#include "symb/control/network/network_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/virtual_time.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using Vec = std::vector<float>;

using test_support::ms;

// Sends the vector scripted for an instant at its tick of that instant.
class NetworkSensor : public os::Task {
 public:
  void script(Time t, Vec v) { script_[t] = std::move(v); }
  std::vector<Time> sent() const {
    std::lock_guard lock(mu_);
    return sent_;
  }

 protected:
  void on_tick() override {
    if (auto it = script_.find(now()); it != script_.end()) {
      send(0, it->second);
      std::lock_guard lock(mu_);
      sent_.push_back(now());
    }
  }

 private:
  std::map<Time, Vec> script_;
  mutable std::mutex mu_;
  std::vector<Time> sent_;
};

class NetworkRecorder : public os::Task {
 public:
  struct Entry {
    Time time;
    os::Port port;
    Vec values;
  };
  std::vector<Entry> entries() const {
    std::lock_guard lock(mu_);
    return entries_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    entries_.push_back({m.time, m.port, Vec(m.numbers().begin(), m.numbers().end())});
  }

 private:
  mutable std::mutex mu_;
  std::vector<Entry> entries_;
};

const std::map<std::string, std::string, std::less<>> kNetworkFiles{
    {"identity.w", "# two inputs straight to two outputs\n1 0 0\n0 1 0\n"},
    {"swap.w", "0 1 0   1 0 0"},
    {"bad.w", "1 0 0\n0 1 zero\n"},
    {"braitenberg.net", "type mlp\ninputs 2\nlayers 2\ninput_scale 1\noutput_scale 100\nweights\n 1 0 0\n 0 1 0\n"},
    {"broken.net", "type mlp\nlayers 2\nweights 1 2\n  3 x\n"},
};

ControlResources network_files() {
  ControlResources r;
  r.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
    auto it = kNetworkFiles.find(ref);
    if (it == kNetworkFiles.end()) return kernel::Error{"no such file"};
    return it->second;
  };
  return r;
}

struct NetworkRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  NetworkSensor* sensor = nullptr;
  NetworkRecorder* rec = nullptr;
  os::TaskId sensor_id, rec_id;

  NetworkRig() {
    EXPECT_TRUE(register_control_task_types(registry, network_files()).ok());
    node = std::make_unique<os::Node>(ex, os::NodeConfig{.name = "bot", .types = &registry});
    auto s = std::make_unique<NetworkSensor>();
    sensor = s.get();
    sensor_id = *node->create("ir", std::move(s), {.priority = 1, .period = 10ms});
    auto r = std::make_unique<NetworkRecorder>();
    rec = r.get();
    rec_id = *node->create("rec", std::move(r), {.queue_capacity = 64});
  }
  kernel::Result<os::TaskId> create(std::string_view type, std::string name, std::string_view params) {
    auto a = os::parse_param_assignments(params);
    if (!a) return kernel::Error{a.error()};
    return node->create(type, std::move(name), *a);
  }
  os::TaskId network(std::string_view type, std::string name, std::string_view params, bool hook_sensor = true) {
    auto id = create(type, std::move(name), params);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    if (hook_sensor) {
      EXPECT_TRUE(node->hook(sensor_id, *id).ok());
    }
    EXPECT_TRUE(node->hook(*id, rec_id).ok());
    return *id;
  }
  std::vector<NetworkRecorder::Entry> on_port(os::Port p) const {
    std::vector<NetworkRecorder::Entry> out;
    for (auto& e : rec->entries())
      if (e.port == p) out.push_back(e);
    return out;
  }
};

TEST(NetworkTask, PerceptronWheelsFollowHandComputedOutputs) {
  NetworkRig rig;
  rig.network("mlp", "net", "inputs=2 layers=2 input_scale=1 weights=identity.w");
  rig.sensor->script(ms(20), {0.5f, -0.2f});
  rig.sensor->script(ms(40), {2.0f, 0.0f});
  rig.ex.run_until(ms(19));
  EXPECT_TRUE(rig.rec->entries().empty()) << "nothing before the first input";
  rig.ex.run_until(ms(50));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 2u);  // one step per input, output=wheels sends port 0 only
  EXPECT_EQ(cmds[0].time, ms(20));
  EXPECT_EQ(cmds[0].port, 0);
  EXPECT_NEAR(cmds[0].values[0], 500 * std::tanh(0.5), 1e-3);
  EXPECT_NEAR(cmds[0].values[1], 500 * std::tanh(-0.2), 1e-3);
  EXPECT_NEAR(cmds[1].values[0], 500 * std::tanh(2.0), 1e-3);
  EXPECT_NEAR(cmds[1].values[1], 0.0, 1e-6);
}

TEST(NetworkTask, DefaultInputScaleIsTheIrRange) {
  NetworkRig rig;
  rig.network("mlp", "net", "inputs=1 layers=\"1 1\" activation=linear weights=\"1 0 1 0\" output=raw");
  rig.sensor->script(ms(10), {4505.0f});
  rig.ex.run_until(ms(10));
  const auto out = rig.on_port(0);
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(out[0].values.size(), 1u);
  EXPECT_NEAR(out[0].values[0], 1.0, 1e-4);
}

TEST(NetworkTask, ClampsNeverSendsNaNAndIgnoresBadInput) {
  NetworkRig rig;
  const auto id = rig.network("mlp", "net",
                              "inputs=2 layers=2 activation=linear input_scale=1 output_scale=1000 speed_limit=300 "
                              "weights=identity.w");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  rig.sensor->script(ms(10), {1.0f, -0.1f});
  rig.sensor->script(ms(20), {nan, 0.0f});         // ignored
  rig.sensor->script(ms(30), {1.0f, 1.0f, 1.0f});  // wrong length: ignored
  rig.sensor->script(ms(40), {1e30f, -1e30f});
  rig.ex.run_until(ms(50));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 2u);
  EXPECT_FLOAT_EQ(cmds[0].values[0], 300.0f);
  EXPECT_FLOAT_EQ(cmds[0].values[1], -100.0f);
  EXPECT_FLOAT_EQ(cmds[1].values[0], 300.0f);
  EXPECT_FLOAT_EQ(cmds[1].values[1], -300.0f);
  for (const auto& c : cmds)
    for (float v : c.values) EXPECT_TRUE(std::isfinite(v));
  const auto info = rig.node->info(id);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->traffic.delivered, 4u);
  std::size_t warnings = 0;
  for (const auto& e : rig.node->log().since(0))
    if (e.level == os::LogLevel::kWarn && e.text.find("ignored") != std::string::npos) ++warnings;
  EXPECT_EQ(warnings, 1u) << "one warning per interval";
}

TEST(NetworkTask, GenomeChangesAtRuntimeInlineAndFromAFile) {
  NetworkRig rig;
  const auto id = rig.network("mlp", "net", "inputs=2 layers=2 input_scale=1 weights=identity.w");
  for (int k = 1; k <= 4; ++k) rig.sensor->script(ms(10 * k), {0.5f, 0.0f});
  rig.ex.run_until(ms(10));
  ASSERT_TRUE(rig.node->set_parameter(id, "weights", "swap.w").ok());
  rig.ex.run_until(ms(20));
  ASSERT_TRUE(rig.node->set_parameter(id, "weights", "0 0 0.5  0 0 -0.5").ok());
  rig.ex.run_until(ms(30));
  // Refused genomes leave the last one in place.
  // The schema accepts both strings; the task refuses them on its own context (and logs why).
  EXPECT_TRUE(rig.node->set_parameter(id, "weights", "1 2 3").ok());
  EXPECT_TRUE(rig.node->set_parameter(id, "weights", "bad.w").ok());
  rig.ex.run_until(ms(40));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 4u);
  EXPECT_NEAR(cmds[0].values[0], 500 * std::tanh(0.5), 1e-3);  // identity
  EXPECT_NEAR(cmds[0].values[1], 0.0, 1e-3);
  EXPECT_NEAR(cmds[1].values[0], 0.0, 1e-3);  // swapped
  EXPECT_NEAR(cmds[1].values[1], 500 * std::tanh(0.5), 1e-3);
  EXPECT_NEAR(cmds[2].values[0], 500 * std::tanh(0.5), 1e-3);  // biases only
  EXPECT_NEAR(cmds[2].values[1], -500 * std::tanh(0.5), 1e-3);
  EXPECT_NEAR(cmds[3].values[0], cmds[2].values[0], 1e-6);
  std::size_t refused = 0;
  for (const auto& e : rig.node->log().since(0))
    if (e.text.find("weights:") != std::string::npos) {
      ++refused;
      EXPECT_TRUE(e.text.find("has 6 values, got 3") != std::string::npos ||
                  e.text.find("weight file 'bad.w': 2:5: 'zero' is not a number") != std::string::npos)
          << e.text;
    }
  EXPECT_EQ(refused, 2u);
}

TEST(NetworkTask, BadParametersAndDescriptionsRejectedWithLocatedErrors) {
  NetworkRig rig;
  struct Case {
    const char* type;
    const char* params;
    const char* error;
  };
  const Case cases[] = {
      {"mlp", "layers=\"4 x\"", "layers: 1:3: 'x' is not a number"},
      {"mlp", "layers=\"4 2.5\"", "layers: sizes are whole numbers"},
      {"mlp", "activation=relu", "activation: unknown activation 'relu'"},
      {"mlp", "inputs=2 layers=2 weights=\"1 2 3\"", "weights: the genome of this network has 6 values, got 3"},
      {"mlp", "inputs=2 layers=2 weights=\"1 0 0 0 1 oops\"", "weights: 1:11: 'oops' is not a number"},
      {"mlp", "inputs=2 weights=bad.w", "weights: weight file 'bad.w': 2:5: 'zero' is not a number"},
      {"mlp", "weights=missing.w", "weights: weight file 'missing.w': no such file"},
      {"mlp", "inputs=3 input_scale=\"1 2\"", "input_scale takes one factor or one per input (3), got 2"},
      {"mlp", "layers=1", "wheel output needs 2 or more network outputs"},
      {"mlp", "output=motors", "output must be wheels, raw or both"},
      {"mlp", "inputs=0", "inputs"},
      {"mlp", "speed_limit=-1", "speed_limit"},
      {"mlp", "layres=2", "layres"},
      {"elman", "layers=2", "an elman network needs a hidden layer"},
      {"ctrnn", "layers=3", "a ctrnn takes layers \"N O\""},
      {"ctrnn", "tau=-2", "tau: time constants must be positive"},
      {"ctrnn", "tau=\"0.1 0.2 0.3\"", "tau: give one time constant or one per neuron (4), got 3"},
      {"network", "", "name the description"},
      {"network", "description=broken.net", "description 'broken.net': 4:5: 'x' is not a number"},
      {"network", "description=nope.net", "description 'nope.net': no such file"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.type) + " " + c.params);
    auto id = rig.create(c.type, "bad", c.params);
    ASSERT_FALSE(id.ok());
    EXPECT_NE(id.error().find(c.error), std::string::npos) << id.error();
  }
  // Structure stays fixed at runtime.
  const auto id = rig.network("mlp", "net", "");
  (void)rig.node->set_parameter(id, "layers", "3 2");
  rig.ex.run_until(ms(5));
  bool said = false;
  for (const auto& e : rig.node->log().since(0)) said |= e.text.find("keeps its layers") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(NetworkTask, DescribedNetworkAndItsWeightOverride) {
  NetworkRig rig;
  rig.network("network", "net", "description=braitenberg.net");
  rig.network("network", "swapped", "description=braitenberg.net weights=swap.w");
  rig.sensor->script(ms(10), {0.5f, 0.0f});
  rig.ex.run_until(ms(10));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 2u);
  std::vector<float> lefts{cmds[0].values[0], cmds[1].values[0]};
  std::sort(lefts.begin(), lefts.end());
  EXPECT_NEAR(lefts[0], 0.0, 1e-4);  // output_scale 100 from the description
  EXPECT_NEAR(lefts[1], 100 * std::tanh(0.5), 1e-3);
}

TEST(NetworkTask, ProbesEveryLayerAndTheOutputs) {
  NetworkRig rig;
  std::mutex mu;
  std::map<std::string, std::size_t> sizes;
  rig.node->set_probe_sink([&](const os::ProbeSample& s) {
    std::lock_guard lock(mu);
    sizes[std::string(s.task) + ":" + std::string(s.channel)] = s.values.size();
  });
  rig.network("elman", "el", "inputs=2 layers=\"3 2\"");
  rig.network("ctrnn", "ct", "inputs=2 layers=\"4 2\"");
  rig.sensor->script(ms(10), {1.0f, 2.0f});
  rig.ex.run_until(ms(10));
  std::lock_guard lock(mu);
  const std::map<std::string, std::size_t> expect{{"el:activations/input", 2},
                                                  {"el:activations/hidden1", 3},
                                                  {"el:activations/output", 2},
                                                  {"el:outputs", 2},
                                                  {"ct:activations/input", 2},
                                                  {"ct:activations/state", 4},
                                                  {"ct:outputs", 2}};
  EXPECT_EQ(sizes, expect);
}

TEST(NetworkTask, CircuitOneNetworkFeedsAnother) {
  NetworkRig rig;
  // Stage 1: 2 inputs -> 2 raw outputs (tanh of each input); stage 2 reads them and drives.
  const auto a = rig.network("mlp", "stage1", "inputs=2 layers=2 input_scale=1 weights=identity.w output=both");
  const auto b = *rig.create("mlp", "stage2", "inputs=2 layers=2 input_scale=1 input_port=1 weights=swap.w");
  ASSERT_TRUE(rig.node->hook(a, b, {.port = 1}).ok());
  ASSERT_TRUE(rig.node->hook(b, rig.rec_id).ok());
  rig.sensor->script(ms(10), {0.5f, -1.0f});
  rig.ex.run_until(ms(10));
  const auto cmds = rig.rec->entries();
  // stage1 (port 0 wheels, port 1 raw) and stage2 (port 0 wheels).
  ASSERT_EQ(cmds.size(), 3u);
  const float r0 = std::tanh(0.5f), r1 = std::tanh(-1.0f);
  const auto raw = rig.on_port(1);
  ASSERT_EQ(raw.size(), 1u);
  EXPECT_NEAR(raw[0].values[0], r0, 1e-6);
  EXPECT_NEAR(raw[0].values[1], r1, 1e-6);
  const auto& last = cmds.back();
  EXPECT_EQ(last.port, 0);
  EXPECT_NEAR(last.values[0], 500 * std::tanh(r1), 1e-3);
  EXPECT_NEAR(last.values[1], 500 * std::tanh(r0), 1e-3);
}

TEST(NetworkTask, ReplacedWhileInputsKeepComingNoStaleNoNaN) {
  NetworkRig rig;
  auto old_id = rig.network("mlp", "ctl", "inputs=2 layers=2 input_scale=1 weights=identity.w");
  for (int k = 1; k <= 30; ++k) rig.sensor->script(ms(10 * k), {0.1f * static_cast<float>(k % 5), 0.3f});
  rig.ex.run_until(ms(145));
  // Swap: the new network is hooked before the old one goes, so no input instant is left out.
  const auto new_id = rig.network("ctrnn", "ctl2", "inputs=2 layers=\"2 2\" weights=\"1 0 0 0 0  0 1 0 0 0\"");
  ASSERT_TRUE(rig.node->remove(old_id).ok());
  rig.ex.run_until(ms(300));
  const auto sent = rig.sensor->sent();
  ASSERT_EQ(sent.size(), 30u);
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 30u) << "one command per input, before and after the swap";
  for (std::size_t k = 0; k < cmds.size(); ++k) {
    EXPECT_EQ(cmds[k].time, sent[k]) << "each command at its own input's instant: none stale";
    for (float v : cmds[k].values) EXPECT_TRUE(std::isfinite(v) && std::fabs(v) <= 500);
  }
  const auto info = rig.node->info(new_id);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->traffic.attempted, info->traffic.delivered + info->traffic.dropped() + info->queue_depth);
  EXPECT_EQ(info->traffic.dropped(), 0u);
}

// A sensor that sends the same vector at every tick (for the thread executor).
class Pulse : public os::Task {
 protected:
  void on_tick() override { send(0, {0.5f, -0.5f}); }
};

TEST(NetworkTask, GenomesWrittenWhileItRunsUnderTheThreadExecutor) {
  kernel::ThreadExecutor ex;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_control_task_types(registry, network_files()).ok());
  os::Node node(ex, {.name = "bot", .types = &registry});
  std::mutex mu;
  std::size_t probes = 0;
  node.set_probe_sink([&](const os::ProbeSample&) {
    std::lock_guard lock(mu);
    ++probes;
  });
  auto rec_task = std::make_unique<NetworkRecorder>();
  NetworkRecorder* rec = rec_task.get();
  const auto rec_id = *node.create("rec", std::move(rec_task), {.queue_capacity = 64});
  const auto pulse = *node.create("pulse", std::make_unique<Pulse>(), {.period = 1ms});
  auto a = os::parse_param_assignments("inputs=2 layers=\"3 2\" input_scale=1");
  ASSERT_TRUE(a.ok());
  const auto net = node.create("elman", "net", *a);
  ASSERT_TRUE(net.ok()) << (net ? "" : net.error());
  ASSERT_TRUE(node.hook(pulse, *net).ok());
  ASSERT_TRUE(node.hook(*net, rec_id).ok());
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  int k = 0;
  while (rec->entries().size() < 60 && std::chrono::steady_clock::now() < deadline) {
    // New genomes from this thread while the network steps on its own.
    std::string w;
    for (int g = 0; g < 26; ++g)  // (2 + 3 + 1) * 3 + (3 + 1) * 2 w += std::to_string(0.01 * ((g + k) % 7)) + " ";
      ASSERT_TRUE(node.set_parameter(*net, "weights", w).ok());
    ++k;
    std::this_thread::sleep_for(1ms);
  }
  const auto cmds = rec->entries();
  node.clear();
  EXPECT_GE(cmds.size(), 60u);
  for (const auto& e : node.log().since(0)) EXPECT_EQ(e.text.find("weights:"), std::string::npos) << e.text;
  for (const auto& c : cmds)
    for (float v : c.values) EXPECT_TRUE(std::isfinite(v) && std::fabs(v) <= 500);
  std::lock_guard lock(mu);
  EXPECT_GT(probes, 0u);
}

TEST(NetworkTask, OutputsInZeroOneAreCentredForTheWheels) {
  NetworkRig rig;
  // A ctrnn at rest: rates sigma(theta) = sigma(1), sigma(-1); wheels 500 (2 sigma - 1) = 500 tanh(theta / 2).
  rig.network("ctrnn", "ct", "inputs=1 layers=\"2 2\" weights=\"0 0 0 1  0 0 0 -1\"");
  // A sigmoid perceptron: 500 (2 sigma(x) - 1).
  rig.network("mlp", "sg", "inputs=1 layers=2 activation=sigmoid input_scale=1 weights=\"1 0  -1 0\"");
  rig.sensor->script(ms(10), {0.0f});
  rig.sensor->script(ms(20), {2.0f});
  rig.ex.run_until(ms(20));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 4u);
  std::vector<Vec> seen;
  for (const auto& c : cmds) seen.push_back(c.values);
  std::sort(seen.begin(), seen.end());
  const float t1 = 500 * std::tanh(0.5f), t2 = 500 * std::tanh(1.0f);
  // ctrnn twice (its input weights are 0: the state stays at rest), the sigmoid at 0 and at 2.
  const std::vector<Vec> expect{{0, 0}, {t1, -t1}, {t1, -t1}, {t2, -t2}};
  ASSERT_EQ(seen.size(), expect.size());
  for (std::size_t k = 0; k < seen.size(); ++k)
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(seen[k][j], expect[k][j], 1e-3) << k;
}

}  // namespace
}  // namespace symb::control
