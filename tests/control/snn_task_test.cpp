// The spiking-network task types in a node under virtual time: a network task fed currents and AER
// events, its AER output (addresses, timestamps, module bits) checked spike by spike against the
// same network stepped directly; catch-up and bad input; the linda type grown from genomes,
// regrown at runtime and refusing a bad genome with its location; the encoder's current and rate
// coding; the decoder's rates and clamping; the layout probe's round trip.
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/snn/network_layout.hpp"
#include "symb/control/snn/snn_task_types.hpp"
#include "symb/control/snn/spike_coding_tasks.hpp"
#include "symb/control/snn/spiking_network_task.hpp"
#include "symb/io/bytes.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/virtual_time.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using snn::AerEvent;

using test_support::ms;

// Keeps every message: numbers, or the events of an AER packet.
class SnnRecorder : public os::Task {
 public:
  struct Entry {
    Time time;
    os::Port port;
    std::vector<float> values;
    std::vector<AerEvent> events;
    bool aer = false;
  };
  std::vector<Entry> entries() const {
    std::lock_guard lock(mu_);
    return entries_;
  }
  std::vector<AerEvent> events(os::Port port) const {
    std::vector<AerEvent> out;
    for (const Entry& e : entries())
      if (e.port == port) out.insert(out.end(), e.events.begin(), e.events.end());
    return out;
  }

 protected:
  void on_message(const os::Message& m) override {
    Entry e{m.time, m.port, std::vector<float>(m.numbers().begin(), m.numbers().end()), {}, false};
    if (const snn::AerPacket* p = snn::aer_of(m)) {
      e.events = p->events;
      e.aer = true;
    }
    std::lock_guard lock(mu_);
    entries_.push_back(std::move(e));
  }

 private:
  mutable std::mutex mu_;
  std::vector<Entry> entries_;
};

// A two-cell genome: an input neuron at (0, 0) that excites an output neuron at (2, 0).
const char* kRelayGenome = R"(grid 3 1
ticks 0
seed at 0 0 class RS
seed at 2 0 class FS
input 0 at 0 0
output 0 at 2 0
)";

// The same shape, grown: the input cell reaches the output cell up a gradient.
std::string grown_relay(float weight) {
  return "grid 3 1\nticks 2\nwarmup 20\nmorphogen O diffusion 0.2 decay 0.05\nsource O at 2 0 rate 1\n"
         "seed at 0 0 class RS\nseed at 2 0 class FS\ninput 0 at 0 0\noutput 0 at 2 0\n"
         "gene once class RS when 1 do grow up O weight " +
         std::to_string(weight) + " delay 2\n";
}

const std::map<std::string, std::string, std::less<>> kSnnFiles{
    {"relay.genome", kRelayGenome},
    {"broken.genome", "grid 3 1\nticks 0\nseed at 0 0 class XX\n"},
};

ControlResources snn_files() {
  ControlResources r;
  r.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
    auto it = kSnnFiles.find(ref);
    if (it == kSnnFiles.end()) return kernel::Error{"no such file"};
    return it->second;
  };
  return r;
}

struct SnnRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  SnnRecorder* rec = nullptr;
  os::TaskId rec_id;
  std::vector<os::ProbeSample> probes;
  std::vector<std::vector<float>> probe_values;

  SnnRig() {
    EXPECT_TRUE(register_control_task_types(registry, snn_files()).ok());
    node = std::make_unique<os::Node>(ex, os::NodeConfig{.name = "bot", .seed = 7, .types = &registry});
    auto r = std::make_unique<SnnRecorder>();
    rec = r.get();
    rec_id = *node->create("rec", std::move(r), {.queue_capacity = 256});
  }
  os::TaskId make(std::string_view type, std::string name, std::string_view params) {
    auto a = os::parse_param_assignments(params);
    EXPECT_TRUE(a.ok()) << (a ? "" : a.error());
    auto id = node->create(type, std::move(name), *a);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    EXPECT_TRUE(node->hook(*id, rec_id).ok());
    return *id;
  }
  void post(os::TaskId to, os::Payload p) {
    os::Message m;
    m.payload = std::move(p);
    ASSERT_TRUE(node->post(to, m).ok());
  }
};

