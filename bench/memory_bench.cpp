// memory_bench: heap bytes the framework spends per task and per hook. Global operator new/delete
// are replaced in this executable by versions that count the bytes requested and returned, so
// every allocation made by the node, its task records, the executor's bookkeeping and the hook
// lists is seen, by the size asked for (not malloc's rounded-up size). Per task: 1000 empty tasks
// with a one-message queue on a VirtualTimeExecutor, minus that queue's storage. Per hook: 1000
// senders hooked to one receiver (fan-in) and one sender hooked to 1000 receivers (fan-out).
// Baseline, for scale: a std::function + std::vector<float> "task" and a raw pointer in a
// std::vector "hook". Targets: <= 512 B per task, <= 64 B per hook. Per robot, the full stack as
// `symb run` builds it for a 2D swarm: 1000 Thymios with the maze demo's MDL2e controller (the
// scenario parsed, the world, the world runner and its drivers, each robot's RobotSystem: node,
// task-type registry, SysLog, tasks, hooks), run for 0.3 s of virtual time; target <= 64 KiB
// per robot (10,000 robots in well under 1 GiB). Wall time per benchmark is the time to build and
// tear down the graph, for reference only.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

#include "bench_report.hpp"
// Private to the os layer; included only for sizeof() in the breakdown.
#include "symb/os/task_record.hpp"

// --- counting allocator ----------------------------------------------------------------------------

