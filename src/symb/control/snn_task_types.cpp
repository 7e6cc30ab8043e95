#include "symb/control/snn_task_types.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/reference_network.hpp"
#include "symb/control/spike_coding_tasks.hpp"
#include "symb/control/spiking_network_task.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using kernel::Error;
using os::ParamSpec;
using os::ParamType;

constexpr double kMaxGenomeText = 200000;

std::string shown(std::string_view s) {
  return s.size() <= 120 ? std::string(s) : std::string(s.substr(0, 120)) + "...";
}

bool is_inline_genome(std::string_view value) {
  if (value.find('\n') != std::string_view::npos) return true;
  const std::size_t i = value.find_first_not_of(" \t\r");
  if (i == std::string_view::npos) return false;
  return value[i] == '#' || value.substr(i, 4) == "grid";
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

SpikingNetworkTaskOptions network_options(const os::ParamSet& p) {
  SpikingNetworkTaskOptions o;
  o.module = static_cast<std::uint32_t>(p.integer("module"));
  o.warn_interval = p.duration("warn_interval");
  return o;
}

std::vector<ParamSpec> network_params() {
  return {
      {"module", ParamType::kInt, std::int64_t{0}, 0.0, static_cast<double>(snn::kMaxModule),
       "AER module bits of the addresses this network sends (tells modules apart on a shared bus)"},
      {"warn_interval", ParamType::kDuration, kernel::Duration(1s), 0.0, 3600.0, "at most one warning per interval"},
  };
}

os::TaskType linda_type(const std::shared_ptr<const ControlResources>& resources) {
  os::TaskType t;
  t.name = "linda";
  t.doc =
      "spiking network grown from a Linda genome: input currents or AER events in, AER spikes out on port 0 (all) "
      "and port 1 (output channels); steps 1 ms steps in batches of its period";
  t.params = {
      {"genome", ParamType::kString, std::string(), 0.0, kMaxGenomeText,
       "the genome: a reference the node resolves, or the genome text itself; set at runtime to regrow"},
      {"seed", ParamType::kInt, std::int64_t{0}, 0.0, 9e15, "development seed (only the genome's noise uses it)"},
      {"pulse", ParamType::kReal, 20.0, -1000.0, 1000.0, "current one AER input event adds to its channel's neurons"},
  };
  for (ParamSpec& s : network_params()) t.params.push_back(std::move(s));
  t.defaults.priority = 2;
  t.defaults.period = 10ms;
  t.defaults.queue_capacity = 8;
  t.make = [resources](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    const std::string& genome = p.string("genome");
    if (genome.empty()) fail("name the genome: genome=REFERENCE (or the genome text)");
    const std::int64_t seed = p.integer("seed");
    auto grown = grow_genome(genome, static_cast<std::uint64_t>(seed), *resources);
    if (!grown) fail(grown.error());
    SpikingNetworkTaskOptions o = network_options(p);
    o.pulse = static_cast<float>(p.real("pulse"));
    o.genome = genome;
    o.seed = seed;
    o.grow = [resources](const std::string& g, std::int64_t s) {
      return grow_genome(g, static_cast<std::uint64_t>(s), *resources);
    };
    auto task = SpikingNetworkTask::create(std::move(grown).value(), std::move(o));
    if (!task) fail(task.error());
    return std::move(task).value();
  };
  return t;
}

os::TaskType izhikevich_type() {
  os::TaskType t;
  t.name = "izhikevich";
  t.doc =
      "a built-in Izhikevich network: example=reference_2003 is the 2003 paper's random 800/200 network with its "
      "thalamic noise input; AER spikes out on port 0";
  t.params = {
      {"example", ParamType::kString, std::string("reference_2003"), 1.0, 64.0, "the example network (reference_2003)"},
      {"excitatory", ParamType::kInt, std::int64_t{800}, 1.0, 20000.0, "excitatory neurons"},
      {"inhibitory", ParamType::kInt, std::int64_t{200}, 0.0, 20000.0, "inhibitory neurons"},
      {"network_seed", ParamType::kInt, std::int64_t{1}, 0.0, 9e15,
       "seed of the network's random parameters and weights (the noise comes from the task's own stream)"},
      {"integration", ParamType::kString, std::string("published"), 1.0, 16.0, "published or euler"},
  };
  for (ParamSpec& s : network_params()) t.params.push_back(std::move(s));
  t.defaults.priority = 2;
  t.defaults.period = 10ms;
  t.defaults.queue_capacity = 8;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    if (p.string("example") != "reference_2003")
      fail("example: unknown network '" + shown(p.string("example")) + "' (known: reference_2003)");
    auto integration = snn::parse_integration(p.string("integration"));
    if (!integration) fail("integration: " + integration.error());
    const auto exc = static_cast<std::size_t>(p.integer("excitatory"));
    const auto inh = static_cast<std::size_t>(p.integer("inhibitory"));
    if ((exc + inh) * (exc + inh) > 25'000'000) fail("the all-to-all example is limited to 5000 neurons");
    kernel::RandomStream random(static_cast<std::uint64_t>(p.integer("network_seed")), 0);
    snn::GrownNetwork net;
    net.spec = snn::reference_network(random, {exc, inh});
    net.spec.integration = *integration;
    SpikingNetworkTaskOptions o = network_options(p);
    o.thalamic = true;
    o.thalamic_excitatory = exc;
    auto task = SpikingNetworkTask::create(std::move(net), std::move(o));
    if (!task) fail(task.error());
    return std::move(task).value();
  };
  return t;
}

