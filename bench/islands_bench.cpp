// islands_bench: throughput of the island model (`symb evolve --islands` under mpirun) with 1, 2
// and 4 ranks on this machine, in evaluations per second of wall clock (all islands together,
// mpirun's start and end included), beside the same work without MPI in the same run: one plain
// `symb evolve` of the same scenario, duration and seed. Repetitions of the four are interleaved
// at random. Each island runs the maze's (1+1)-ONLINE evolution for 2 h of simulated time with
// a migration every 10 min. Reported: evaluations/s per rank count and its ratio to the plain run
// (the figure the cores and MPI's start give); no pass/fail target (issue 19 asks for the figures).
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include <benchmark/benchmark.h>

#include "bench_report.hpp"

namespace {

namespace fs = std::filesystem;
using SteadyClock = std::chrono::steady_clock;

constexpr int kRepetitions = 3;
const fs::path g_dir = fs::temp_directory_path() / ("bench_islands_" + std::to_string(::getpid()));

std::string read_all(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `command`; the evaluations it reports (from `report`, summing every "evaluations" figure).
void run(benchmark::State& state, const std::string& command, const fs::path& report, bool islands) {
  for (auto _ : state) {
    std::error_code ec;
    fs::remove_all(g_dir / "run", ec);
    const auto t0 = SteadyClock::now();
    if (std::system(command.c_str()) != 0) {
      state.SkipWithError(("failed: " + command).c_str());
      return;
    }
    const double s = std::chrono::duration<double>(SteadyClock::now() - t0).count();
    state.SetIterationTime(s);
    const std::string text = read_all(report);
    double evaluations = 0;
    if (islands) {
      static const std::regex row(R"(\n\d+  \d+  (\d+)  \d+  )");
      for (auto it = std::sregex_iterator(text.begin(), text.end(), row); it != std::sregex_iterator(); ++it)
        evaluations += std::stod((*it)[1]);
    } else {
      std::smatch m;
      if (std::regex_search(text, m, std::regex(R"(evaluations: (\d+))"))) evaluations = std::stod(m[1]);
    }
    if (evaluations == 0) {
      state.SkipWithError("no evaluations reported");
      return;
    }
    state.counters["evaluations"] = evaluations;
    state.counters["evaluations_per_s"] = evaluations / s;
  }
}

std::string evolve_args() {
  return std::string(SYMB_BINARY) + " evolve " + SYMB_SCENARIO_DIR +
         "/evolve_maze.yaml --duration 2h --checkpoint-every 0 --quiet --seed 1 --out " + (g_dir / "run").string();
}

void BM_PlainEvolve(benchmark::State& state) {
  run(state, evolve_args() + " > /dev/null", g_dir / "run" / "summary.txt", false);
}

void BM_Islands(benchmark::State& state) {
  const std::string command =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe --mca btl self,vader --mca "
      "oob_tcp_if_include lo -np " +
      std::to_string(state.range(0)) + " " + evolve_args() + " --islands --migrate-every 10min > /dev/null";
  run(state, command, g_dir / "run" / "islands.txt", true);
}

BENCHMARK(BM_PlainEvolve)->UseManualTime()->Iterations(1)->Repetitions(kRepetitions)->Unit(benchmark::kSecond);
BENCHMARK(BM_Islands)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->UseManualTime()
    ->Iterations(1)
    ->Repetitions(kRepetitions)
    ->Unit(benchmark::kSecond);

}  // namespace

int main(int argc, char** argv) {
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0) {
    std::printf("islands_bench: no mpirun (Debian openmpi-bin): skipped\n");
    return 0;
  }
  symb::bench::CollectingReporter reporter(false);
  const bool ran = symb::bench::run_interleaved(argc, argv, reporter);
  std::error_code ec;
  fs::remove_all(g_dir, ec);
  if (!ran) return 1;
  const double plain = reporter.median("BM_PlainEvolve", "evaluations_per_s");
  std::printf("\nevaluations per second of wall clock (median of %d), 2 h of maze evolution per island:\n",
              kRepetitions);
  std::printf("  plain symb evolve (one run, no MPI): %8.1f\n", plain);
  for (int ranks : {1, 2, 4}) {
    const double e = reporter.median("BM_Islands/" + std::to_string(ranks), "evaluations_per_s");
    std::printf("  --islands, %d rank%s:                 %8.1f  (%.2fx the plain run)\n", ranks, ranks > 1 ? "s" : " ",
                e, plain > 0 ? e / plain : 0.0);
  }
  std::printf("summary: island model on %u cores: %.2fx the plain run's evaluations/s at 2 ranks, %.2fx at 4\n",
              std::thread::hardware_concurrency(),
              plain > 0 ? reporter.median("BM_Islands/2", "evaluations_per_s") / plain : 0.0,
              plain > 0 ? reporter.median("BM_Islands/4", "evaluations_per_s") / plain : 0.0);
  return 0;
}
