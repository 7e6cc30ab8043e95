// pingpong_bench: cross-thread round-trip latency of the os layer on the ThreadExecutor (one OS
// thread per task). Task A sends a ping to task B, which is hooked back to A and answers; A sends
// the next ping when the answer arrives. Reported: median and p99 round-trip time and round trips
// per second, against the same ping-pong between two plain std::threads over a plain
// std::mutex + std::condition_variable queue, measured in the same run with repetitions of the two
// interleaved at random. Target: framework median latency within 1.5x of the plain one.
//
// Pinning: every ping and pong thread of both sides runs on one fixed core (the first this process
// may use). Left to the scheduler, whether a pair shared a core (a wake is a context switch on the
// spot) or not (a wake is a cross-core interrupt) was settled once per process, differently for
// the two sides, and the median ratio swung from 0.2x to 12x between processes. One core rather
// than one each: on the shared box the other core is usually busy with another tenant, and a
// cross-core wake then waits for that tenant's time slice (medians of 40 us, the same on both
// sides, which hides the hand-off being measured).
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"

#include "bench_report.hpp"

namespace {

using namespace symb;
using SteadyClock = std::chrono::steady_clock;

constexpr os::Port kPing = 1;
constexpr os::Port kPong = 2;
constexpr os::Port kStop = 3;
// A batch is what the benchmark thread times as one iteration; the go and done hand-offs at its
// ends are 2 wakes in 2 * kBatch, too few to move the per-round-trip figures.
constexpr std::size_t kBatch = 500;
constexpr int kBatchesPerRepetition = 1;
constexpr int kRepetitions = 100;
constexpr double kTargetRatio = 1.5;

// The core the ping and the pong threads run on: the first this process may use. -1: no affinity
// could be read, run unpinned.
struct Cores {
  int ping = -1, pong = -1;
};
Cores pick_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return {};
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) return {c, c};
  return {};
}
const Cores g_cores = pick_cores();
bool g_pin_failed = false;  // written by the pinned threads before their first timed round trip

// Pins the calling thread to `core`.
void pin_to(int core) {
  if (core < 0) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(core, &set);
  if (pthread_setaffinity_np(pthread_self(), sizeof(set), &set) != 0) g_pin_failed = true;
}

os::Payload ping_payload() { return os::Payload{1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f, 8.0f}; }

// Round trips of one variant, over all its repetitions.
struct Samples {
  std::vector<std::int64_t> rtt_ns;
  double seconds = 0;
  std::uint64_t round_trips = 0;
};
Samples g_framework;
Samples g_plain;

// How a batch's last round trip tells the benchmark thread, which is no task and so can only wait.
class Done {
 public:
  void reset() {
    std::lock_guard lock(mu_);
    done_ = false;
  }
  void signal() {
    {
      std::lock_guard lock(mu_);
      done_ = true;
    }
    cv_.notify_one();
  }
  void wait() {
    std::unique_lock lock(mu_);
    cv_.wait(lock, [&] { return done_; });
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  bool done_ = false;
};

double percentile(std::vector<std::int64_t> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return static_cast<double>(v[std::min(rank, v.size() - 1)]);
}

void report_repetition(benchmark::State& state, const Samples& s, std::size_t first_sample) {
  const std::vector<std::int64_t> mine(s.rtt_ns.begin() + static_cast<std::ptrdiff_t>(first_sample), s.rtt_ns.end());
  state.counters["median_us"] = percentile(mine, 0.5) / 1e3;
  state.counters["p99_us"] = percentile(mine, 0.99) / 1e3;
  state.counters["round_trips_per_s"] =
      benchmark::Counter(static_cast<double>(mine.size()), benchmark::Counter::kIsRate);
}

// --- framework -------------------------------------------------------------------------------------

class Pinger final : public os::Task {
 public:
  // Set by the benchmark thread before it posts "go"; the post hands them over through the queue's
  // lock, and the task is idle until then, so no race.
  std::size_t remaining = 0;
  bool record = false;
  std::vector<std::int64_t>* samples = nullptr;
  Done* done = nullptr;