namespace {

std::atomic<std::uint64_t> g_requested{0};
std::atomic<std::uint64_t> g_returned{0};
std::atomic<std::uint64_t> g_allocations{0};

// Sizes seen while a measurement window is open, allocated and freed, so the report can say
// which blocks a structure keeps. A fixed table under a spin lock: the allocator must not
// allocate, and executor threads may allocate while a window is open.
struct SizeBin {
  std::size_t size = 0;
  std::uint64_t allocated = 0;
  std::uint64_t freed = 0;
};
constexpr std::size_t kBins = 64;
SizeBin g_bins[kBins];
std::atomic<bool> g_binning{false};
std::atomic_flag g_bins_lock = ATOMIC_FLAG_INIT;

void note_size(std::size_t n, bool allocated) {
  if (!g_binning.load(std::memory_order_relaxed)) return;
  while (g_bins_lock.test_and_set(std::memory_order_acquire)) {
  }
  for (auto& b : g_bins) {
    if (b.allocated == 0 && b.freed == 0) {
      if (!allocated) break;  // a block from before the window: not ours to account
      b.size = n;
    }
    if (b.size == n) {
      ++(allocated ? b.allocated : b.freed);
      break;
    }
  }
  g_bins_lock.clear(std::memory_order_release);
}

// The requested size lives just in front of the block, so delete can return exactly what new
// counted without trusting the sized-delete argument (not every caller passes one).
constexpr std::size_t kHeader = __STDCPP_DEFAULT_NEW_ALIGNMENT__;

void* counted_alloc(std::size_t n, std::size_t align) {
  const std::size_t head = std::max(align, kHeader);
  void* raw = nullptr;
  if (align <= kHeader) {
    raw = std::malloc(n + head);
  } else {
    const std::size_t total = (n + head + align - 1) / align * align;
    raw = std::aligned_alloc(align, total);
  }
  if (raw == nullptr) return nullptr;
  char* user = static_cast<char*>(raw) + head;
  std::memcpy(user - sizeof(std::size_t), &n, sizeof(std::size_t));
  g_requested.fetch_add(n, std::memory_order_relaxed);
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  note_size(n, true);
  return user;
}

void counted_free(void* p, std::size_t align) {
  if (p == nullptr) return;
  char* user = static_cast<char*>(p);
  std::size_t n = 0;
  std::memcpy(&n, user - sizeof(std::size_t), sizeof(std::size_t));
  g_returned.fetch_add(n, std::memory_order_relaxed);
  note_size(n, false);
  std::free(user - std::max(align, kHeader));
}

void* throwing_alloc(std::size_t n, std::size_t align) {
  if (void* p = counted_alloc(n, align)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t n) { return throwing_alloc(n, kHeader); }
void* operator new[](std::size_t n) { return throwing_alloc(n, kHeader); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return counted_alloc(n, kHeader); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return counted_alloc(n, kHeader); }
void* operator new(std::size_t n, std::align_val_t a) { return throwing_alloc(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return throwing_alloc(n, static_cast<std::size_t>(a)); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_alloc(n, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept { counted_free(p, kHeader); }
void operator delete[](void* p) noexcept { counted_free(p, kHeader); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p, kHeader); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p, kHeader); }
void operator delete(void* p, const std::nothrow_t&) noexcept { counted_free(p, kHeader); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { counted_free(p, kHeader); }
void operator delete(void* p, std::align_val_t a) noexcept { counted_free(p, static_cast<std::size_t>(a)); }
void operator delete[](void* p, std::align_val_t a) noexcept { counted_free(p, static_cast<std::size_t>(a)); }
void operator delete(void* p, std::size_t, std::align_val_t a) noexcept {
  counted_free(p, static_cast<std::size_t>(a));
}
void operator delete[](void* p, std::size_t, std::align_val_t a) noexcept {
  counted_free(p, static_cast<std::size_t>(a));
}
void operator delete(void* p, std::align_val_t a, const std::nothrow_t&) noexcept {
  counted_free(p, static_cast<std::size_t>(a));
}
void operator delete[](void* p, std::align_val_t a, const std::nothrow_t&) noexcept {
  counted_free(p, static_cast<std::size_t>(a));
}

namespace {

using namespace symb;

constexpr std::size_t kN = 1000;
constexpr std::size_t kThreadTasks = 100;
constexpr double kTaskTarget = 512;
constexpr double kHookTarget = 64;
constexpr std::size_t kRobots = 1000;
constexpr double kRobotTarget = 64 * 1024;

// Bytes that changed hands between open() and close().
struct Window {
  std::uint64_t requested = 0;  // every byte asked for, transient ones (vector regrowth) included
  std::uint64_t retained = 0;   // asked for and not given back: what the structure keeps
  std::uint64_t allocations = 0;
  std::vector<SizeBin> sizes;

  static Window open() {
    for (auto& b : g_bins) b = SizeBin{};
    Window w;
    w.requested = g_requested.load();
    w.retained = g_requested.load() - g_returned.load();
    w.allocations = g_allocations.load();
    g_binning.store(true);
    return w;
  }
  // Takes the sizes table first: copying it allocates.
  void close() {
    g_binning.store(false);
    while (g_bins_lock.test_and_set(std::memory_order_acquire)) {
    }
    SizeBin snapshot[kBins];
    std::copy(std::begin(g_bins), std::end(g_bins), std::begin(snapshot));
    g_bins_lock.clear(std::memory_order_release);
    requested = g_requested.load() - requested;
    retained = g_requested.load() - g_returned.load() - retained;
    allocations = g_allocations.load() - allocations;
    for (const auto& b : snapshot)
      if (b.allocated > 0) sizes.push_back(b);
    // Largest share of what is kept first.
    std::sort(sizes.begin(), sizes.end(), [](const SizeBin& x, const SizeBin& y) {
      return x.size * (x.allocated - x.freed) > y.size * (y.allocated - y.freed);
    });
  }
};

// What the summary prints, filled by the last iteration of each benchmark (every iteration counts
// the same bytes: nothing here depends on time).
struct Measured {
  double requested_per = 0;
  double retained_per = 0;
  double allocations_per = 0;
  std::vector<SizeBin> sizes;
};
Measured g_task, g_task_thread, g_hook_fan_in, g_hook_fan_out;
Measured g_plain_task, g_plain_hook_fan_in, g_plain_hook_fan_out;
Measured g_robot_parse, g_robot_build, g_robot_run, g_robot;

void record(benchmark::State& state, Measured& out, const Window& w, std::size_t n, std::size_t excluded) {
  out.requested_per = static_cast<double>(w.requested - excluded) / static_cast<double>(n);
  out.retained_per = static_cast<double>(w.retained - excluded) / static_cast<double>(n);
  out.allocations_per = static_cast<double>(w.allocations) / static_cast<double>(n);
  out.sizes = w.sizes;
  state.counters["retained_B_per"] = out.retained_per;
  state.counters["requested_B_per"] = out.requested_per;
  state.counters["allocs_per"] = out.allocations_per;
}

class EmptyTask final : public os::Task {};

// Names are made before the window opens; all fit std::string's inline buffer, so the record's
// copy of the name costs nothing here (a name over 15 characters would add its length).
std::vector<std::string> task_names(std::size_t n, const char* prefix) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < n; ++i) {
    // Appended, not `prefix + std::to_string(i)`: that form trips g++ 12's false -Wrestrict at -O3.
    std::string name = prefix;
    name += std::to_string(i);
    names.push_back(std::move(name));
  }
  return names;
}

os::TaskOptions one_slot_queue() {
  os::TaskOptions o;
  o.queue_capacity = 1;
  return o;
}

void BM_TaskMemory(benchmark::State& state) {
  const auto names = task_names(kN, "t");
  for (auto _ : state) {
    kernel::VirtualTimeExecutor exec;
    os::Node node(exec, os::NodeConfig{.name = "mem"});
    Window w = Window::open();
    for (const auto& name : names) (void)node.create(name, std::make_unique<EmptyTask>(), one_slot_queue());
    exec.run_until_idle();  // start events handled: the steady state of a running graph
    w.close();
    record(state, g_task, w, kN, kN * sizeof(os::Message));
  }
}

// The same on the ThreadExecutor, for reference: thread stacks are mapped by pthread, not through
// operator new, so they stay out of the count as the target asks. Fewer tasks: each is a thread.
void BM_TaskMemoryThreads(benchmark::State& state) {
  constexpr std::size_t n = kThreadTasks;
  const auto names = task_names(n, "t");
  for (auto _ : state) {
    kernel::ThreadExecutor exec;
    os::Node node(exec, os::NodeConfig{.name = "mem"});
    Window w = Window::open();
    for (const auto& name : names) (void)node.create(name, std::make_unique<EmptyTask>(), one_slot_queue());
    w.close();
    record(state, g_task_thread, w, n, n * sizeof(os::Message));
  }
}

void BM_HookMemoryFanIn(benchmark::State& state) {
  const auto names = task_names(kN, "s");
  for (auto _ : state) {
    kernel::VirtualTimeExecutor exec;
    os::Node node(exec, os::NodeConfig{.name = "mem"});
    std::vector<os::TaskId> senders;
    senders.reserve(kN);
    for (const auto& name : names)
      senders.push_back(*node.create(name, std::make_unique<EmptyTask>(), one_slot_queue()));
    const os::TaskId rx = *node.create("rx", std::make_unique<EmptyTask>(), one_slot_queue());
    Window w = Window::open();
    for (os::TaskId s : senders) (void)node.hook(s, rx);
    w.close();
    record(state, g_hook_fan_in, w, kN, 0);
  }
}

void BM_HookMemoryFanOut(benchmark::State& state) {
  const auto names = task_names(kN, "r");
  for (auto _ : state) {
    kernel::VirtualTimeExecutor exec;
    os::Node node(exec, os::NodeConfig{.name = "mem"});
    std::vector<os::TaskId> receivers;
    receivers.reserve(kN);
    for (const auto& name : names)
      receivers.push_back(*node.create(name, std::make_unique<EmptyTask>(), one_slot_queue()));
    const os::TaskId tx = *node.create("tx", std::make_unique<EmptyTask>(), one_slot_queue());
    Window w = Window::open();
    for (os::TaskId r : receivers) (void)node.hook(tx, r);
    w.close();
    record(state, g_hook_fan_out, w, kN, 0);
  }
}

// A swarm as `symb run` builds it: kRobots Thymios at random starts in a 20 x 20 m arena, each
// with the maze demo's MDL2e controller between its IR and its wheels.
std::string swarm_scenario() {
  return "name: swarm\nseed: 7\nduration: 1s\ncontrol_period: 30ms\nworld:\n  arena: {width: 2000, height: 2000}\n"
         "robots:\n  - name: t\n    count: " +
         std::to_string(kRobots) +
         "\n    start: random\n    tasks:\n      - name: controller\n        type: mdl2e\n"
         "        params: {program: " SYMB_SCENARIO_DIR
         "/mdl2e/obstacle_avoidance.mdl2e}\n    hooks:\n      - ir -> controller -> wheels\n";
}

// Three windows, so the report can say where the bytes go: the parsed scenario (kept by `symb run`
// for the whole run), the session built (world, runner, robots), and what running adds (the tasks'
// start, queues and logs in their steady state).
void BM_RobotMemory(benchmark::State& state) {
  const std::string text = swarm_scenario();
  for (auto _ : state) {
    Window parse = Window::open();
    auto scenario = sim::parse_scenario(text, "swarm.yaml", {});
    parse.close();
    if (!scenario) {
      state.SkipWithError(scenario.error().c_str());
      return;
    }
    kernel::VirtualTimeExecutor exec;
    Window build = Window::open();
    auto session = sim::ScenarioSession::create(scenario.value(), exec, {});
    build.close();
    if (!session) {
      state.SkipWithError(session.error().c_str());
      return;
    }
    Window run = Window::open();
    session.value()->start();
    exec.run_for(std::chrono::milliseconds(300));
    run.close();
    record(state, g_robot_parse, parse, kRobots, 0);
    record(state, g_robot_build, build, kRobots, 0);
    record(state, g_robot_run, run, kRobots, 0);
    g_robot.retained_per = g_robot_parse.retained_per + g_robot_build.retained_per + g_robot_run.retained_per;
    g_robot.requested_per = g_robot_parse.requested_per + g_robot_build.requested_per + g_robot_run.requested_per;
    g_robot.allocations_per =
        g_robot_parse.allocations_per + g_robot_build.allocations_per + g_robot_run.allocations_per;
    state.counters["retained_B_per_robot"] = g_robot.retained_per;
    session.value()->stop();
  }
}

// --- baseline --------------------------------------------------------------------------------------

// The least a "task" can be: something to call and somewhere to put its input.
struct PlainTask {
  std::function<void()> body;
  std::vector<float> queue;
};

constexpr std::size_t kPlainQueueFloats = 8;

void BM_PlainTaskMemory(benchmark::State& state) {
  float sink = 0;
  for (auto _ : state) {
    std::vector<PlainTask> tasks;  // grown one by one, like the node's task table
    Window w = Window::open();
    for (std::size_t i = 0; i < kN; ++i)
      tasks.push_back(PlainTask{[&sink] { sink += 1; }, std::vector<float>(kPlainQueueFloats)});
    w.close();
    record(state, g_plain_task, w, kN, kN * kPlainQueueFloats * sizeof(float));
    benchmark::DoNotOptimize(tasks.data());
  }
}

void BM_PlainHookMemoryFanIn(benchmark::State& state) {
  for (auto _ : state) {
    PlainTask rx;
    std::vector<std::vector<PlainTask*>> outputs(kN);
    Window w = Window::open();
    for (auto& out : outputs) out.push_back(&rx);
    w.close();
    record(state, g_plain_hook_fan_in, w, kN, 0);
    benchmark::DoNotOptimize(outputs.data());
  }
}

void BM_PlainHookMemoryFanOut(benchmark::State& state) {
  for (auto _ : state) {
    std::vector<PlainTask> receivers(kN);
    std::vector<PlainTask*> output;
    Window w = Window::open();
    for (auto& r : receivers) output.push_back(&r);
    w.close();
    record(state, g_plain_hook_fan_out, w, kN, 0);
    benchmark::DoNotOptimize(output.data());
  }
}

// Few iterations: the counts are exact after one, and building 1000 tasks is not what is timed.
BENCHMARK(BM_TaskMemory)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PlainTaskMemory)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HookMemoryFanIn)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PlainHookMemoryFanIn)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HookMemoryFanOut)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PlainHookMemoryFanOut)->Iterations(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TaskMemoryThreads)->Iterations(3)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RobotMemory)->Iterations(1)->Unit(benchmark::kMillisecond);