// A hand-built three-neuron network: input channel 0 -> neuron 0 -> (weight 40, delay 3) neuron 1
// = output channel 0; neuron 2 silent, output channel 1.
snn::GrownNetwork relay_network() {
  snn::GrownNetwork g;
  g.spec.neurons = {snn::params_of(snn::NeuronClass::kRS), snn::params_of(snn::NeuronClass::kRS),
                    snn::params_of(snn::NeuronClass::kRS)};
  g.spec.synapses = {{0, 1, 40.0f, 3}};
  g.inputs = {{0}};
  g.outputs = {{1}, {2}};
  return g;
}

TEST(SpikingNetworkTask, SpikesLeaveAsAerWithModuleBitsAndStepTimes) {
  SnnRig rig;
  SpikingNetworkTaskOptions o;
  o.module = 5;
  auto task = SpikingNetworkTask::create(relay_network(), o);
  ASSERT_TRUE(task.ok()) << (task ? "" : task.error());
  const auto id = *rig.node->create("net", std::move(task).value(), {.period = 10ms});
  ASSERT_TRUE(rig.node->hook(id, rig.rec_id).ok());
  rig.post(id, os::Payload{20.0f});  // channel 0 held at 20
  rig.ex.run_until(ms(500));

  // The reference: the same network stepped by hand with the same input.
  auto ref = snn::SpikingNetwork::create(relay_network().spec);
  ASSERT_TRUE(ref.ok()) << ref.error();
  std::vector<AerEvent> all, out;
  for (std::uint32_t t = 0; t < 500; ++t) {
    ref.value().input()[0] += 20.0f;
    for (std::uint32_t n : ref.value().step()) {
      all.push_back({snn::aer_address(5, n), t * 1000});
      if (n == 1) out.push_back({snn::aer_address(5, 0), t * 1000});
    }
  }
  ASSERT_GT(out.size(), 5u) << "the relay must fire";
  EXPECT_EQ(rig.rec->events(kAllSpikesPort), all);
  EXPECT_EQ(rig.rec->events(kOutputSpikesPort), out);
  for (const auto& e : rig.rec->entries()) EXPECT_TRUE(e.aer);
  for (const AerEvent& e : all) EXPECT_EQ(snn::aer_module(e.address), 5u);
}

