#include "symb/control/snn/snn_task_types.hpp"

#include <memory>
#include <string>

#include "symb/control/control_task_types.hpp"
#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/reference_network.hpp"
#include "symb/control/snn/spike_coding_tasks.hpp"
#include "symb/control/snn/spiking_network_task.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using kernel::Error;

constexpr double kMaxGenomeText = 200000;

bool is_inline_genome(std::string_view value) {
  if (value.find('\n') != std::string_view::npos) return true;
  const std::size_t i = value.find_first_not_of(" \t\r");
  if (i == std::string_view::npos) return false;
  return value[i] == '#' || value.substr(i, 4) == "grid";
}

using kernel::Result;

template <class P>
void add_network_params(os::ParamTable<P>& p) {
  p.add("module", &P::module)
      .range(0.0, static_cast<double>(snn::kMaxModule))
      .doc("AER module bits of the addresses this network sends (tells modules apart on a shared bus)");
  p.add("warn_interval", &P::warn_interval).range(0.0, 3600.0).doc("at most one warning per interval").live();
}

struct IzhikevichParams : SpikingNetworkTaskOptions {
  std::string example = "reference_2003";
  std::int64_t excitatory = 800;
  std::int64_t inhibitory = 200;
  std::int64_t network_seed = 1;
  std::string integration = "published";
};

os::TaskType linda_type(const std::shared_ptr<const ControlResources>& resources) {
  using P = SpikingNetworkTaskOptions;
  os::ParamTable<P> p;
  p.add("genome", &P::genome)
      .range(0.0, kMaxGenomeText)
      .doc("the genome: a reference the node resolves, or the genome text itself; set at runtime to regrow")
      .live();
  p.add("seed", &P::seed).range(0.0, 9e15).doc("development seed (only the genome's noise uses it)").live();
  p.add("pulse", &P::pulse)
      .range(-1000.0, 1000.0)
      .doc("current one AER input event adds to its channel's neurons")
      .live();
  add_network_params(p);
  auto t = os::declare_task_type(
      "linda",
      "spiking network grown from a Linda genome: input currents or AER events in, AER spikes out on port 0 (all) "
      "and port 1 (output channels); steps 1 ms steps in batches of its period",
      std::move(p), [resources](const P& c) -> Result<std::unique_ptr<SpikingNetworkTask>> {
        if (c.genome.empty()) return Error{"name the genome: genome=REFERENCE (or the genome text)"};
        auto grown = grow_genome(c.genome, static_cast<std::uint64_t>(c.seed), *resources);
        if (!grown) return Error{grown.error()};
        SpikingNetworkTaskOptions o = c;
        o.grow = [resources](const std::string& g, std::int64_t s) {
          return grow_genome(g, static_cast<std::uint64_t>(s), *resources);
        };
        return SpikingNetworkTask::create(std::move(grown).value(), std::move(o));
      });
  t.defaults.priority = 2;
  t.defaults.period = 10ms;
  t.defaults.queue_capacity = 8;
  return t;
}

os::TaskType izhikevich_type() {
  using P = IzhikevichParams;
  os::ParamTable<P> p;
  p.add("example", &P::example).range(1.0, 64.0).doc("the example network (reference_2003)");
  p.add("excitatory", &P::excitatory).range(1.0, 20000.0).doc("excitatory neurons");
  p.add("inhibitory", &P::inhibitory).range(0.0, 20000.0).doc("inhibitory neurons");
  p.add("network_seed", &P::network_seed)
      .range(0.0, 9e15)
      .doc("seed of the network's random parameters and weights (the noise comes from the task's own stream)");
  p.add("integration", &P::integration).range(1.0, 16.0).doc("published or euler");
  add_network_params(p);
  auto t = os::declare_task_type(
      "izhikevich",
      "a built-in Izhikevich network: example=reference_2003 is the 2003 paper's random 800/200 network with its "
      "thalamic noise input; AER spikes out on port 0",
      std::move(p), [](const P& c) -> Result<std::unique_ptr<SpikingNetworkTask>> {
        if (c.example != "reference_2003")
          return Error{"example: unknown network '" + shown_reference(c.example) + "' (known: reference_2003)"};
        auto integration = snn::parse_integration(c.integration);
        if (!integration) return Error{"integration: " + integration.error()};
        const auto exc = static_cast<std::size_t>(c.excitatory);
        const auto inh = static_cast<std::size_t>(c.inhibitory);
        if ((exc + inh) * (exc + inh) > 25'000'000) return Error{"the all-to-all example is limited to 5000 neurons"};
        kernel::RandomStream random(static_cast<std::uint64_t>(c.network_seed), 0);
        snn::GrownNetwork net;
        net.spec = snn::reference_network(random, {exc, inh});
        net.spec.integration = *integration;
        SpikingNetworkTaskOptions o = c;
        o.thalamic = true;
        o.thalamic_excitatory = exc;
        return SpikingNetworkTask::create(std::move(net), std::move(o));
      });
  t.defaults.priority = 2;
  t.defaults.period = 10ms;
  t.defaults.queue_capacity = 8;
  return t;
}