// Blocks still held at the end of the window, by size; blocks that came and went (a table's
// earlier, smaller storage) are summed on one line, as they count in "requested" only.
void print_sizes(const Measured& m, std::size_t n) {
  std::uint64_t transient_blocks = 0;
  std::uint64_t transient_bytes = 0;
  for (const auto& b : m.sizes) {
    transient_blocks += b.freed;
    transient_bytes += b.freed * b.size;
    const std::uint64_t kept = b.allocated - b.freed;
    if (kept == 0) continue;
    const char* what = "";
    if (b.size == sizeof(os::detail::TaskRecord))
      what = "  sizeof(detail::TaskRecord)";
    else if (b.size == sizeof(os::Message))
      what = "  sizeof(Message): the queue slot, excluded";
    else if (b.size == sizeof(EmptyTask))
      what = "  sizeof(Task): the task object itself";
    else if (b.size == sizeof(os::detail::Hook))
      what = "  sizeof(detail::Hook)";
    else if (kept == 1)
      what = "  one table's storage (grows by doubling)";
    // Sizes are only a hint: a private object of the same size shares the line.
    const bool shared = *what != '\0' && kept != 1 && kept != n;
    std::printf("      kept %5llu x %6zu B = %6.1f B per item%s%s\n", static_cast<unsigned long long>(kept), b.size,
                static_cast<double>(kept * b.size) / static_cast<double>(n), what,
                shared ? " (for some; the rest are another type of that size)" : "");
  }
  if (transient_blocks > 0)
    std::printf("      freed again: %llu blocks, %.1f B per item (earlier storage of growing tables)\n",
                static_cast<unsigned long long>(transient_blocks),
                static_cast<double>(transient_bytes) / static_cast<double>(n));
}

