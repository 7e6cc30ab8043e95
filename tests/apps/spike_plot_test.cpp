// The spike pictures of `symb run`: rasters and grown networks come out as well-formed SVG (every
// tag closed, in order) with one dot per spike, one circle per neuron, one line per synapse in the
// colour of its sign, channel marks, escaped titles, and big rasters thinned with a note.
#include "symb/apps/run/spike_plot.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

namespace symb::apps::run {
namespace {

using control::snn::GrownNetwork;
using control::snn::NeuronClass;
using control::snn::params_of;

// Whether every element is closed in order; comments, the XML declaration and self-closing tags
// are accepted. A '<' in text (an unescaped title) breaks it.
bool well_formed(const std::string& svg, std::string* why) {
  std::vector<std::string_view> open;
  std::size_t i = 0;
  while ((i = svg.find('<', i)) != std::string::npos) {
    const std::size_t end = svg.find('>', i);
    if (end == std::string::npos) return *why = "unterminated tag at " + std::to_string(i), false;
    const std::string_view tag = std::string_view(svg).substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return *why = "empty tag", false;
    if (tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      const std::string_view name = tag.substr(1);
      if (open.empty() || open.back() != name) return *why = "</" + std::string(name) + "> closes nothing open", false;
      open.pop_back();
      continue;
    }
    const std::string_view name = tag.substr(0, tag.find_first_of(" \t\n/"));
    for (char c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) return *why = "bad tag name '" + std::string(name) + "'", false;
    if (tag.back() != '/') open.push_back(name);
  }
  if (!open.empty()) return *why = "<" + std::string(open.back()) + "> never closed", false;
  return true;
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
  return n;
}

void expect_well_formed(const std::string& svg) {
  std::string why;
  EXPECT_TRUE(well_formed(svg, &why)) << why;
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_EQ(count(svg, "<svg "), 1u);
}

TEST(SpikePlot, RasterHasOneDotPerSpike) {
  std::vector<SpikeDot> spikes;
  for (std::uint32_t t = 0; t < 100; ++t) spikes.push_back({t * 0.013, t % 20});
  const std::string svg = raster_svg(spikes, 20, "robot 1 / linda <net> & co");
  expect_well_formed(svg);
  EXPECT_EQ(count(svg, "<circle"), 100u);
  EXPECT_NE(svg.find("linda &lt;net&gt; &amp; co"), std::string::npos);
  EXPECT_NE(svg.find("(100 spikes)"), std::string::npos);
  EXPECT_NE(svg.find("time (s)"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

TEST(SpikePlot, RasterDotsSitInTheirRowsAndTimes) {
  const std::vector<SpikeDot> spikes{{0.0, 0}, {1.0, 9}};
  const std::string svg = raster_svg(spikes, 10, "two");
  expect_well_formed(svg);
  ASSERT_EQ(count(svg, "<circle"), 2u);
  const auto attr = [&](std::size_t circle, const std::string& name) {
    std::size_t at = 0;
    for (std::size_t k = 0; k <= circle; ++k) at = svg.find("<circle", at + 1);
    at = svg.find(name + "=\"", at) + name.size() + 2;
    return std::stod(svg.substr(at));
  };
  EXPECT_LT(attr(0, "cx"), attr(1, "cx")) << "later spikes to the right";
  EXPECT_GT(attr(0, "cy"), attr(1, "cy")) << "neuron 0 at the bottom";
}

TEST(SpikePlot, RasterSkipsBadTimesAndGrowsRowsForHighNeurons) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<SpikeDot> spikes{{0.1, 3}, {nan, 1}, {std::numeric_limits<double>::infinity(), 2}, {0.2, 40}};
  const std::string svg = raster_svg(spikes, 4, "bad");
  expect_well_formed(svg);
  EXPECT_EQ(count(svg, "<circle"), 2u);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
  const std::string empty = raster_svg({}, 0, "silent");
  expect_well_formed(empty);
  EXPECT_EQ(count(empty, "<circle"), 0u);
}

TEST(SpikePlot, BigRastersAreThinnedAndSaySo) {
  std::vector<SpikeDot> spikes(450'000);
  for (std::size_t i = 0; i < spikes.size(); ++i)
    spikes[i] = {static_cast<double>(i) * 1e-4, static_cast<std::uint32_t>(i % 500)};
  const std::string svg = raster_svg(spikes, 500, "busy");
  expect_well_formed(svg);
  EXPECT_EQ(count(svg, "<circle"), 150'000u) << "every 3rd of 450,000";
  EXPECT_NE(svg.find("450000 spikes, thinned: 1 in 3 shown"), std::string::npos);
  const std::vector<SpikeDot> at_limit(kMaxRasterDots, SpikeDot{0.5, 1});
  const std::string full = raster_svg(at_limit, 2, "full");
  EXPECT_EQ(count(full, "<circle"), kMaxRasterDots);
  EXPECT_EQ(full.find("thinned"), std::string::npos);
}

GrownNetwork small_network() {
  GrownNetwork g;
  g.width = 4;
  g.height = 3;
  const NeuronClass cls[] = {NeuronClass::kRS, NeuronClass::kFS, NeuronClass::kCH, NeuronClass::kRS};
  const int xs[] = {0, 3, 1, 2}, ys[] = {0, 0, 2, 1};
  for (int i = 0; i < 4; ++i) {
    g.spec.neurons.push_back(params_of(cls[i]));
    g.classes.push_back(cls[i]);
    g.x.push_back(xs[i]);
    g.y.push_back(ys[i]);
    g.cell_ids.push_back(static_cast<std::uint32_t>(i * 2));
  }
  g.spec.synapses = {{0, 1, 5.0f, 1}, {1, 2, -8.0f, 0}, {2, 3, 2.0f, 3}, {3, 0, 1.0f, 1}, {0, 2, -0.5f, 2}};
  g.inputs = {{0}, {2}};
  g.outputs = {{1, 3}};
  return g;
}

TEST(SpikePlot, NetworkDrawsNeuronsSynapsesAndChannels) {
  const GrownNetwork g = small_network();
  const std::string svg = network_svg(g, "linda <gen 3>");
  expect_well_formed(svg);
  EXPECT_EQ(count(svg, "<circle"), 4u);
  EXPECT_EQ(count(svg, "<line"), 5u);
  EXPECT_EQ(count(svg, "marker-end=\"url(#ex)\""), 3u);
  EXPECT_EQ(count(svg, "marker-end=\"url(#in)\""), 2u);
  EXPECT_EQ(count(svg, ">in 0<"), 1u);
  EXPECT_EQ(count(svg, ">in 1<"), 1u);
  EXPECT_EQ(count(svg, ">out 0<"), 2u);
  EXPECT_NE(svg.find("linda &lt;gen 3&gt;"), std::string::npos);
  EXPECT_NE(svg.find("4 neurons, 5 synapses, 4x3 grid"), std::string::npos);
  for (const char* name : {"RS", "IB", "CH", "FS", "LTS", "TC", "RZ"})
    EXPECT_NE(svg.find(std::string(">") + name + " neuron<"), std::string::npos) << name;
  // The strongest synapse is the widest.
  EXPECT_NE(svg.find("stroke-width=\"3.00\""), std::string::npos);
}

TEST(SpikePlot, NetworkSurvivesBrokenLayouts) {
  GrownNetwork g = small_network();
  g.spec.synapses.push_back({0, 17, 1.0f, 0});  // target out of range
  g.spec.synapses.push_back({2, 2, 1.0f, 0});   // a self-synapse: a stub
  g.x.pop_back();                               // neuron 3 has no site
  g.outputs.push_back({99});
  const std::string svg = network_svg(g, "broken");
  expect_well_formed(svg);
  EXPECT_EQ(count(svg, "<circle"), 3u);
  EXPECT_EQ(count(svg, "<line"), 4u) << "0->1, 1->2, 0->2 and the self-synapse";
  const std::string empty = network_svg(GrownNetwork{}, "nothing grew");
  expect_well_formed(empty);
  EXPECT_EQ(count(empty, "<circle"), 0u);
  EXPECT_EQ(count(empty, "<line"), 0u);
}

}  // namespace
}  // namespace symb::apps::run
