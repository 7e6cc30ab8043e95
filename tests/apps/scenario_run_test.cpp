// `symb run`'s output folder: besides the trajectory, steps and summary, every sample a controller
// probes lands in probes.csv and each probed series gets a picture; the probe recorder thins long
// series evenly and keeps every sample in the CSV.
#include "symb/apps/run/scenario_run.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/run/probe_recorder.hpp"
#include "symb/control/snn/aedat.hpp"

namespace symb::apps::run {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ScenarioRun, ProbesOfTheControllersReachTheOutputFolder) {
  const fs::path out = fs::temp_directory_path() / ("symb_run_probes_" + std::to_string(::getpid()));
  fs::remove_all(out);
  RunOptions o;
  o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/ahhs_obstacle_avoidance.yaml";
  o.duration = 3s;
  o.out_dir = out;
  auto r = run_scenario(o);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->steps, 100u);
  const std::string csv = read(out / "probes.csv");
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.rfind("time_s,robot,task,channel,values...\n", 0), 0u);
  EXPECT_NE(csv.find(",thymio,controller,hormones/c0,"), std::string::npos) << csv.substr(0, 400);
  // One picture per probed series, each an SVG with a polyline.
  std::size_t pictures = 0;
  for (const auto& e : fs::directory_iterator(out / "probes")) {
    ++pictures;
    const std::string svg = read(e.path());
    EXPECT_NE(svg.find("<svg"), std::string::npos);
    EXPECT_NE(svg.find("<polyline"), std::string::npos) << e.path();
  }
  EXPECT_GE(pictures, 2u);
  fs::remove_all(out);
}

// Two tasks hooked in a ring that answer every message (issue 15): the robot's node cuts the cycle
// (os/message.hpp, kMaxHops) and the run stops at once with an error that names it, under both
// executors, instead of never leaving its first instant.
TEST(ScenarioRun, AHookCycleStopsTheRunWithAnErrorNamingIt) {
  std::ifstream in(std::string(SYMB_SCENARIO_DIR) + "/braitenberg.yaml");
  std::ostringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto replace = [&yaml](const std::string& from, const std::string& to) {
    const auto at = yaml.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    yaml.replace(at, from.size(), to);
  };
  replace("weights: network/", std::string("weights: ") + SYMB_SCENARIO_DIR + "/network/");
  replace("    hooks:\n",
          "      - {name: a, type: mlp, params: {inputs: 2, layers: \"2\"}}\n"
          "      - {name: b, type: mlp, params: {inputs: 2, layers: \"2\"}}\n"
          "    hooks:\n      - controller -> a\n      - a -> b\n      - b -> a\n");
  const fs::path file = fs::temp_directory_path() / ("symb_run_cycle_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream out(file, std::ios::binary);
    out << yaml;
  }
  for (const bool realtime : {false, true}) {
    RunOptions o;
    o.scenario_path = file.string();
    o.realtime = realtime;
    o.duration = realtime ? std::chrono::duration_cast<kernel::Duration>(20s) : kernel::Duration{10min};
    const auto t0 = std::chrono::steady_clock::now();
    auto r = run_scenario(o);
    ASSERT_FALSE(r.ok()) << (realtime ? "threads" : "virtual time");
    EXPECT_NE(r.error().find("node 'thymio': message cycle "), std::string::npos) << r.error();
    EXPECT_TRUE(r.error().find("a -> b -> a") != std::string::npos ||
                r.error().find("b -> a -> b") != std::string::npos)
        << r.error();
    // Stopped at the cut: the first slice (1 s of virtual time) or the first check (0.1 s).
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 15s) << (realtime ? "threads" : "virtual time");
  }
  fs::remove(file);
}