os::TaskType encoder_type() {
  using P = SpikeEncoderOptions;
  os::ParamTable<P> p;
  p.add("coding", &P::coding,
        os::choice<SpikeCoding>("coding", {{"current", SpikeCoding::kCurrent}, {"rate", SpikeCoding::kRate}}))
      .range(1.0, 16.0)
      .doc("current or rate")
      .live();
  p.add("input_scale", &P::input_scale)
      .range(-1e6, 1e6)
      .doc("sensor values times this, clamped to 0..1 (default 1/4505 for IR)")
      .live();
  p.add("gain", &P::gain).range(-1000.0, 1000.0).doc("current coding: current at 1").live();
  p.add("max_rate", &P::max_rate).range(0.0, 1000.0).doc("rate coding: Hz at 1").live();
  p.add("window", &P::window)
      .range(0.001, 10.0)
      .doc("rate coding: each reading gives events for this long (the sensor period)")
      .live();
  p.add("module", &P::module).range(0.0, static_cast<double>(snn::kMaxModule)).doc("AER module bits").live();
  p.add("warn_interval", &P::warn_interval).range(0.0, 3600.0).doc("at most one warning per interval").live();
  auto t = os::declare_task_type(
      "spike_encoder",
      "sensor vector in on port 0; out on port 0: input currents (coding=current) or rate-coded AER events "
      "(coding=rate), one channel per sensor value",
      std::move(p), [](const P& o) { return SpikeEncoderTask::create(o); });
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  return t;
}

os::TaskType decoder_type() {
  using P = SpikeDecoderOptions;
  os::ParamTable<P> p;
  p.add("channels", &P::channels)
      .range(1.0, static_cast<double>(SpikeDecoderTask::kMaxChannels))
      .doc("output channels decoded (2: [left, right])");
  p.add("gain", &P::gain).range(-1e6, 1e6).doc("wheel units per Hz").live();
  p.add("offset", &P::offset).range(-1e6, 1e6).doc("wheel units at 0 Hz").live();
  p.add("speed_limit", &P::speed_limit).range(1e-6, 1e6).doc("commands are clamped to +-this").live();
  p.add("window", &P::window).range(0.001, 60.0).doc("the rate estimate's window").live();
  p.add("warn_interval", &P::warn_interval).range(0.0, 3600.0).doc("at most one warning per interval").live();
  auto t = os::declare_task_type(
      "spike_decoder",
      "output-channel spikes (AER) in; every period [offset + gain * rate(c)] for each channel out on port 0 "
      "(rates in Hz over the window), clamped to +-speed_limit",
      std::move(p), [](const P& o) { return SpikeDecoderTask::create(o); });
  t.defaults.priority = 2;
  t.defaults.period = 30ms;
  t.defaults.queue_capacity = 8;
  return t;
}

os::TaskType codec_type() {
  auto t = os::declare_task_type(
      "aer_codec",
      "AER packets in -> their wire form as bytes out on port 0 (for a stream task in frames mode); bytes in -> "
      "AER packets out on port 1: spikes across byte links between nodes",
      os::ParamTable<os::NoParams>{}, [](const os::NoParams&) { return std::make_unique<AerCodecTask>(); });
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 16;
  return t;
}

}  // namespace

kernel::Result<snn::GrownNetwork> grow_genome(std::string_view genome, std::uint64_t seed,
                                              const ControlResources& resources) {
  std::string text;
  std::string where = "genome";
  if (is_inline_genome(genome)) {
    text = std::string(genome);
  } else {
    const std::string reference(genome);
    where = "genome '" + shown_reference(reference) + "'";
    if (!resources.read_program) return Error{"cannot read " + where + " (no read_program)"};
    auto read = resources.read_program(reference);
    if (!read) return Error{where + ": " + read.error()};
    text = std::move(read).value();
  }
  auto parsed = snn::parse_genome(text);
  if (!parsed) return Error{where + ": " + parsed.error()};
  auto grown = snn::develop(*parsed, seed);
  if (!grown) return Error{where + ": " + grown.error()};
  return grown;
}

kernel::Status register_snn_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
  auto shared = std::make_shared<const ControlResources>(resources);
  for (os::TaskType t : {linda_type(shared), izhikevich_type(), encoder_type(), decoder_type(), codec_type()})
    if (auto st = registry.add(std::move(t)); !st) return st;
  return {};
}

}  // namespace symb::control
