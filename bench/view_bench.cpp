// What the web view (`symb run --view`, apps/view/) costs a run: the real-time factor of the maze
// and the swarm scenario, as fast as possible, with the view open and one client connected, beside
// the same run without the view, interleaved in the same process (bench_report.hpp). Two clients:
//   Reader   reads every frame as a browser does (the target: >= 90 % of no view)
//   Stalled  upgrades to a WebSocket, then never reads: its frames pile up and are dropped; the
//            run must not notice (the frame queue, view_server.hpp)
// Each run is run_scenario as `symb run` calls it (no output folder), timed by its own clock over
// the stepping only (RunResult::real_time_factor). The client connects when the URL is announced,
// before the run starts.
#include <atomic>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/apps/run/scenario_run.hpp"

#include "../tests/support/ws_test_client.hpp"
#include "bench_report.hpp"

namespace {

using namespace std::chrono_literals;

enum class Client { kNone, kReader, kStalled };

struct Case {
  const char* scenario;
  std::chrono::seconds duration;
};
// Simulated time per run: half a second or so of wall clock each on the reference box. The last
// is the 1,000 robots for long enough (about 6 s, 15 KB a pose frame) that a stalled client's socket buffers fill and
// its queue overflows: only then are frames dropped (NoView and ViewStalled only).
constexpr Case kCases[] = {
    {"maze.yaml", 6000s}, {"swarm.yaml", 600s}, {"swarm_1000.yaml", 6s}, {"swarm_1000.yaml", 300s}};
constexpr int kStallCase = 3;

void run_case(benchmark::State& state, Client kind) {
  const Case& c = kCases[state.range(0)];
  double frames = 0, queued = 0, dropped = 0;
  for (auto _ : state) {
    symb::apps::run::RunOptions o;
    o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/" + c.scenario;
    o.duration = c.duration;
    o.speed = 0;
    o.view.on = kind != Client::kNone;
    symb::testing::WsTestClient client;
    std::thread reader;
    std::atomic<std::uint64_t> read{0};
    o.on_notice = [&](const std::string& line) {
      const auto port = line.find(':', line.find("127.0.0.1")) + 1;
      const auto slash = line.find('/', port);
      client.open(static_cast<std::uint16_t>(std::stoi(line.substr(port, slash - port))),
                  "/ws" + line.substr(line.find("?token=")), kind == Client::kStalled ? 4096 : 0);
      if (kind == Client::kReader)
        reader = std::thread([&] {
          while (client.read_frame(10s)) ++read;
          client.close();
        });
    };
    auto r = symb::apps::run::run_scenario(o);
    if (reader.joinable()) reader.join();
    client.close();
    if (!r) {
      state.SkipWithError(r.error().c_str());
      return;
    }
    if (o.view.on && !client.upgraded()) {
      state.SkipWithError("the client did not get a WebSocket");
      return;
    }
    state.SetIterationTime(r->wall_seconds);
    state.counters["rtf"] = r->real_time_factor;
    frames = static_cast<double>(read.load());
    queued = static_cast<double>(r->view_frames);
    dropped = static_cast<double>(r->view_frames_dropped);
  }
  state.counters["frames_read"] = frames;
  state.counters["frames_queued"] = queued;
  state.counters["frames_dropped"] = dropped;
}

void NoView(benchmark::State& state) { run_case(state, Client::kNone); }
void ViewReader(benchmark::State& state) { run_case(state, Client::kReader); }
void ViewStalled(benchmark::State& state) { run_case(state, Client::kStalled); }

BENCHMARK(NoView)->DenseRange(0, 2)->UseManualTime()->Iterations(1)->Repetitions(5)->Unit(benchmark::kMillisecond);
BENCHMARK(ViewReader)->DenseRange(0, 2)->UseManualTime()->Iterations(1)->Repetitions(5)->Unit(benchmark::kMillisecond);
BENCHMARK(ViewStalled)->DenseRange(0, 2)->UseManualTime()->Iterations(1)->Repetitions(5)->Unit(benchmark::kMillisecond);
BENCHMARK(NoView)->Arg(kStallCase)->UseManualTime()->Iterations(1)->Repetitions(2)->Unit(benchmark::kMillisecond);
BENCHMARK(ViewStalled)->Arg(kStallCase)->UseManualTime()->Iterations(1)->Repetitions(2)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::printf(
      "\nReal-time factor with the view open and one client, against no view (medians, interleaved; target >= 90 "
      "%%):\n");
  for (int i = 0; i <= kStallCase; ++i) {
    const std::string arg = "/" + std::to_string(i);
    const double base = reporter.median("NoView" + arg, "rtf");
    const double reader = reporter.median("ViewReader" + arg, "rtf");
    const double stalled = reporter.median("ViewStalled" + arg, "rtf");
    if (base <= 0) continue;
    if (i == kStallCase) {
      std::printf("  %-16s no view %8.1fx   stalled %8.1fx (%5.1f %%, %4.0f of %4.0f frames dropped)\n",
                  "swarm_1000 (long)", base, stalled, 100 * stalled / base,
                  reporter.median("ViewStalled" + arg, "frames_dropped"),
                  reporter.median("ViewStalled" + arg, "frames_queued"));
      continue;
    }
    std::printf(
        "  %-16s no view %8.1fx   reader %8.1fx (%5.1f %%, %4.0f frames read)   stalled %8.1fx (%5.1f %%, %4.0f of "
        "%4.0f frames dropped)\n",
        kCases[i].scenario, base, reader, 100 * reader / base, reporter.median("ViewReader" + arg, "frames_read"),
        stalled, 100 * stalled / base, reporter.median("ViewStalled" + arg, "frames_dropped"),
        reporter.median("ViewStalled" + arg, "frames_queued"));
  }
  for (const auto& e : reporter.errors()) std::printf("error: %s\n", e.c_str());
  return 0;
}