// A spiking controller (linda_maze.yaml): its spikes land in an AEDAT 2.0 file that reads back
// with exactly the spikes the run counted, in time order, from neurons the grown network has;
// beside it a raster and the grown network's picture.
TEST(ScenarioRun, SpikingControllersWriteAedatRasterAndNetworkPicture) {
  const fs::path out = fs::temp_directory_path() / ("symb_run_spikes_" + std::to_string(::getpid()));
  fs::remove_all(out);
  RunOptions o;
  o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/linda_maze.yaml";
  o.duration = 5s;
  o.out_dir = out;
  auto r = run_scenario(o);
  ASSERT_TRUE(r.ok()) << r.error();
  const fs::path dir = out / "spikes";
  const std::string bytes = read(dir / "thymio_controller.aedat");
  auto file = control::snn::read_aedat(bytes);
  ASSERT_TRUE(file.ok()) << file.error();
  ASSERT_GT(file->events.size(), 100u) << "the motor neurons fire tonically";
  std::uint32_t last = 0;
  for (const control::snn::AerEvent& e : file->events) {
    EXPECT_LT(control::snn::aer_neuron(e.address), 7u);  // the avoider genome grows 7 neurons
    EXPECT_GE(e.timestamp_us, last);
    EXPECT_LT(e.timestamp_us, 5'000'000u);
    last = e.timestamp_us;
  }
  // The run's own count of spikes: the rate probe (Hz per neuron per 10 ms batch) summed back.
  double counted = 0;
  std::istringstream csv(read(out / "probes.csv"));
  for (std::string line; std::getline(csv, line);)
    if (line.find(",thymio,controller,rate,") != std::string::npos)
      counted += std::stod(line.substr(line.rfind(',') + 1)) * 7 * 0.010;
  EXPECT_NEAR(counted, static_cast<double>(file->events.size()), 1.0);
  const std::string network = read(dir / "thymio_controller_network.svg");
  EXPECT_NE(network.find("7 neurons, 10 synapses"), std::string::npos) << network.substr(0, 300);
  EXPECT_NE(read(dir / "thymio_controller_raster.svg").find("<circle"), std::string::npos);
  fs::remove_all(out);
}

TEST(ProbeRecorder, KeepsEverySampleInTheCsvAndThinsTheSeriesEvenly) {
  std::ostringstream csv;
  ProbeRecorder rec(&csv);
  const auto sink = rec.sink();
  const std::size_t n = 3 * ProbeRecorder::kMaxPoints;
  for (std::size_t i = 0; i < n; ++i) {
    const float v[2] = {static_cast<float>(i), -1.0f};
    sink(os::ProbeSample{kernel::Time{std::chrono::milliseconds(30 * i)}, "r", "t", "ch", v});
  }
  sink(os::ProbeSample{kernel::Time{0}, "r", "u", "other", {}});
  EXPECT_EQ(rec.samples(), n + 1);
  const auto series = rec.series();
  ASSERT_EQ(series.size(), 2u);
  const ProbeSeries& s = *series[0];
  EXPECT_EQ(s.samples, n);
  EXPECT_EQ(s.width, 2u);
  EXPECT_LT(s.times.size(), ProbeRecorder::kMaxPoints);
  EXPECT_GT(s.times.size(), ProbeRecorder::kMaxPoints / 2);
  // Evenly spaced: every kept sample is a multiple of the final stride apart.
  const double step = s.values[1][0] - s.values[0][0];
  EXPECT_GE(step, 2);
  for (std::size_t i = 1; i < s.values.size(); ++i) EXPECT_EQ(s.values[i][0] - s.values[i - 1][0], step) << i;
  // The CSV has every sample.
  std::size_t lines = 0;
  for (char c : csv.str()) lines += c == '\n';
  EXPECT_EQ(lines, n + 2);  // header, n samples, the empty one
  EXPECT_EQ(probe_file_name(*series[1]), "r.u.other.svg");
  std::ostringstream svg;
  write_probe_svg(svg, s);
  EXPECT_NE(svg.str().find("ch[1]"), std::string::npos);
}

}  // namespace
}  // namespace symb::apps::run
