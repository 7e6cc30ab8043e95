// Control loop latency on a Thymio II over the Aseba protocol, against Aseba Playground on a local
// TCP port (issue 22). Two ways of closing one loop, interleaved in the same run:
//
//   BM_ControlLoop  the framework: robot::thymio::AsebaThymio reads prox.horizontal, the `ir`
//                   sensor task, the scenario's MDL2e maze controller and the `wheels` sink (a
//                   ThreadExecutor, as `symb board --robot aseba:tcp:...` runs them) write
//                   motor.*.target. One sample: from sending the get variables to writing the
//                   wheel command that answers it.
//   BM_RawGetSet    the baseline written here: a blocking socket, get variables for the same 7
//                   words by hand, wait for the reply, write set variables for the two targets.
//                   One sample: the same span.
//
// Both include Playground's own answer time (it answers between its simulation steps), so the
// ratio is the framework's cost on top of the round trip. Median and p99 of every sample, then the
// ratio of the medians. The box is shared and noisy: compare the ratio, not the absolute times.
// Without asebaplayground the program says so and exits 0.
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "symb/io/tcp_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/robot/thymio_aseba.hpp"
#include "symb/sim/playground_world.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

#include "bench_report.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace symb;
using Clock = std::chrono::steady_clock;

constexpr int kLoopsPerRepetition = 60;

std::uint16_t g_port = 0;

// Playground serves one client at a time per robot, and a client that connects before it has
// noticed the previous one leave gets no answers: each run waits for that after closing.
void let_playground_notice() { std::this_thread::sleep_for(500ms); }
sim::Scenario g_scenario;
std::mutex g_samples_mu;
std::vector<double> g_loop_us, g_raw_us, g_own_us;

// The wheels the controller drives: each command goes on to the Thymio; the first one after each
// new IR sample records how long after that sample was asked for it was written.
class TimedWheels final : public robot::Actuator {
 public:
  TimedWheels(std::shared_ptr<robot::thymio::AsebaThymio> t)
      : robot::Actuator("wheels", t->wheels()->channels()), thymio_(std::move(t)) {}
  // Samples recorded so far.
  std::vector<double> take() {
    std::lock_guard lock(mu_);
    return std::move(latencies_us_);
  }
  // The framework's own part of each: from the answer's arrival to the wheel write.
  std::vector<double> take_own() {
    std::lock_guard lock(mu_);
    return std::move(own_us_);
  }
  std::size_t count() {
    std::lock_guard lock(mu_);
    return latencies_us_.size();
  }

 protected:
  kernel::Status apply(std::span<const float> values) override {
    auto st = thymio_->wheels()->set(values);
    if (!st) return kernel::Error{st.error()};
    const auto latest = thymio_->ir()->latest();
    if (!latest || latest->time == last_sample_) return {};
    last_sample_ = latest->time;
    const auto now = std::chrono::duration_cast<kernel::Duration>(Clock::now().time_since_epoch());
    const kernel::Duration round_trip = thymio_->stats().last_round_trip;  // of this sample: the next is 30 ms away
    std::lock_guard lock(mu_);
    latencies_us_.push_back(std::chrono::duration<double, std::micro>(now - latest->time).count());
    own_us_.push_back(std::chrono::duration<double, std::micro>(now - latest->time - round_trip).count());
    return {};
  }

 private:
  std::shared_ptr<robot::thymio::AsebaThymio> thymio_;
  kernel::Time last_sample_{0};
  std::mutex mu_;
  std::vector<double> latencies_us_, own_us_;
};

