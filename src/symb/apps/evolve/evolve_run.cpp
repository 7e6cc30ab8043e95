#include "symb/apps/evolve/evolve_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <sstream>
#include <string_view>
#include <thread>
#include <utility>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/evolve/evolve_checkpoint.hpp"
#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/run/run_control.hpp"
#include "symb/apps/text_file.hpp"
#include "symb/apps/view/live_view.hpp"
#include "symb/evo/genome/genome.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::apps::evolve {

namespace {

namespace fs = std::filesystem;
using kernel::Error;

constexpr std::size_t kMeanWindow = 20;
// The evolution task types symb evolve can watch: both publish "fitness", their best so far
// ("champion_fitness" / "best_fitness"), "evaluations" and "champion" genes.
constexpr std::string_view kEvolutionTypes[] = {"one_plus_one", "mu_plus_one"};

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

std::string exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// Written beside, then renamed over: a kill never leaves half a checkpoint.
kernel::Status write_file_atomically(const fs::path& path, const std::string& text) {
  fs::path tmp = path;
  tmp += ".tmp";
  if (auto st = write_file(tmp, text); !st) return st;
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) return Error{"cannot write " + path.string() + ": " + ec.message()};
  return {};
}

struct NewChampion {
  kernel::Time time{0};
  std::uint64_t evaluation = 0;  // the evaluation that made it
  std::vector<float> genes;
  float sigma = 0;
  float fitness = 0;
};

// Collects the evolution task's probe samples into evaluation rows and champions. The samples of
// one evaluation come in the task's order: fitness, champion_fitness, sigma, evaluations, and
// (on a new champion) champion.
class Watcher {
 public:
  Watcher(std::string node, std::string task) : node_(std::move(node)), task_(std::move(task)) {}

  void record(const os::ProbeSample& s) {
    if (s.node != node_ || s.task != task_ || s.values.empty()) return;
    std::lock_guard lock(mu_);
    if (s.channel == "fitness") {
      pending_ = EvaluationRow{};
      pending_.time = s.time;
      pending_.fitness = s.values[0];
      pending_.kind = s.values.size() > 1 ? static_cast<int>(s.values[1]) : 0;
    } else if (s.channel == "champion_fitness" || s.channel == "best_fitness") {
      pending_.champion_fitness = s.values[0];
    } else if (s.channel == "sigma") {
      pending_.sigma = s.values[0];
    } else if (s.channel == "evaluations") {
      pending_.evaluations = static_cast<std::uint64_t>(s.values[0]);
      rows_.push_back(pending_);
    } else if (s.channel == "immigrants" && s.values.size() >= 2) {
      immigrants_taken_ = static_cast<std::uint64_t>(s.values[1]);
    } else if (s.channel == "champion") {
      champions_.push_back({s.time, pending_.evaluations, std::vector<float>(s.values.begin(), s.values.end()),
                            pending_.sigma, pending_.fitness});
    }
  }

  // What came since the last take.
  std::vector<EvaluationRow> take_rows() {
    std::lock_guard lock(mu_);
    return std::exchange(rows_, {});
  }
  std::vector<NewChampion> take_champions() {
    std::lock_guard lock(mu_);
    return std::exchange(champions_, {});
  }
  // Migrants that entered the population (the task's "immigrants" probe).
  std::uint64_t immigrants_taken() {
    std::lock_guard lock(mu_);
    return immigrants_taken_;
  }

 private:
  std::string node_, task_;
  std::mutex mu_;
  EvaluationRow pending_;
  std::vector<EvaluationRow> rows_;
  std::vector<NewChampion> champions_;
  std::uint64_t immigrants_taken_ = 0;
};

struct GenomeFrame {
  double lo = -4, hi = 4, sigma_min = 1e-4, sigma_max = 4;
};

evo::RealGenome make_genome(const NewChampion& c, const GenomeFrame& f) {
  evo::RealGenome g;
  g.lo = f.lo;
  g.hi = f.hi;
  g.sigma_min = f.sigma_min;
  g.sigma_max = f.sigma_max;
  // Floats, as the network drove with them; a rounding step outside the bounds is put back.
  for (float v : c.genes) g.values.push_back(std::clamp(static_cast<double>(v), f.lo, f.hi));
  g.sigma = std::clamp(static_cast<double>(c.sigma), f.sigma_min, f.sigma_max);
  return g;
}