 protected:
  // Under the ThreadExecutor a task's handlers run on its own thread: pin it there.
  void on_start() override { pin_to(g_cores.ping); }
  void on_message(const os::Message& m) override {
    if (m.source.valid()) {  // a pong; "go" comes from outside any task
      if (record) samples->push_back((now() - sent_at_).count());
      if (--remaining == 0) {
        done->signal();
        return;
      }
    }
    sent_at_ = now();
    send(kPing, payload_);
  }

 private:
  os::Payload payload_ = ping_payload();
  kernel::Time sent_at_{0};
};

class Ponger final : public os::Task {
 protected:
  void on_start() override { pin_to(g_cores.pong); }
  void on_message(const os::Message& m) override { send(kPong, m.payload); }
};

// The task graph lives across repetitions (see main): a repetition is one batch, and batches of
// the two variants are interleaved at random, so a burst of load from the other tenants of the
// box lands on both sides of the ratio instead of on whichever happened to run then.
class FrameworkRig {
 public:
  FrameworkRig() : node_(exec_, os::NodeConfig{.name = "pingpong"}) {
    auto owned = std::make_unique<Pinger>();
    pinger_ = owned.get();
    pinger_->samples = &g_framework.rtt_ns;
    pinger_->done = &done_;
    os::TaskOptions opts;
    opts.queue_capacity = 4;
    auto a = node_.create("ping", std::move(owned), opts);
    auto b = node_.create("pong", std::make_unique<Ponger>(), opts);
    os::HookOptions h;
    h.policy = os::QueuePolicy::kRefuse;
    ok_ = a && b && node_.hook(*a, *b, h) && node_.hook(*b, *a, h);
    if (ok_) ping_ = *a;
  }
  bool ok() const { return ok_; }
  // Seconds for kBatch round trips; negative if the batch could not start.
  double run_batch(bool record) {
    pinger_->remaining = kBatch;
    pinger_->record = record;
    done_.reset();
    const auto t0 = SteadyClock::now();
    if (!node_.post(ping_, os::Message{})) return -1;
    done_.wait();
    return std::chrono::duration<double>(SteadyClock::now() - t0).count();
  }
  std::uint64_t dropped() const { return node_.traffic().dropped(); }

 private:
  kernel::ThreadExecutor exec_;
  os::Node node_;
  Pinger* pinger_ = nullptr;
  os::TaskId ping_;
  Done done_;
  bool ok_ = false;
};

// --- plain baseline --------------------------------------------------------------------------------

// The textbook blocking queue: a fixed ring under one mutex, a condition variable for "not empty".
// Fixed storage rather than std::deque, whose 512-byte blocks would make it allocate every second
// message of this size and lose for a reason that has nothing to do with the hand-off.
template <class T>
class MutexQueue {
 public:
  explicit MutexQueue(std::size_t capacity) : slots_(capacity) {}

  bool push(const T& v) {
    {
      std::lock_guard lock(mu_);
      if (size_ == slots_.size()) return false;
      slots_[(head_ + size_) % slots_.size()] = v;
      ++size_;
    }
    not_empty_.notify_one();
    return true;
  }
  T pop() {
    std::unique_lock lock(mu_);
    not_empty_.wait(lock, [&] { return size_ > 0; });
    T v = slots_[head_];
    head_ = (head_ + 1) % slots_.size();
    --size_;
    return v;
  }