TEST(SpikingNetworkTask, AerInputEventsPulseTheirChannelAtTheirMillisecond) {
  SnnRig rig;
  SpikingNetworkTaskOptions o;
  o.pulse = 200;  // one event makes neuron 0 fire at the next step
  auto task = SpikingNetworkTask::create(relay_network(), o);
  ASSERT_TRUE(task.ok());
  auto* raw = task.value().get();
  const auto id = *rig.node->create("net", std::move(task).value(), {.period = 10ms});
  ASSERT_TRUE(rig.node->hook(id, rig.rec_id).ok());
  rig.ex.run_until(ms(20));
  // At 20 ms: events for 35 ms and 72 ms ahead, one 5 ms in the past (late), one for channel 9
  // (no such channel) and one 5 s ahead (too far): two dropped.
  rig.post(id, snn::aer_payload({{snn::aer_address(0, 0), 35'000},
                                 {snn::aer_address(0, 0), 72'000},
                                 {snn::aer_address(3, 0), 15'000},
                                 {snn::aer_address(0, 9), 40'000},
                                 {snn::aer_address(0, 0), 5'020'000}}));
  rig.ex.run_until(ms(200));
  std::vector<std::uint32_t> fired;
  for (const AerEvent& e : rig.rec->events(kAllSpikesPort))
    if (snn::aer_neuron(e.address) == 0) fired.push_back(e.timestamp_us / 1000);
  // Pulsed in step k, neuron 0 crosses 30 mV during it and fires at the start of step k + 1.
  EXPECT_EQ(fired, (std::vector<std::uint32_t>{21, 36, 73}));
  const SpikingNetworkStats s = raw->stats();
  EXPECT_EQ(s.input_events, 3u);
  EXPECT_EQ(s.late_events, 1u);
  EXPECT_EQ(s.dropped_events, 2u);
}

TEST(SpikingNetworkTask, BadInputIsCountedAndNothingBreaks) {
  SnnRig rig;
  auto task = SpikingNetworkTask::create(relay_network(), {});
  ASSERT_TRUE(task.ok());
  auto* raw = task.value().get();
  const auto id = *rig.node->create("net", std::move(task).value(), {.period = 10ms});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  rig.post(id, os::Payload{nan});
  rig.post(id, os::Payload{1e9f});
  rig.post(id, os::Payload{5.0f, 1.0f, 2.0f, 3.0f});  // extra channels: ignored values, accepted
  rig.ex.run_until(ms(100));
  const SpikingNetworkStats s = raw->stats();
  EXPECT_EQ(s.ignored, 2u);
  EXPECT_EQ(s.current_vectors, 1u);
  EXPECT_EQ(s.steps, 100u);
}

TEST(SpikingNetworkTask, CreationRejectsBadNetworksAndOptions) {
  snn::GrownNetwork bad = relay_network();
  bad.outputs = {{7}};
  EXPECT_FALSE(SpikingNetworkTask::create(bad, {}).ok());
  bad = relay_network();
  bad.spec.synapses[0].delay = 99;
  EXPECT_FALSE(SpikingNetworkTask::create(bad, {}).ok());
  SpikingNetworkTaskOptions o;
  o.module = 256;
  EXPECT_FALSE(SpikingNetworkTask::create(relay_network(), o).ok());
  o = {};
  o.pulse = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(SpikingNetworkTask::create(relay_network(), o).ok());
}

TEST(LindaType, GrowsFromAGenomeFileOrInlineTextAndRegrowsAtRuntime) {
  SnnRig rig;
  std::vector<std::vector<float>> layouts;
  rig.node->set_probe_sink([&layouts](const os::ProbeSample& s) {
    if (s.channel == "layout") layouts.emplace_back(s.values.begin(), s.values.end());
  });
  const auto id = rig.make("linda", "net", "genome=relay.genome");
  rig.ex.run_until(ms(50));
  ASSERT_EQ(layouts.size(), 1u);
  auto first = snn::layout_from_values(layouts[0]);
  ASSERT_TRUE(first.ok()) << (first ? "" : first.error());
  EXPECT_EQ(first->spec.neurons.size(), 2u);
  EXPECT_TRUE(first->spec.synapses.empty());

  // Regrown at runtime from inline text: now the input cell has grown a synapse to the output.
  ASSERT_TRUE(rig.node->set_parameter(id, "genome", grown_relay(35)).ok());
  rig.ex.run_until(ms(100));
  ASSERT_EQ(layouts.size(), 2u);
  auto second = snn::layout_from_values(layouts[1]);
  ASSERT_TRUE(second.ok());
  ASSERT_EQ(second->spec.synapses.size(), 1u);
  EXPECT_EQ(second->spec.synapses[0].delay, 2u);
  EXPECT_FLOAT_EQ(second->spec.synapses[0].weight, 35.0f);

  // A broken genome is refused with its location; the grown network goes on.
  rig.ex.run_until(ms(110));
  ASSERT_TRUE(rig.node->set_parameter(id, "genome", "broken.genome").ok());  // applied on the task's context
  rig.ex.run_until(ms(150));
  EXPECT_EQ(layouts.size(), 2u);
  bool located = false;
  for (const auto& e : rig.node->log().since(0))
    if (e.text.find("broken.genome") != std::string::npos && e.text.find("3:") != std::string::npos) located = true;
  EXPECT_TRUE(located) << "the refusal names the genome and the line";
  auto p = rig.node->parameters(id);
  ASSERT_TRUE(p.ok());
}

TEST(LindaType, CreationErrorsNameTheGenomeAndTheLine) {
  SnnRig rig;
  auto a = os::parse_param_assignments("genome=broken.genome");
  ASSERT_TRUE(a.ok());
  auto id = rig.node->create("linda", "net", *a);
  ASSERT_FALSE(id.ok());
  EXPECT_NE(id.error().find("broken.genome"), std::string::npos) << id.error();
  EXPECT_NE(id.error().find("3:"), std::string::npos) << id.error();
  a = os::parse_param_assignments("genome=missing.genome");
  id = rig.node->create("linda", "net", *a);
  ASSERT_FALSE(id.ok());
  EXPECT_NE(id.error().find("no such file"), std::string::npos) << id.error();
  a = os::parse_param_assignments("");
  id = rig.node->create("linda", "net", *a);
  ASSERT_FALSE(id.ok());
}

TEST(IzhikevichType, ReferenceExampleRunsAndIsDeterministic) {
  auto run = [](std::uint64_t node_seed) {
    kernel::VirtualTimeExecutor ex;
    os::TaskTypeRegistry registry;
    EXPECT_TRUE(register_control_task_types(registry, snn_files()).ok());
    os::Node node(ex, os::NodeConfig{.name = "bot", .seed = node_seed, .types = &registry});
    auto r = std::make_unique<SnnRecorder>();
    SnnRecorder* rec = r.get();
    const auto rec_id = *node.create("rec", std::move(r), {.queue_capacity = 256});
    auto a = os::parse_param_assignments("example=reference_2003");
    auto id = node.create("izhikevich", "net", *a);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    EXPECT_TRUE(node.hook(*id, rec_id).ok());
    ex.run_until(ms(1000));
    return rec->events(kAllSpikesPort);
  };
  const auto a = run(1), b = run(1), c = run(2);
  const double rate = static_cast<double>(a.size()) / 1000.0;  // spikes per neuron per second
  EXPECT_GT(rate, 2.0);
  EXPECT_LT(rate, 30.0);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(SpikeEncoder, CurrentCodingScalesAndClamps) {
  SnnRig rig;
  const auto id = rig.make("spike_encoder", "enc", "coding=current gain=40 input_scale=0.001");
  rig.post(id, os::Payload{0.0f, 500.0f, 1000.0f, 4000.0f, -10.0f});
  rig.ex.run_until(ms(1));
  const auto e = rig.rec->entries();
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].values, (std::vector<float>{0.0f, 20.0f, 40.0f, 40.0f, 0.0f}));
}

TEST(SpikeEncoder, RateCodingGivesPoissonCountsAtTheCodedRate) {
  SnnRig rig;
  const auto id = rig.make("spike_encoder", "enc", "coding=rate max_rate=400 window=100ms input_scale=1");
  for (int k = 0; k < 50; ++k) {
    rig.ex.run_until(ms(100 * k));
    rig.post(id, os::Payload{0.0f, 0.25f, 1.0f});
  }
  rig.ex.run_until(ms(5000));
  std::size_t counts[3] = {0, 0, 0};
  for (const AerEvent& e : rig.rec->events(0)) {
    ASSERT_LT(snn::aer_neuron(e.address), 3u);
    ++counts[snn::aer_neuron(e.address)];
  }
  // 50 readings x 100 ms = 5 s: 0, 100 and 400 Hz expected; Poisson sd sqrt(n).
  EXPECT_EQ(counts[0], 0u);
  EXPECT_NEAR(static_cast<double>(counts[1]), 500.0, 4 * std::sqrt(500.0));
  EXPECT_NEAR(static_cast<double>(counts[2]), 2000.0, 4 * std::sqrt(2000.0));
}

TEST(SpikeDecoder, RatesOverTheWindowBecomeClampedWheelCommands) {
  SnnRig rig;
  const auto id = rig.make("spike_decoder", "dec", "channels=2 gain=10 offset=-100 window=100ms speed_limit=450");
  // 100 ms before 100 ms: channel 0 fires 5 times (50 Hz), channel 1 40 times (400 Hz).
  std::vector<AerEvent> events;
  for (int k = 0; k < 5; ++k)
    events.push_back({snn::aer_address(0, 0), static_cast<std::uint32_t>(10'000 + 15'000 * k)});
  for (int k = 0; k < 40; ++k)
    events.push_back({snn::aer_address(0, 1), static_cast<std::uint32_t>(1'000 + 2'000 * k)});
  events.push_back({snn::aer_address(0, 7), 5'000});  // channel beyond 2: not counted
  rig.ex.run_until(ms(85));
  rig.post(id, snn::aer_payload(events));
  rig.post(id, os::Payload{1.0f});  // not a packet: ignored
  rig.ex.run_until(ms(90));
  const auto cmds = rig.rec->entries();
  ASSERT_EQ(cmds.size(), 3u);  // at 30, 60, 90 ms (a period after creation, then every period)
  EXPECT_EQ(cmds[0].values, (std::vector<float>{-100.0f, -100.0f}));  // silent: the offset
  EXPECT_EQ(cmds[2].values, (std::vector<float>{-100.0f + 10 * 50.0f, 450.0f}));
}

// Spikes between nodes: node A's network sends its output spikes through an aer_codec as bytes; a
// link (here: whatever node A's link task receives is posted into node B) carries them to node
// B's aer_codec, which hands packets to node B's network as input events. Every output spike of A
// arrives in B bit-identical (module bits included), and B's input neuron answers each one.
TEST(AerAcrossNodes, SpikesCrossAByteLinkAndDriveTheOtherNodesNetwork) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_control_task_types(registry, snn_files()).ok());
  os::Node a(ex, os::NodeConfig{.name = "a", .seed = 1, .types = &registry});
  os::Node b(ex, os::NodeConfig{.name = "b", .seed = 2, .types = &registry});
  auto make = [](os::Node& node, std::string_view type, std::string name, std::string_view params) {
    auto p = os::parse_param_assignments(params);
    EXPECT_TRUE(p.ok());
    auto id = node.create(type, std::move(name), *p);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    return *id;
  };
  // A: a relay network (input channel 0 held at 20 -> neuron 0 -> neuron 1 = output channel 0).
  SpikingNetworkTaskOptions o;
  o.module = 3;
  auto net_a_task = SpikingNetworkTask::create(relay_network(), o);
  ASSERT_TRUE(net_a_task.ok());
  const auto net_a = *a.create("net", std::move(net_a_task).value(), {.period = 10ms});
  const auto codec_a = make(a, "aer_codec", "codec", "");
  os::HookOptions port1;
  port1.port = kOutputSpikesPort;
  ASSERT_TRUE(a.hook(net_a, codec_a, port1).ok());
  // The link: node A's bytes, posted into node B's codec.
  const auto codec_b = make(b, "aer_codec", "codec", "");
  class Link : public os::Task {
   public:
    Link(os::Node& to, os::TaskId id) : to_(to), id_(id) {}
    std::vector<std::vector<std::byte>> carried;

   protected:
    void on_message(const os::Message& m) override {
      if (const io::Bytes* bytes = io::bytes_of(m)) carried.push_back(bytes->data);
      os::Message copy = m;
      copy.source = {};
      ASSERT_TRUE(to_.post(id_, copy).ok());
    }

   private:
    os::Node& to_;
    os::TaskId id_;
  };
  auto link_task = std::make_unique<Link>(b, codec_b);
  Link* link = link_task.get();
  const auto link_id = *a.create("link", std::move(link_task), {.queue_capacity = 64});
  os::HookOptions port0;
  port0.port = kAerBytesPort;
  ASSERT_TRUE(a.hook(codec_a, link_id, port0).ok());
  // B: the relay network again; its input channel 0 takes the events (pulse 200: one spike each).
  SpikingNetworkTaskOptions ob;
  ob.pulse = 200;
  auto net_b_task = SpikingNetworkTask::create(relay_network(), ob);
  ASSERT_TRUE(net_b_task.ok());
  auto* net_b_raw = net_b_task.value().get();
  const auto net_b = *b.create("net", std::move(net_b_task).value(), {.period = 10ms});
  auto rec_a = std::make_unique<SnnRecorder>();
  auto rec_b = std::make_unique<SnnRecorder>();
  SnnRecorder* sent = rec_a.get();
  SnnRecorder* got = rec_b.get();
  const auto rec_a_id = *a.create("rec", std::move(rec_a), {.queue_capacity = 256});
  const auto rec_b_id = *b.create("rec", std::move(rec_b), {.queue_capacity = 256});
  ASSERT_TRUE(a.hook(net_a, rec_a_id, port1).ok());
  os::HookOptions packets;
  packets.port = kAerPacketsPort;
  ASSERT_TRUE(b.hook(codec_b, net_b, packets).ok());
  ASSERT_TRUE(b.hook(codec_b, rec_b_id, packets).ok());
  os::HookOptions all_spikes;
  all_spikes.port = kAllSpikesPort;
  ASSERT_TRUE(b.hook(net_b, rec_b_id, all_spikes).ok());
  os::Message current;
  current.payload = os::Payload{20.0f};
  ASSERT_TRUE(a.post(net_a, current).ok());
  ex.run_until(ms(1000));

  const std::vector<AerEvent> out_a = sent->events(kOutputSpikesPort);
  ASSERT_GT(out_a.size(), 10u);
  EXPECT_FALSE(link->carried.empty());
  EXPECT_EQ(got->events(kAerPacketsPort), out_a) << "bit-identical across the link";
  for (const AerEvent& e : out_a) EXPECT_EQ(snn::aer_module(e.address), 3u);
  const SpikingNetworkStats s = net_b_raw->stats();
  EXPECT_EQ(s.input_events, out_a.size());
  EXPECT_EQ(s.dropped_events, 0u);
  // B's input neuron (0) answers the events: a spike no earlier than 1 ms after an event's own
  // millisecond (events that arrive after B stepped past it act in B's next step: counted late),
  // and one per event unless two land in one step.
  std::vector<std::uint32_t> fired_b;
  for (const AerEvent& e : got->events(kAllSpikesPort))
    if (snn::aer_neuron(e.address) == 0) fired_b.push_back(e.timestamp_us / 1000);
  EXPECT_GE(fired_b.size(), out_a.size() / 2);
  EXPECT_LE(fired_b.size(), out_a.size());
  ASSERT_FALSE(fired_b.empty());
  EXPECT_GE(fired_b.front(), out_a.front().timestamp_us / 1000 + 1);
}

TEST(NetworkLayout, RoundTripsAndRejectsCutOrForeignValues) {
  snn::GrownNetwork g = relay_network();
  g.width = 3;
  g.height = 2;
  g.x = {0, 2, 1};
  g.y = {0, 0, 1};
  g.cell_ids = {0, 1, 4};
  g.classes = {snn::NeuronClass::kRS, snn::NeuronClass::kFS, snn::NeuronClass::kLTS};
  for (snn::NeuronClass c : g.classes) g.spec.neurons.push_back(snn::params_of(c));
  g.spec.neurons.erase(g.spec.neurons.begin(), g.spec.neurons.begin() + 3);
  g.spec.bias = {0, 6, 0};
  const std::vector<float> v = snn::layout_values(g);
  auto back = snn::layout_from_values(v);
  ASSERT_TRUE(back.ok()) << (back ? "" : back.error());
  EXPECT_EQ(back->spec.synapses, g.spec.synapses);
  EXPECT_EQ(back->spec.neurons, g.spec.neurons);
  EXPECT_EQ(back->x, g.x);
  EXPECT_EQ(back->classes, g.classes);
  EXPECT_EQ(back->inputs, g.inputs);
  EXPECT_EQ(back->outputs, g.outputs);
  for (std::size_t cut = 0; cut < v.size(); ++cut)
    EXPECT_FALSE(snn::layout_from_values(std::span<const float>(v.data(), cut)).ok()) << cut;
  std::vector<float> foreign = v;
  foreign[0] = 9;
  EXPECT_FALSE(snn::layout_from_values(foreign).ok());
}

}  // namespace
}  // namespace symb::control