const char* verdict(double v, double target) { return v <= target ? "MET" : "NOT MET"; }

}  // namespace

int main(int argc, char** argv) {
  int n = argc;
  benchmark::Initialize(&n, argv);
  if (benchmark::ReportUnrecognizedArguments(n, argv)) return 1;
  symb::bench::CollectingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();

  std::printf(
      "\nheap bytes per item, N = %zu (retained = requested - returned; requested includes transient "
      "vector regrowth)\n",
      kN);
  std::printf("%-44s %12s %12s %10s\n", "", "retained B", "requested B", "allocs");
  const auto line = [](const char* name, const Measured& m) {
    std::printf("%-44s %12.1f %12.1f %10.2f\n", name, m.retained_per, m.requested_per, m.allocations_per);
  };
  line("task, VirtualTimeExecutor (framework)", g_task);
  print_sizes(g_task, kN);
  line("task, ThreadExecutor, N=100 (framework)", g_task_thread);
  print_sizes(g_task_thread, kThreadTasks);
  line("task: std::function + std::vector<float>", g_plain_task);
  line("hook, 1000 senders -> 1 receiver (framework)", g_hook_fan_in);
  print_sizes(g_hook_fan_in, kN);
  line("hook, 1 sender -> 1000 receivers (framework)", g_hook_fan_out);
  print_sizes(g_hook_fan_out, kN);
  line("hook: pointer in a std::vector, fan-in", g_plain_hook_fan_in);
  line("hook: pointer in a std::vector, fan-out", g_plain_hook_fan_out);
  std::printf("sizeof: TaskRecord %zu, Task %zu, Message %zu (Payload %zu), Hook %zu, TaskSlot %zu\n",
              sizeof(os::detail::TaskRecord), sizeof(EmptyTask), sizeof(os::Message), sizeof(os::Payload),
              sizeof(os::detail::Hook), sizeof(os::detail::TaskSlot));
  line("robot, full stack, N=1000 (symb run of a swarm)", g_robot);
  line("  of it: the parsed scenario", g_robot_parse);
  line("  of it: the session built", g_robot_build);
  line("  of it: running 0.3 s", g_robot_run);
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());

  const double hook_worst = std::max(g_hook_fan_in.retained_per, g_hook_fan_out.retained_per);
  std::printf(
      "memory: task %.0f B (queue slot excluded; baseline %.0f B), target <= %.0f B: %s; "
      "hook %.0f B fan-in, %.0f B fan-out (baseline %.0f / %.0f B), target <= %.0f B: %s\n",
      g_task.retained_per, g_plain_task.retained_per, kTaskTarget, verdict(g_task.retained_per, kTaskTarget),
      g_hook_fan_in.retained_per, g_hook_fan_out.retained_per, g_plain_hook_fan_in.retained_per,
      g_plain_hook_fan_out.retained_per, kHookTarget, verdict(hook_worst, kHookTarget));
  std::printf(
      "memory: robot %.0f B (2D Thymio with the maze controller, full stack, 1000 robots), target <= %.0f B: %s\n",
      g_robot.retained_per, kRobotTarget, verdict(g_robot.retained_per, kRobotTarget));
  return 0;
}