 private:
  std::mutex mu_;
  std::condition_variable not_empty_;
  std::vector<T> slots_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

// The same work as the framework's tasks: a Message built per send with source, port, timestamp
// and payload copy, so the comparison is about the hand-off and not about the message.
os::Message make_message(os::TaskId source, os::Port port, const os::Payload& payload, SteadyClock::time_point epoch) {
  os::Message m;
  m.source = source;
  m.port = port;
  m.time = std::chrono::duration_cast<kernel::Time>(SteadyClock::now() - epoch);
  m.payload = payload;
  return m;
}

class PlainRig {
 public:
  PlainRig() {
    b_ = std::thread([this] {
      pin_to(g_cores.pong);
      for (;;) {
        const os::Message m = to_b_.pop();
        if (m.port == kStop) return;
        to_a_.push(make_message(kIdB, kPong, m.payload, epoch_));
      }
    });
    a_ = std::thread([this] {
      pin_to(g_cores.ping);
      const os::Payload payload = ping_payload();
      SteadyClock::time_point sent_at;
      for (;;) {
        const os::Message m = to_a_.pop();
        if (m.port == kStop) return;
        if (m.source.valid()) {
          if (record_) g_plain.rtt_ns.push_back((SteadyClock::now() - sent_at).count());
          if (--remaining_ == 0) {
            done_.signal();
            continue;
          }
        }
        sent_at = SteadyClock::now();
        to_b_.push(make_message(kIdA, kPing, payload, epoch_));
      }
    });
  }
  ~PlainRig() {
    os::Message stop;
    stop.port = kStop;
    to_a_.push(stop);
    to_b_.push(stop);
    a_.join();
    b_.join();
  }
  PlainRig(const PlainRig&) = delete;
  PlainRig& operator=(const PlainRig&) = delete;

  // As FrameworkRig::run_batch: the "go" message, like Node::post, comes from no task.
  double run_batch(bool record) {
    remaining_ = kBatch;
    record_ = record;
    done_.reset();
    const auto t0 = SteadyClock::now();
    if (!to_a_.push(os::Message{})) return -1;
    done_.wait();
    return std::chrono::duration<double>(SteadyClock::now() - t0).count();
  }

 private:
  static constexpr os::TaskId kIdA{0, 0};
  static constexpr os::TaskId kIdB{1, 0};
  const SteadyClock::time_point epoch_ = SteadyClock::now();
  MutexQueue<os::Message> to_a_{4};
  MutexQueue<os::Message> to_b_{4};
  Done done_;
  // Handed over to thread a through to_a_'s lock, as the pinger's fields are.
  std::size_t remaining_ = 0;
  bool record_ = false;
  std::thread a_;
  std::thread b_;
};

std::unique_ptr<FrameworkRig> g_framework_rig;
std::unique_ptr<PlainRig> g_plain_rig;

template <class Rig>
void run_repetition(benchmark::State& state, Rig* rig, Samples& samples) {
  if (rig == nullptr) {
    state.SkipWithError("rig not built");
    return;
  }
  const std::size_t first = samples.rtt_ns.size();
  for (auto _ : state) {
    const double s = rig->run_batch(true);
    if (s < 0) {
      state.SkipWithError("could not start a batch");
      return;
    }
    state.SetIterationTime(s);
    samples.seconds += s;
    samples.round_trips += kBatch;
  }
  report_repetition(state, samples, first);
}

void BM_PingPong_Framework(benchmark::State& state) { run_repetition(state, g_framework_rig.get(), g_framework); }
void BM_PingPong_Plain(benchmark::State& state) { run_repetition(state, g_plain_rig.get(), g_plain); }

BENCHMARK(BM_PingPong_Framework)
    ->UseManualTime()
    ->Iterations(kBatchesPerRepetition)
    ->Repetitions(kRepetitions)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PingPong_Plain)
    ->UseManualTime()
    ->Iterations(kBatchesPerRepetition)
    ->Repetitions(kRepetitions)
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  auto args = symb::bench::with_default_flags(argc, argv, {"--benchmark_enable_random_interleaving=true"});
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  // Sample storage is taken up front so that no round trip pays for a vector growing.
  const std::size_t capacity = kBatch * kBatchesPerRepetition * kRepetitions * 2;
  g_framework.rtt_ns.reserve(capacity);
  g_plain.rtt_ns.reserve(capacity);
  g_framework_rig = std::make_unique<FrameworkRig>();
  if (!g_framework_rig->ok()) g_framework_rig.reset();
  g_plain_rig = std::make_unique<PlainRig>();
  // Fresh threads and cold caches are not what we measure.
  for (int i = 0; i < 2; ++i) {
    if (g_framework_rig) g_framework_rig->run_batch(false);
    g_plain_rig->run_batch(false);
  }
  // Aggregates only on the console: a line per repetition would bury the summary.
  symb::bench::CollectingReporter reporter(/*show_repetitions=*/false);
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  const std::uint64_t framework_drops = g_framework_rig ? g_framework_rig->dropped() : 0;
  g_framework_rig.reset();
  g_plain_rig.reset();

