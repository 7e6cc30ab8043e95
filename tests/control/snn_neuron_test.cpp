// Izhikevich neurons (izhikevich.hpp): the class table and names, one RS neuron's spike times
// against a golden file made by an independent float32 transcription of net.m (see the file's
// header), and the published qualitative behaviour of the classes.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/izhikevich.hpp"

namespace {

using namespace symb::control::snn;

// Spike times (steps at whose start the neuron fired) of a neuron of class `c` from rest.
std::vector<int> spike_times(NeuronClass c, float current, Integration scheme, int steps) {
  const NeuronParams p = params_of(c);
  NeuronState s{kRestVoltage, p.b * kRestVoltage};
  std::vector<int> out;
  for (int t = 0; t < steps; ++t)
    if (step_neuron(s, p, current, scheme)) out.push_back(t);
  return out;
}

std::vector<int> intervals(const std::vector<int>& spikes) {
  std::vector<int> out;
  for (std::size_t k = 1; k < spikes.size(); ++k) out.push_back(spikes[k] - spikes[k - 1]);
  return out;
}

std::map<std::string, std::vector<int>> read_golden() {
  const auto path = std::filesystem::path(SYMB_SCENARIO_DIR) / "snn_rs_spikes.txt";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::map<std::string, std::vector<int>> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string scheme;
    words >> scheme;
    int t = 0;
    while (words >> t) out[scheme].push_back(t);
  }
  return out;
}

TEST(IzhikevichNeuronTest, ClassTableIsFigureTwo) {
  EXPECT_EQ(params_of(NeuronClass::kRS), (NeuronParams{0.02f, 0.2f, -65.0f, 8.0f}));
  EXPECT_EQ(params_of(NeuronClass::kIB), (NeuronParams{0.02f, 0.2f, -55.0f, 4.0f}));
  EXPECT_EQ(params_of(NeuronClass::kCH), (NeuronParams{0.02f, 0.2f, -50.0f, 2.0f}));
  EXPECT_EQ(params_of(NeuronClass::kFS), (NeuronParams{0.1f, 0.2f, -65.0f, 2.0f}));
  EXPECT_EQ(params_of(NeuronClass::kLTS), (NeuronParams{0.02f, 0.25f, -65.0f, 2.0f}));
  EXPECT_EQ(params_of(NeuronClass::kTC), (NeuronParams{0.02f, 0.25f, -65.0f, 0.05f}));
  EXPECT_EQ(params_of(NeuronClass::kRZ), (NeuronParams{0.1f, 0.26f, -65.0f, 2.0f}));
}

TEST(IzhikevichNeuronTest, NamesRoundTripAndErrorsListTheValidOnes) {
  const char* names[] = {"RS", "IB", "CH", "FS", "LTS", "TC", "RZ"};
  for (int k = 0; k < kNeuronClassCount; ++k) {
    const auto c = static_cast<NeuronClass>(k);
    EXPECT_STREQ(to_string(c), names[k]);
    auto parsed = parse_neuron_class(names[k]);
    ASSERT_TRUE(parsed.ok()) << names[k];
    EXPECT_EQ(*parsed, c);
  }
  auto bad = parse_neuron_class("rs");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("'rs'"), std::string::npos) << bad.error();
  EXPECT_NE(bad.error().find("RS, IB, CH, FS, LTS, TC, RZ"), std::string::npos) << bad.error();
  EXPECT_FALSE(parse_neuron_class("").ok());

  EXPECT_STREQ(to_string(Integration::kPublished), "published");
  EXPECT_STREQ(to_string(Integration::kEuler), "euler");
  EXPECT_EQ(*parse_integration("published"), Integration::kPublished);
  EXPECT_EQ(*parse_integration("euler"), Integration::kEuler);
  auto bad_scheme = parse_integration("rk4");
  ASSERT_FALSE(bad_scheme.ok());
  EXPECT_NE(bad_scheme.error().find("published, euler"), std::string::npos) << bad_scheme.error();
}

TEST(IzhikevichNeuronTest, FiresAtTheStartOfTheStepAndIsResetBeforeIntegrating) {
  const NeuronParams p = params_of(NeuronClass::kRS);
  for (Integration scheme : {Integration::kPublished, Integration::kEuler}) {
    NeuronState s{35.0f, 1.0f};
    ASSERT_TRUE(step_neuron(s, p, 0.0f, scheme));
    // Reset to c = -65, u = 9, then one step from there with I = 0: v rises only a little.
    EXPECT_LT(s.v, -60.0f);
    EXPECT_GT(s.u, 8.0f);
    NeuronState below{29.9f, 1.0f};
    EXPECT_FALSE(step_neuron(below, p, 0.0f, scheme));
    EXPECT_GT(below.v, kPeakVoltage);  // crossed during the step: fires at the start of the next
  }
}