os::TaskType encoder_type() {
  const SpikeEncoderOptions d;
  os::TaskType t;
  t.name = "spike_encoder";
  t.doc =
      "sensor vector in on port 0; out on port 0: input currents (coding=current) or rate-coded AER events "
      "(coding=rate), one channel per sensor value";
  t.params = {
      {"coding", ParamType::kString, std::string("current"), 1.0, 16.0, "current or rate"},
      {"input_scale", ParamType::kReal, static_cast<double>(d.input_scale), -1e6, 1e6,
       "sensor values times this, clamped to 0..1 (default 1/4505 for IR)"},
      {"gain", ParamType::kReal, static_cast<double>(d.gain), -1000.0, 1000.0, "current coding: current at 1"},
      {"max_rate", ParamType::kReal, static_cast<double>(d.max_rate), 0.0, 1000.0, "rate coding: Hz at 1"},
      {"window", ParamType::kDuration, d.window, 0.001, 10.0,
       "rate coding: each reading gives events for this long (the sensor period)"},
      {"module", ParamType::kInt, std::int64_t{0}, 0.0, static_cast<double>(snn::kMaxModule), "AER module bits"},
      {"warn_interval", ParamType::kDuration, d.warn_interval, 0.0, 3600.0, "at most one warning per interval"},
  };
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    SpikeEncoderOptions o;
    auto coding = parse_spike_coding(p.string("coding"));
    if (!coding) fail(coding.error());
    o.coding = *coding;
    o.input_scale = static_cast<float>(p.real("input_scale"));
    o.gain = static_cast<float>(p.real("gain"));
    o.max_rate = static_cast<float>(p.real("max_rate"));
    o.window = p.duration("window");
    o.module = static_cast<std::uint32_t>(p.integer("module"));
    o.warn_interval = p.duration("warn_interval");
    auto task = SpikeEncoderTask::create(o);
    if (!task) fail(task.error());
    return std::move(task).value();
  };
  return t;
}

os::TaskType decoder_type() {
  const SpikeDecoderOptions d;
  os::TaskType t;
  t.name = "spike_decoder";
  t.doc =
      "output-channel spikes (AER) in; every period [offset + gain * rate(c)] for each channel out on port 0 "
      "(rates in Hz over the window), clamped to +-speed_limit";
  t.params = {
      {"channels", ParamType::kInt, std::int64_t{2}, 1.0, static_cast<double>(SpikeDecoderTask::kMaxChannels),
       "output channels decoded (2: [left, right])"},
      {"gain", ParamType::kReal, d.gain, -1e6, 1e6, "wheel units per Hz"},
      {"offset", ParamType::kReal, d.offset, -1e6, 1e6, "wheel units at 0 Hz"},
      {"speed_limit", ParamType::kReal, d.speed_limit, 1e-6, 1e6, "commands are clamped to +-this"},
      {"window", ParamType::kDuration, d.window, 0.001, 60.0, "the rate estimate's window"},
      {"warn_interval", ParamType::kDuration, d.warn_interval, 0.0, 3600.0, "at most one warning per interval"},
  };
  t.defaults.priority = 2;
  t.defaults.period = 30ms;
  t.defaults.queue_capacity = 8;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    SpikeDecoderOptions o;
    o.channels = static_cast<std::size_t>(p.integer("channels"));
    o.gain = p.real("gain");
    o.offset = p.real("offset");
    o.speed_limit = p.real("speed_limit");
    o.window = p.duration("window");
    o.warn_interval = p.duration("warn_interval");
    auto task = SpikeDecoderTask::create(o);
    if (!task) fail(task.error());
    return std::move(task).value();
  };
  return t;
}

os::TaskType codec_type() {
  os::TaskType t;
  t.name = "aer_codec";
  t.doc =
      "AER packets in -> their wire form as bytes out on port 0 (for a stream task in frames mode); bytes in -> "
      "AER packets out on port 1: spikes across byte links between nodes";
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 16;
  t.make = [](const os::ParamSet&) -> std::unique_ptr<os::Task> { return std::make_unique<AerCodecTask>(); };
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
    where = "genome '" + shown(reference) + "'";
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