void BM_ControlLoop(benchmark::State& state) {
  auto stream = io::TcpStream::connect("127.0.0.1", g_port, 2s);
  if (!stream) return state.SkipWithError(stream.error().c_str());
  robot::thymio::AsebaThymioOptions o;
  o.control_period = g_scenario.control_period;
  o.reply_timeout = g_scenario.control_period;
  auto thymio = robot::thymio::AsebaThymio::create(std::shared_ptr<io::IOStream>(std::move(stream).value()), o);
  if (auto st = thymio->connect(); !st) return state.SkipWithError(st.error().c_str());
  auto wheels = std::make_shared<TimedWheels>(thymio);
  (void)thymio->wheels()->open();
  kernel::ThreadExecutor executor;
  sim::RobotSystemOptions ro;
  ro.control_period = g_scenario.control_period;
  ro.read_program = sim::file_program_reader(g_scenario.base_dir);
  sim::RobotDevices devices;
  devices.ir = thymio->ir();
  devices.wheels = wheels;
  auto built = sim::RobotSystem::build(executor, g_scenario.robots.front(), devices, ro);
  if (!built) return state.SkipWithError(built.error().c_str());
  thymio->start();
  // The first loops warm up (the node's description messages still arriving).
  while (wheels->count() < 5) std::this_thread::sleep_for(1ms);
  (void)wheels->take();
  (void)wheels->take_own();
  std::vector<double> got;
  for (auto _ : state) {
    const auto deadline = Clock::now() + 2s;
    while (wheels->count() == 0 && Clock::now() < deadline) std::this_thread::sleep_for(200us);
    auto v = wheels->take();
    if (v.empty()) return state.SkipWithError("no wheel command for 2 s");
    state.SetIterationTime(v.front() * 1e-6);
    got.push_back(v.front());
  }
  const std::vector<double> own = wheels->take_own();
  thymio->stop();
  built.value().reset();
  thymio->link().stream().close();
  let_playground_notice();
  std::lock_guard lock(g_samples_mu);
  g_loop_us.insert(g_loop_us.end(), got.begin(), got.end());
  g_own_us.insert(g_own_us.end(), own.begin(), own.end());
}

// The baseline: the loop by hand over a plain blocking socket.
void BM_RawGetSet(benchmark::State& state) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(g_port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    if (fd >= 0) ::close(fd);
    return state.SkipWithError("cannot connect");
  }
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  const timeval patience{2, 0};  // a reply that never comes fails the run instead of hanging it
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &patience, sizeof patience);
  auto put = [](std::uint8_t* p, std::uint16_t v) {
    p[0] = static_cast<std::uint8_t>(v & 0xFF);
    p[1] = static_cast<std::uint8_t>(v >> 8);
  };
  // get variables (node 1, prox.horizontal at 42, 7 words); set variables (node 1, 57, 0, 0).
  std::uint8_t get[12], set[14];
  put(get, 6), put(get + 2, 0), put(get + 4, 0xA00B), put(get + 6, 1), put(get + 8, 42), put(get + 10, 7);
  put(set, 8), put(set + 2, 0), put(set + 4, 0xA00C), put(set + 6, 1), put(set + 8, 57), put(set + 10, 0),
      put(set + 12, 0);
  std::vector<std::uint8_t> in;
  std::uint8_t buf[4096];
  // Reads until a variables message starting at 42 arrives (skipping the rest).
  auto await_reply = [&]() -> bool {
    for (;;) {
      while (in.size() >= 6) {
        const std::size_t len = in[0] | (in[1] << 8);
        if (in.size() < 6 + len) break;
        const std::uint16_t type = static_cast<std::uint16_t>(in[4] | (in[5] << 8));
        const bool ours = type == 0x9005 && len >= 2 && (in[6] | (in[7] << 8)) == 42;
        in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(6 + len));
        if (ours) return true;
      }
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) return false;
      in.insert(in.end(), buf, buf + n);
    }
  };
  std::vector<double> got;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const char* failed = ::send(fd, get, sizeof get, MSG_NOSIGNAL) != sizeof get   ? "send get"
                         : !await_reply()                                          ? "await reply"
                         : ::send(fd, set, sizeof set, MSG_NOSIGNAL) != sizeof set ? "send set"
                                                                                   : nullptr;
    if (failed != nullptr) {
      const std::string why = std::string("socket: ") + failed + ": " + std::strerror(errno);
      ::close(fd);
      return state.SkipWithError(why.c_str());
    }
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    state.SetIterationTime(us * 1e-6);
    got.push_back(us);
    // Pace it like the control loop, so both see Playground at the same phase spread.
    std::this_thread::sleep_until(t0 + g_scenario.control_period);
  }
  ::close(fd);
  let_playground_notice();
  std::lock_guard lock(g_samples_mu);
  g_raw_us.insert(g_raw_us.end(), got.begin(), got.end());
}