TEST(IzhikevichNeuronTest, SchemesFollowTheirFormulas) {
  const NeuronParams p = params_of(NeuronClass::kRS);
  const float v = -60.0f, u = -12.0f, i = 4.0f;
  NeuronState e{v, u};
  step_neuron(e, p, i, Integration::kEuler);
  EXPECT_EQ(e.v, v + (0.04f * (v * v) + 5.0f * v + 140.0f - u + i));
  EXPECT_EQ(e.u, u + p.a * (p.b * v - u));
  NeuronState h{v, u};
  step_neuron(h, p, i, Integration::kPublished);
  const float v1 = v + 0.5f * (0.04f * (v * v) + 5.0f * v + 140.0f - u + i);
  const float v2 = v1 + 0.5f * (0.04f * (v1 * v1) + 5.0f * v1 + 140.0f - u + i);
  EXPECT_EQ(h.v, v2);
  EXPECT_EQ(h.u, u + p.a * (p.b * v2 - u));  // from the NEW v
}

TEST(IzhikevichNeuronTest, RegularSpikingMatchesTheGoldenFile) {
  const auto golden = read_golden();
  ASSERT_EQ(golden.count("published"), 1u);
  ASSERT_EQ(golden.count("euler"), 1u);
  EXPECT_EQ(spike_times(NeuronClass::kRS, 10.0f, Integration::kPublished, 1000), golden.at("published"));
  EXPECT_EQ(spike_times(NeuronClass::kRS, 10.0f, Integration::kEuler, 1000), golden.at("euler"));
  EXPECT_GE(golden.at("published").size(), 15u);  // a sane file: about 20 Hz
}

TEST(IzhikevichNeuronTest, ClassesShowTheirPublishedBehaviour) {
  for (Integration scheme : {Integration::kPublished, Integration::kEuler}) {
    SCOPED_TRACE(to_string(scheme));
    const auto rs = spike_times(NeuronClass::kRS, 10.0f, scheme, 1000);
    const auto fs = spike_times(NeuronClass::kFS, 10.0f, scheme, 1000);
    const auto ib = spike_times(NeuronClass::kIB, 10.0f, scheme, 1000);
    const auto ch = spike_times(NeuronClass::kCH, 10.0f, scheme, 1000);
    // Fast spiking: more than twice the regular-spiking rate under the same current.
    EXPECT_GT(fs.size(), 2 * rs.size());
    // RS adapts: the first interval is the shortest, the later ones are longer.
    const auto rs_isi = intervals(rs);
    ASSERT_GE(rs_isi.size(), 5u);
    EXPECT_LT(rs_isi.front(), *std::min_element(rs_isi.begin() + 2, rs_isi.end()));
    // IB: an initial burst (a short first interval), then tonic spikes far apart.
    const auto ib_isi = intervals(ib);
    ASSERT_GE(ib_isi.size(), 5u);
    EXPECT_LE(ib_isi.front(), 8);
    EXPECT_GE(*std::min_element(ib_isi.end() - 4, ib_isi.end()), 25);
    // CH: repeated bursts: after the onset, both short (in-burst) and long (between-burst) intervals.
    const auto ch_isi = intervals(ch);
    ASSERT_GE(ch_isi.size(), 5u);
    EXPECT_LE(ch_isi.front(), 8);
    const auto late = std::vector<int>(ch_isi.begin() + 5, ch_isi.end());
    EXPECT_GE(std::count_if(late.begin(), late.end(), [](int d) { return d <= 8; }), 5);
    EXPECT_GE(std::count_if(late.begin(), late.end(), [](int d) { return d >= 30; }), 5);
  }
}

TEST(IzhikevichNeuronTest, RestsWithoutInput) {
  for (Integration scheme : {Integration::kPublished, Integration::kEuler})
    for (int k = 0; k < kNeuronClassCount; ++k) {
      const auto c = static_cast<NeuronClass>(k);
      const auto spikes = spike_times(c, 0.0f, scheme, 1000);
      // The resonator's rest lies above -65 mV: starting there it rebounds into one spike, then rests.
      EXPECT_LE(spikes.size(), c == NeuronClass::kRZ ? 1u : 0u) << to_string(c) << " " << to_string(scheme);
    }
}

}  // namespace