std::string genome_file_text(const NewChampion& c, const GenomeFrame& f, const std::string& scenario) {
  return "# champion of symb evolve " + scenario + ": evaluation " + std::to_string(c.evaluation) + " at " +
         fixed(seconds(c.time), 2) + " s, fitness when it won " + exact(c.fitness) +
         "\n# replay: symb run scenarios/braitenberg.yaml --genome THIS_FILE\n" +
         evo::to_text(evo::Genome{make_genome(c, f)});
}

}  // namespace

kernel::Result<EvolveResult> run_evolution(const EvolveOptions& options) {
  auto scenario_text = read_file(options.scenario_path);
  if (!scenario_text) return Error{scenario_text.error()};
  auto loaded = sim::load_scenario(options.scenario_path);
  if (!loaded) return Error{loaded.error()};
  sim::Scenario scenario = std::move(loaded).value();
  if (options.duration) scenario.duration = *options.duration;
  const std::uint64_t scenario_hash = fnv1a(*scenario_text);

  // The evolution task: the first of its type.
  std::string robot_name, task_name;
  for (const sim::RobotSpec& r : scenario.robots)
    for (const sim::TaskSpec& t : r.tasks)
      if (robot_name.empty() &&
          std::find(std::begin(kEvolutionTypes), std::end(kEvolutionTypes), t.type) != std::end(kEvolutionTypes))
        robot_name = r.name, task_name = t.name;
  if (robot_name.empty())
    return Error{options.scenario_path +
                 ": no evolution task (a task of type one_plus_one or mu_plus_one; see scenarios/evolve_maze.yaml)"};

  const fs::path out = options.out_dir;
  const fs::path checkpoint_path = out / "checkpoint.txt";
  std::optional<EvolveCheckpoint> checkpoint;
  std::optional<std::uint64_t> seed = options.seed;
  if (options.resume) {
    auto text = read_file(checkpoint_path);
    if (!text) return Error{"--resume: no checkpoint to resume from (" + text.error() + ")"};
    auto parsed = parse_checkpoint(*text);
    if (!parsed) return Error{checkpoint_path.string() + ":" + parsed.error()};
    checkpoint = *parsed;
    if (checkpoint->scenario_hash != scenario_hash)
      return Error{"--resume: " + options.scenario_path + " is not the scenario file the checkpoint was made with " +
                   "(its contents changed)"};
    if (seed && *seed != checkpoint->seed)
      return Error{"--resume: --seed " + std::to_string(*seed) + " differs from the checkpoint's seed " +
                   std::to_string(checkpoint->seed)};
    seed = checkpoint->seed;
    if (!options.duration) scenario.duration = checkpoint->duration;
    if (scenario.duration < checkpoint->time)
      return Error{"--resume: --duration is shorter than the time the checkpoint reached (" +
                   fixed(seconds(checkpoint->time), 1) + " s)"};
  }

  std::error_code ec;
  fs::create_directories(out / "champions", ec);
  if (ec) return Error{"cannot create " + (out / "champions").string() + ": " + ec.message()};
  std::ofstream csv(out / "fitness.csv", std::ios::binary | std::ios::trunc);
  if (!csv) return Error{"cannot write " + (out / "fitness.csv").string()};
  csv << "time_s,kind,fitness,champion_fitness,sigma,evaluations\n";

  kernel::VirtualTimeExecutor executor;
  sim::SessionOptions session_options;
  session_options.seed = seed;
  auto created = sim::ScenarioSession::create(scenario, executor, session_options);
  if (!created) return Error{created.error()};
  std::unique_ptr<sim::ScenarioSession> session = std::move(created).value();
  sim::RobotSystem* robot = session->find_robot(robot_name);
  if (!robot) return Error{"the scenario's robot '" + robot_name + "' is missing from the session"};
  os::Node& node = robot->node();
  const auto evolution_id = node.find(task_name);
  if (!evolution_id) return Error{"the evolution task '" + task_name + "' was not created"};
  GenomeFrame frame;
  if (auto p = node.parameters(*evolution_id); p.ok()) {
    // (mu+1) mutates with one fixed sigma: its genomes' sigma range is that one value.
    const bool fixed_sigma = p->find("sigma_min") == nullptr;
    frame = {p->real("lo"), p->real("hi"), p->real(fixed_sigma ? "sigma" : "sigma_min"),
             p->real(fixed_sigma ? "sigma" : "sigma_max")};
  } else {
    return Error{"the evolution task's parameters: " + p.error()};
  }

  EvolveResult result;
  result.scenario = scenario.name;
  result.seed = session->seed();
  Watcher watcher(node.name(), task_name);
  // The web view: made before the sink, which hands it the evolving robot's probes too.
  run::RunControl control(options.speed, scenario.control_period);
  std::unique_ptr<view::LiveView> live;
  if (options.view.on) {
    view::LiveViewOptions vo = view::live_view_options(options.view, robot_name);
    vo.fitness_robot = robot_name;  // its fitness plotted over the whole run, whoever is shown
    vo.fitness_task = task_name;
    auto started = view::LiveView::start(*session, scenario.name, seconds(scenario.duration), &control, std::move(vo));
    if (!started) return Error{started.error()};
    live = std::move(started).value();
    if (options.on_notice) options.on_notice("view: " + live->url());
  }
  node.set_probe_sink([&watcher, &live](const os::ProbeSample& s) {
    watcher.record(s);
    if (live) live->on_probe(s);
  });
  struct ProbeSinkGuard {  // the sink points at `watcher`, which goes before the session
    os::Node& n;
    ~ProbeSinkGuard() { n.set_probe_sink({}); }
  } probe_sink_guard{node};

  EvaluationHistory history;
  std::deque<float> recent;
  double best = 0;
  std::optional<NewChampion> champion;
  const auto flush = [&]() -> kernel::Status {
    const std::vector<EvaluationRow> rows = watcher.take_rows();
    for (const EvaluationRow& r : rows) {
      history.add(r);
      csv << fixed(seconds(r.time), 3) << "," << r.kind << "," << exact(r.fitness) << "," << exact(r.champion_fitness)
          << "," << exact(r.sigma) << "," << r.evaluations << "\n";
      recent.push_back(r.fitness);
      if (recent.size() > kMeanWindow) recent.pop_front();
      best = r.champion_fitness;
    }
    for (NewChampion& c : watcher.take_champions()) {
      char name[48];
      std::snprintf(name, sizeof name, "champion_%06llu.genome", static_cast<unsigned long long>(c.evaluation));
      if (auto st = write_file(out / "champions" / name, genome_file_text(c, frame, options.scenario_path)); !st)
        return st;
      ++result.champions;
      champion = std::move(c);
    }
    // On disk as it goes: a process killed (an island's rank) keeps every evaluation up to here.
    if (!rows.empty()) csv.flush();
    if (!csv) return Error{"cannot write " + (out / "fitness.csv").string()};
    return {};
  };

  const auto wall_start = std::chrono::steady_clock::now();
  const auto wall_seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  const kernel::Time start = executor.clock().now();
  const kernel::Time end = start + scenario.duration;
  // Where a resumed run's replay ends (kTimeNever: not replaying).
  kernel::Time resume_at = checkpoint ? start + checkpoint->time : kernel::kTimeNever;
  const auto replaying = [&] { return resume_at != kernel::kTimeNever; };
  const kernel::Time stop_at = options.stop_at ? start + *options.stop_at : kernel::kTimeNever;
  const bool checkpoints = options.checkpoint_every.count() > 0;
  kernel::Time next_checkpoint = checkpoints ? start + options.checkpoint_every : kernel::kTimeNever;
  const bool migrating = options.migrate && options.migrate_every.count() > 0;
  kernel::Time next_migration = migrating ? start + options.migrate_every : kernel::kTimeNever;
  // Pacing (--speed) runs from the resume point: the replay before it goes as fast as it can.
  auto pace_start = wall_start;
  kernel::Time pace_from = replaying() ? resume_at : start;
  auto last_report = wall_start;

  const auto report = [&](kernel::Time t) {
    if (!options.on_progress) return;
    EvolveProgress p;
    p.simulated_seconds = seconds(t - start);
    p.total_seconds = seconds(scenario.duration);
    p.wall_seconds = wall_seconds();
    p.evaluations = history.size();
    p.best = best;
    double sum = 0;
    for (float f : recent) sum += f;
    p.mean = recent.empty() ? 0 : sum / static_cast<double>(recent.size());
    p.per_second = p.wall_seconds > 0 ? static_cast<double>(history.size()) / p.wall_seconds : 0;
    p.replaying = replaying();
    options.on_progress(p);
  };

  session->start();
  double paced_speed = control.speed();
  for (kernel::Time t = start; t < end;) {
    if (live) {
      // The page's controls (not while replaying to a checkpoint): paused, the run stands at t,
      // serving the page's shell, until resumed or asked for a step (one control period).
      bool step = false, waited = false;
      while (!replaying() && control.paused() && !(step = control.take_step())) {
        waited = true;
        executor.wait_injected(std::chrono::milliseconds(20));
        executor.run_until(t);
        live->between_slices();
      }
      if (control.speed() != paced_speed || step || waited) {
        paced_speed = control.speed();
        pace_start = std::chrono::steady_clock::now();
        pace_from = t;
      }
      if (step) {
        executor.run_until(t = std::min(end, t + control.step_length()));
        if (auto st = flush(); !st) return Error{st.error()};
        live->between_slices();
        continue;
      }
    }
    const double speed = live ? paced_speed : options.speed;
    const kernel::Duration slice =
        speed > 0 ? std::chrono::milliseconds(20) : std::chrono::milliseconds(live ? 100 : 1000);
    kernel::Time next = std::min({end, t + slice, next_checkpoint});
    next = std::min(next, resume_at);
    next = std::min(next, stop_at);
    next = std::min(next, next_migration);
    executor.run_until(next);
    t = next;
    if (auto st = flush(); !st) return Error{st.error()};
    if (t == next_migration) {
      const std::vector<float> migrant = options.migrate(champion ? champion->genes : std::vector<float>{}, best);
      if (!migrant.empty() && t < end) {
        os::Message m;
        m.port = evo::kImmigrantPort;
        m.payload = os::Payload(std::span<const float>(migrant));
        if (node.post(*evolution_id, m).ok()) ++result.migrants;
      }
      next_migration += options.migrate_every;
    }
    if (auto e = session->cycle_error(); !e.empty()) return Error{e};
    if (replaying() && t == resume_at) {
      if (history.size() != checkpoint->evaluations || history.hash() != checkpoint->history_hash)
        return Error{"--resume: this run does not reproduce the checkpoint: at " + fixed(seconds(t - start), 1) +
                     " s it has " + std::to_string(history.size()) + " evaluations (history hash " +
                     hex64(history.hash()) + "), the checkpoint says " + std::to_string(checkpoint->evaluations) +
                     " (" + hex64(checkpoint->history_hash) +
                     "); a different build or referenced file? Start afresh without --resume"};
      result.resumed = true;
      result.resumed_from_seconds = seconds(t - start);
      resume_at = kernel::kTimeNever;
      pace_start = std::chrono::steady_clock::now();
    }
    if (checkpoints && t == next_checkpoint) {
      // Replaying towards a checkpoint: the one on disk is further on; leave it.
      if (!replaying() && t < end) {
        const EvolveCheckpoint c{options.scenario_path, scenario_hash, result.seed, scenario.duration, t - start,
                                 history.size(),        history.hash()};
        if (auto st = write_file_atomically(checkpoint_path, to_text(c)); !st) return Error{st.error()};
      }
      next_checkpoint += options.checkpoint_every;
    }
    if (t == stop_at) {
      result.stopped = true;
      break;
    }
    if (live) live->between_slices();
    if (speed > 0 && !replaying()) {
      const auto due = pace_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>(seconds(t - pace_from) / speed));
      if (!live) {
        std::this_thread::sleep_until(due);
      } else {
        // Waiting, the page's shell is served and its controls are heard.
        for (auto now = std::chrono::steady_clock::now(); now < due && !control.paused() && control.speed() == speed;
             now = std::chrono::steady_clock::now()) {
          executor.wait_injected(std::min<kernel::Duration>(due - now, std::chrono::milliseconds(20)));
          live->between_slices();
        }
      }
    }
    if (std::chrono::steady_clock::now() - last_report > std::chrono::milliseconds(100) || t == end) {
      report(t);
      last_report = std::chrono::steady_clock::now();
    }
  }
  if (live) live->finish();
  session->stop();
  if (auto st = flush(); !st) return Error{st.error()};
  result.wall_seconds = wall_seconds();
  live.reset();
  result.simulated_seconds = seconds(executor.clock().now() - start);
  result.evaluations = history.size();
  result.champion_fitness = best;
  result.history_hash = history.hash();
  result.migrants_taken = watcher.immigrants_taken();
  if (champion) result.champion_genes = champion->genes;
  csv.close();
  if (!csv) return Error{"cannot write " + (out / "fitness.csv").string()};
  result.files = {out / "fitness.csv"};
  if (checkpoints) result.files.push_back(checkpoint_path);
  if (result.stopped) return result;

  // The final checkpoint: the whole run, so a --resume of a finished run just re-checks it.
  {
    const EvolveCheckpoint c{options.scenario_path, scenario_hash,  result.seed,   scenario.duration,
                             end - start,           history.size(), history.hash()};
    if (auto st = write_file_atomically(checkpoint_path, to_text(c)); !st) return Error{st.error()};
  }
  if (champion) {
    if (auto st = write_file(out / "champion.genome", genome_file_text(*champion, frame, options.scenario_path)); !st)
      return Error{st.error()};
    result.files.push_back(out / "champion.genome");
    result.files.push_back(out / "champions");
  }

  // The picture: measured fitness and the champion's stored fitness over time, from the CSV.
  run::ProbeSeries series;
  series.robot = robot_name;
  series.task = task_name;
  series.channel = "fitness ([0] measured, [1] champion)";
  series.width = 2;
  {
    auto text = read_file(out / "fitness.csv");
    if (!text) return Error{text.error()};
    std::istringstream in(*text);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      double t = 0, f = 0, c = 0;
      int kind = 0;
      if (std::sscanf(line.c_str(), "%lf,%d,%lf,%lf", &t, &kind, &f, &c) != 4) continue;
      series.times.push_back(t);
      series.values.push_back({static_cast<float>(f), static_cast<float>(c)});
      ++series.samples;
    }
  }
  std::ostringstream svg;
  run::write_probe_svg(svg, series);
  if (auto st = write_file(out / "fitness.svg", svg.str()); !st) return Error{st.error()};
  result.files.push_back(out / "fitness.svg");

  std::ostringstream summary;
  summary << "scenario: " << scenario.name << " (" << options.scenario_path << ")\n"
          << "seed: " << result.seed << "\n"
          << "evolution task: " << robot_name << "/" << task_name << "\n"
          << "simulated: " << fixed(result.simulated_seconds, 1) << " s in " << fixed(result.wall_seconds, 2)
          << " s of wall clock\n"
          << "evaluations: " << result.evaluations << " ("
          << fixed(result.wall_seconds > 0 ? static_cast<double>(result.evaluations) / result.wall_seconds : 0, 1)
          << " per second)\n"
          << "new champions: " << result.champions << "\n"
          << "champion fitness: " << exact(result.champion_fitness) << "\n"
          << "history hash: " << hex64(result.history_hash) << "\n";
  if (result.resumed)
    summary << "resumed: re-ran to the checkpoint at " << fixed(result.resumed_from_seconds, 1)
            << " s, history matched\n";
  if (auto st = write_file(out / "summary.txt", summary.str()); !st) return Error{st.error()};
  result.files.push_back(out / "summary.txt");
  return result;
}

}  // namespace symb::apps::evolve