BENCHMARK(BM_ControlLoop)
    ->UseManualTime()
    ->Iterations(kLoopsPerRepetition)
    ->Repetitions(5)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RawGetSet)
    ->UseManualTime()
    ->Iterations(kLoopsPerRepetition)
    ->Repetitions(5)
    ->Unit(benchmark::kMicrosecond);

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

std::string find_playground() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin"}) {
    const fs::path p = fs::path(dir) / "asebaplayground";
    if (::access(p.c_str(), X_OK) == 0) return p;
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string binary = find_playground();
  if (binary.empty()) {
    std::printf("bench_aseba: asebaplayground is not installed (Debian package aseba); nothing measured\n");
    return 0;
  }
  auto loaded = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/maze.yaml");
  if (!loaded) {
    std::fprintf(stderr, "bench_aseba: %s\n", loaded.error().c_str());
    return 1;
  }
  g_scenario = std::move(loaded).value();
  {
    auto l = io::TcpListener::bind("127.0.0.1", 0);
    if (!l) return 1;
    g_port = (*l)->port();
  }
  const fs::path dir = fs::temp_directory_path() / ("symb_bench_aseba_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "world.playground") << *sim::playground_world(g_scenario, g_port);
  std::fflush(stdout);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("QT_QPA_PLATFORM", "offscreen", 1);
    ::setenv("HOME", dir.c_str(), 1);
    ::setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
    const std::string log = (dir / "playground.log").string();
    if (std::FILE* f = std::freopen(log.c_str(), "a", stdout)) (void)f;
    ::dup2(::fileno(stdout), 2);
    ::execl(binary.c_str(), "asebaplayground", (dir / "world.playground").c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool listening = false;
  for (int i = 0; i < 150 && !listening; ++i) {
    listening = static_cast<bool>(io::TcpStream::connect("127.0.0.1", g_port, 200ms));
    if (!listening) std::this_thread::sleep_for(100ms);
  }
  let_playground_notice();
  int status = 0;
  if (!listening) {
    std::fprintf(stderr, "bench_aseba: Playground did not listen on port %u\n", static_cast<unsigned>(g_port));
    status = 1;
  } else {
    symb::bench::CollectingReporter reporter(false);
    if (!symb::bench::run_interleaved(argc, argv, reporter)) status = 1;
    for (const auto& e : reporter.errors()) std::fprintf(stderr, "bench_aseba: %s\n", e.c_str());
    const double loop_median = quantile(g_loop_us, 0.5), raw_median = quantile(g_raw_us, 0.5);
    std::printf("\ncontrol loop over TCP to Aseba Playground (maze.yaml's MDL2e controller), %zu and %zu samples:\n",
                g_loop_us.size(), g_raw_us.size());
    std::printf("  framework (get -> ir -> mdl2e -> wheels -> set): median %.0f us, p99 %.0f us\n", loop_median,
                quantile(g_loop_us, 0.99));
    std::printf("  raw get/set by hand:                             median %.0f us, p99 %.0f us\n", raw_median,
                quantile(g_raw_us, 0.99));
    std::printf("  the framework's own part (answer arrived -> wheel write): median %.0f us, p99 %.0f us\n",
                quantile(g_own_us, 0.5), quantile(g_own_us, 0.99));
    if (raw_median > 0)
      std::printf("  framework / raw: %.2fx the median (+%.0f us)\n", loop_median / raw_median,
                  loop_median - raw_median);
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  if (status == 0 && !std::getenv("SYMB_KEEP")) fs::remove_all(dir);
  return status;
}