  // Two views of each variant. Pooled: every round trip of every batch, so p99 and the overall
  // rate include the batches that ran while another tenant of the box had a core. Per batch: the
  // median over batches of each batch's own figure, which those few slow batches cannot move.
  struct Row {
    const char* name;
    std::size_t n;
    double median_us, p99_us, p999_us, pooled_per_s;
    double batch_p99_us, batch_per_s;
  };
  const auto row = [&](const char* name, const char* benchmark, const Samples& s) {
    return Row{name,
               s.rtt_ns.size(),
               percentile(s.rtt_ns, 0.5) / 1e3,
               percentile(s.rtt_ns, 0.99) / 1e3,
               percentile(s.rtt_ns, 0.999) / 1e3,
               s.seconds > 0 ? static_cast<double>(s.round_trips) / s.seconds : 0.0,
               reporter.median(benchmark, "p99_us"),
               reporter.median(benchmark, "round_trips_per_s")};
  };
  const Row fw = row("framework (ThreadExecutor)", "BM_PingPong_Framework", g_framework);
  const Row plain = row("plain mutex+condvar", "BM_PingPong_Plain", g_plain);
  const auto ratio = [](double x, double y) { return y > 0 ? x / y : 0.0; };

  std::printf("\nping-pong round trips: %d batches of %zu per variant, interleaved at random\n", kRepetitions, kBatch);
  // Round trips per second is the batch's length over its time, so it carries the mean, and with it
  // the rare round trip stalled for a scheduler slice by another process: p99.9 shows those.
  std::printf("%-28s %8s | %11s %10s %10s %13s | %10s %13s\n", "", "", "pooled", "", "", "", "median", "batch");
  std::printf("%-28s %8s | %11s %10s %10s %13s | %10s %13s\n", "variant", "samples", "median [us]", "p99 [us]",
              "p99.9 [us]", "round trips/s", "p99 [us]", "round trips/s");
  for (const Row& x : {fw, plain})
    std::printf("%-28s %8zu | %11.2f %10.2f %10.1f %13.0f | %10.2f %13.0f\n", x.name, x.n, x.median_us, x.p99_us,
                x.p999_us, x.pooled_per_s, x.batch_p99_us, x.batch_per_s);
  std::printf("%-28s %8s | %11.2f %10.2f %10.2f %13.2f | %10.2f %13.2f\n", "ratio framework/plain", "",
              ratio(fw.median_us, plain.median_us), ratio(fw.p99_us, plain.p99_us), ratio(fw.p999_us, plain.p999_us),
              ratio(fw.pooled_per_s, plain.pooled_per_s), ratio(fw.batch_p99_us, plain.batch_p99_us),
              ratio(fw.batch_per_s, plain.batch_per_s));
  std::printf("framework drops: %llu\n", static_cast<unsigned long long>(framework_drops));
  if (g_pin_failed)
    std::printf("ERROR could not pin the threads to cores %d and %d\n", g_cores.ping, g_cores.pong);
  else
    std::printf("ping threads on core %d, pong threads on core %d (both sides)\n", g_cores.ping, g_cores.pong);
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());

  const double r = ratio(fw.median_us, plain.median_us);
  const bool met = fw.n > 0 && plain.n > 0 && r <= kTargetRatio && reporter.errors().empty() && framework_drops == 0 &&
                   !g_pin_failed;
  std::printf(
      "pingpong: framework median %.1f us, p99 %.1f us (median batch p99 %.1f us), %.0f round trips/s; "
      "plain mutex+condvar median %.1f us, p99 %.1f us (median batch p99 %.1f us), %.0f round trips/s; "
      "median ratio %.2f, target <= %.1f: %s\n",
      fw.median_us, fw.p99_us, fw.batch_p99_us, fw.batch_per_s, plain.median_us, plain.p99_us, plain.batch_p99_us,
      plain.batch_per_s, r, kTargetRatio, met ? "MET" : "NOT MET");
  return 0;
}
