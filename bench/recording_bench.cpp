// What recording a 2D run's steps costs at 1,000 robots (issue 17): the steps of a real run (a
// 1,000-robot obstacle-avoidance swarm on a 20 x 20 m arena, 100 steps of 30 ms, recorded once
// before the benchmarks) written again and again as
//   CsvPrintf  steps.csv the way it was written before: snprintf per number (the baseline)
//   Csv        steps.csv as `symb run` writes it now: std::to_chars into one buffer per step
//   Hdf5       steps.h5 (apps/run/steps_h5.hpp): chunked, shuffled, deflated arrays
// each for every step and for every 10th (--record-every 10). Counters: CPU milliseconds per
// world step (CPU time: steadier than the wall clock on the shared box) and bytes per step.
// The summary prints each against CsvPrintf measured in the same run.
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/apps/run/steps_csv.hpp"
#include "symb/apps/run/steps_h5.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

#include "bench_report.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kRobots = 1000;
constexpr int kSteps = 100;

struct Recorded {
  std::vector<symb::sim::StepRecord> steps;
  std::vector<std::string> names;
};

const Recorded& recorded() {
  static const Recorded r = [] {
    Recorded out;
    const std::string yaml =
        "name: rec\nseed: 7\nduration: 10s\ncontrol_period: 30ms\nworld:\n"
        "  arena: {width: 2000, height: 2000}\nrobots:\n  - name: t\n    count: " +
        std::to_string(kRobots) +
        "\n    start: random\n    tasks:\n      - name: controller\n        type: mdl2e\n"
        "        params: {program: " SYMB_SCENARIO_DIR
        "/mdl2e/obstacle_avoidance.mdl2e}\n    hooks:\n      - ir -> controller -> wheels\n";
    auto scenario = symb::sim::parse_scenario(yaml, "recording_bench.yaml");
    if (!scenario) throw std::runtime_error(scenario.error());
    symb::kernel::VirtualTimeExecutor executor;
    auto session = symb::sim::ScenarioSession::create(*scenario, executor);
    if (!session) throw std::runtime_error(session.error());
    for (std::size_t i = 0; i < (*session)->world().robot_count(); ++i)
      out.names.push_back((*session)->world().robot_name(i));
    (*session)->runner().add_observer([&out](const symb::sim::StepRecord& s) { out.steps.push_back(s); });
    (*session)->start();
    executor.run_until(executor.clock().now() + kSteps * 30ms);
    (*session)->stop();
    out.steps.resize(std::min<std::size_t>(out.steps.size(), kSteps));
    return out;
  }();
  return r;
}

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

fs::path scratch(const char* name) {
  return fs::temp_directory_path() / ("symb_recording_bench_" + std::to_string(::getpid()) + name);
}

// Writes every `every`-th recorded step with `write_step`; counters per world step.
template <class Open, class WriteStep, class Close>
void record(benchmark::State& state, Open open, WriteStep write_step, Close close) {
  const Recorded& r = recorded();
  const auto every = static_cast<std::size_t>(state.range(0));
  double cpu = 0, bytes = 0;
  for (auto _ : state) {
    const double c0 = cpu_seconds();
    auto sink = open();
    for (std::size_t t = 0; t < r.steps.size(); t += every) write_step(sink, r.steps[t]);
    bytes += static_cast<double>(close(sink));
    cpu += cpu_seconds() - c0;
  }
  const double steps = static_cast<double>(state.iterations()) * static_cast<double>(r.steps.size());
  state.counters["cpu_ms_per_step"] = 1e3 * cpu / steps;
  state.counters["bytes_per_step"] = bytes / steps;
}

void CsvPrintf(benchmark::State& state) {
  const fs::path path = scratch(".printf.csv");
  const auto& names = recorded().names;
  record(
      state, [&] { return std::make_unique<std::ofstream>(path, std::ios::binary); },
      [&](auto& out, const symb::sim::StepRecord& rec) {
        char buf[96];
        for (std::size_t i = 0; i < rec.robots.size(); ++i) {
          const symb::sim::RobotState& s = rec.robots[i].state;
          std::snprintf(buf, sizeof buf, "%.3f,", static_cast<double>(rec.step) * 0.03);
          *out << buf << names[i];
          std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%.4f", s.pose.x, s.pose.y, s.pose.theta);
          *out << buf;
          for (float v : rec.robots[i].ir) {
            std::snprintf(buf, sizeof buf, ",%.1f", static_cast<double>(v));
            *out << buf;
          }
          std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%d\n", s.left_speed, s.right_speed, s.in_contact ? 1 : 0);
          *out << buf;
        }
      },
      [&](auto& out) {
        out->close();
        return fs::file_size(path);
      });
  fs::remove(path);
}

void Csv(benchmark::State& state) {
  const fs::path path = scratch(".csv");
  const auto& names = recorded().names;
  std::string text;
  record(
      state, [&] { return std::make_unique<std::ofstream>(path, std::ios::binary); },
      [&](auto& out, const symb::sim::StepRecord& rec) {
        text.clear();
        for (std::size_t i = 0; i < rec.robots.size(); ++i)
          symb::apps::run::append_steps_csv_row(text, static_cast<double>(rec.step) * 0.03, names[i], rec.robots[i]);
        out->write(text.data(), static_cast<std::streamsize>(text.size()));
      },
      [&](auto& out) {
        out->close();
        return fs::file_size(path);
      });
  fs::remove(path);
}

void Hdf5(benchmark::State& state) {
  const fs::path path = scratch(".h5");
  symb::apps::run::StepsH5Meta meta;
  meta.robot_count = kRobots;
  meta.record_every = static_cast<std::uint32_t>(state.range(0));
  meta.robots = recorded().names;
  for (std::size_t i = 0; i < meta.robots.size(); ++i) meta.robot_indices.push_back(i);
  record(
      state,
      [&] {
        auto h5 = symb::apps::run::StepsH5::create(path, meta);
        if (!h5) throw std::runtime_error(h5.error());
        return std::move(h5).value();
      },
      [&](auto& h5, const symb::sim::StepRecord& rec) { h5->append(rec, static_cast<double>(rec.step) * 0.03); },
      [&](auto& h5) {
        if (auto st = h5->close(3, false); !st) throw std::runtime_error(st.error());
        return fs::file_size(path);
      });
  fs::remove(path);
}

BENCHMARK(CsvPrintf)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->Repetitions(5);
BENCHMARK(Csv)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->Repetitions(5);
BENCHMARK(Hdf5)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->Repetitions(5);

}  // namespace

int main(int argc, char** argv) {
  (void)recorded();  // the run, before any timing
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::printf("\n1,000 robots, per world step (median of the repetitions; CPU time):\n");
  std::printf("%-14s %12s %12s %16s\n", "writer", "CPU ms", "bytes", "CPU vs printf");
  for (const char* every : {"1", "10"}) {
    const double base = reporter.median(std::string("CsvPrintf/") + every, "cpu_ms_per_step");
    for (const char* name : {"CsvPrintf", "Csv", "Hdf5"}) {
      const std::string key = std::string(name) + "/" + every;
      const double ms = reporter.median(key, "cpu_ms_per_step");
      std::printf("%-14s %12.3f %12.0f %15.2fx\n", (std::string(name) + " every " + every).c_str(), ms,
                  reporter.median(key, "bytes_per_step"), base > 0 ? ms / base : 0.0);
    }
  }
  for (const std::string& e : reporter.errors()) std::printf("error: %s\n", e.c_str());
  return 0;
}
