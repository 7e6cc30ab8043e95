// `symb evolve` (issue 7, deliverable 6): an evolution experiment's output folder, checkpoints
// that resume to the same result as an uninterrupted run (stopped in process, and the binary
// killed with SIGKILL), refusals of checkpoints that do not match, and `symb run --genome`
// replaying the champion.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/apps/evolve/evolve_checkpoint.hpp"
#include "symb/apps/evolve/evolve_run.hpp"
#include "symb/apps/symb_cli.hpp"
#include "symb/evo/genome/genome.hpp"

namespace symb::apps::evolve {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kScenario = std::string(SYMB_SCENARIO_DIR) + "/evolve_maze.yaml";

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("symb_evolve_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

struct Cli {
  int code = 0;
  std::string out, err;
};

Cli symb(std::vector<std::string> args) {
  std::vector<std::string_view> views(args.begin(), args.end());
  std::ostringstream out, err;
  CliContext ctx{out, err, false};
  const int code = run_symb(views, ctx);
  return {code, out.str(), err.str()};
}

EvolveOptions options(const fs::path& out, kernel::Duration duration) {
  EvolveOptions o;
  o.scenario_path = kScenario;
  o.out_dir = out;
  o.duration = duration;
  o.checkpoint_every = 5min;
  o.seed = 7;
  return o;
}

TEST(EvolveCheckpoint, RoundTripsAndRejectsMalformedTexts) {
  const EvolveCheckpoint c{"a b.yaml", 0x0123456789abcdefULL, 42, 3600s, 600s, 28, 0xfedcba9876543210ULL};
  auto back = parse_checkpoint(to_text(c));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(*back, c);
  const std::string good = to_text(c);
  const auto error_of = [](const std::string& text) {
    auto r = parse_checkpoint(text);
    return r ? std::string("accepted") : r.error();
  };
  EXPECT_EQ(error_of(""), "1: empty checkpoint");
  EXPECT_NE(error_of("symb-evolve-checkpoint 2\n").find("1: expected 'symb-evolve-checkpoint 1'"), std::string::npos);
  std::string bad = good;
  bad.replace(bad.find("seed 42"), 7, "seed 4x");
  EXPECT_NE(error_of(bad).find("seed: expected a whole number"), std::string::npos) << error_of(bad);
  bad = good + "seed 1\n";
  EXPECT_NE(error_of(bad).find("'seed' given twice"), std::string::npos);
  bad = good.substr(0, good.find("history_hash"));
  EXPECT_NE(error_of(bad).find("missing 'history_hash'"), std::string::npos);
  bad = good + "colour blue\n";
  EXPECT_NE(error_of(bad).find("unknown key 'colour'"), std::string::npos);
}

// Run A: 20 min uninterrupted. Run B: stopped at 10 min (as if killed; checkpoints every 5 min),
// then resumed to the end. Same evaluations, same champions, byte for byte.
TEST(Evolve, ResumedRunEqualsUninterruptedRun) {
  const fs::path a = scratch("a"), b = scratch("b");
  auto ra = run_evolution(options(a, 20min));
  ASSERT_TRUE(ra.ok()) << ra.error();
  EXPECT_GT(ra->evaluations, 50u);  // 20 min / 21 s = 57
  EXPECT_GE(ra->champions, 1u);
  for (const char* f : {"fitness.csv", "fitness.svg", "champion.genome", "summary.txt", "checkpoint.txt"})
    EXPECT_TRUE(fs::exists(a / f)) << f;
  // fitness.csv: a header and a row per evaluation; the champion file parses as a real genome.
  const std::string csv = read(a / "fitness.csv");
  EXPECT_EQ(csv.rfind("time_s,kind,fitness,champion_fitness,sigma,evaluations\n", 0), 0u);
  EXPECT_EQ(static_cast<std::uint64_t>(std::count(csv.begin(), csv.end(), '\n')), ra->evaluations + 1);
  auto genome = evo::parse_genome_text(read(a / "champion.genome"));
  ASSERT_TRUE(genome.ok()) << genome.error();
  ASSERT_EQ(evo::kind_of(*genome), evo::GenomeKind::kReal);
  EXPECT_EQ(std::get<evo::RealGenome>(*genome).values.size(), 16u);
  EXPECT_EQ(listing(a / "champions").size(), ra->champions);
  EXPECT_NE(read(a / "fitness.svg").find("<polyline"), std::string::npos);

  EvolveOptions ob = options(b, 20min);
  ob.stop_at = 10min;
  auto rb = run_evolution(ob);
  ASSERT_TRUE(rb.ok()) << rb.error();
  EXPECT_TRUE(rb->stopped);
  EXPECT_FALSE(fs::exists(b / "champion.genome"));
  auto cp = parse_checkpoint(read(b / "checkpoint.txt"));
  ASSERT_TRUE(cp.ok()) << cp.error();
  EXPECT_EQ(cp->time, kernel::Time(10min));
  EXPECT_EQ(cp->seed, 7u);
  EXPECT_GT(cp->evaluations, 20u);
  EXPECT_LT(cp->evaluations, ra->evaluations);

  EvolveOptions resume;  // no seed, no duration: the checkpoint's
  resume.scenario_path = kScenario;
  resume.out_dir = b;
  resume.resume = true;
  auto rr = run_evolution(resume);
  ASSERT_TRUE(rr.ok()) << rr.error();
  EXPECT_TRUE(rr->resumed);
  EXPECT_EQ(rr->resumed_from_seconds, 600.0);
  EXPECT_EQ(rr->seed, 7u);
  EXPECT_EQ(rr->evaluations, ra->evaluations);
  EXPECT_EQ(rr->history_hash, ra->history_hash);
  EXPECT_EQ(read(b / "fitness.csv"), csv);
  EXPECT_EQ(read(b / "champion.genome"), read(a / "champion.genome"));
  EXPECT_EQ(listing(b / "champions"), listing(a / "champions"));

  // A checkpoint whose history this run does not reproduce is refused, with the reason.
  write(b / "checkpoint.txt", to_text(EvolveCheckpoint{cp->scenario, cp->scenario_hash, cp->seed, cp->duration,
                                                       cp->time, cp->evaluations, cp->history_hash ^ 1}));
  auto refused = run_evolution(resume);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("does not reproduce the checkpoint"), std::string::npos) << refused.error();
  // Another seed than the checkpoint's, too.
  resume.seed = 8;
  write(b / "checkpoint.txt", to_text(*cp));
  refused = run_evolution(resume);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("differs from the checkpoint's seed 7"), std::string::npos) << refused.error();
  fs::remove_all(a);
  fs::remove_all(b);
}

// The same experiment with encapsulated (mu+1)-ONLINE: evolve_maze.yaml with the evolution task
// swapped for a mu_plus_one one. Its best member is the champion (with its fixed sigma), and a
// resumed run gives the same files.
TEST(Evolve, MuPlusOneExperimentWritesItsBestAndResumes) {
  const fs::path dir = scratch("mu");
  fs::create_directories(dir);
  std::string yaml = read(kScenario);
  const std::string from = "type: one_plus_one\n        params: {evaluation: 20s, recovery: 1s, sigma_min: 0.05,";
  const auto at = yaml.find(from);
  ASSERT_NE(at, std::string::npos) << "evolve_maze.yaml changed: update this test";
  yaml.replace(at, from.size(),
               "type: mu_plus_one\n        params: {evaluation: 20s, recovery: 1s, mu: 5, sigma: 0.5,");
  const fs::path scenario = dir / "evolve_maze_mu.yaml";
  write(scenario, yaml);
  EvolveOptions o = options(dir / "whole", 20min);
  o.scenario_path = scenario.string();
  auto whole = run_evolution(o);
  ASSERT_TRUE(whole.ok()) << whole.error();
  EXPECT_GT(whole->evaluations, 50u);
  EXPECT_GE(whole->champions, 1u);
  EXPECT_GT(whole->champion_fitness, 0.0);
  const std::string csv = read(dir / "whole" / "fitness.csv");
  EXPECT_EQ(static_cast<std::uint64_t>(std::count(csv.begin(), csv.end(), '\n')), whole->evaluations + 1);
  auto genome = evo::parse_genome_text(read(dir / "whole" / "champion.genome"));
  ASSERT_TRUE(genome.ok()) << genome.error();
  ASSERT_EQ(evo::kind_of(*genome), evo::GenomeKind::kReal);
  const auto& real = std::get<evo::RealGenome>(*genome);
  EXPECT_EQ(real.values.size(), 16u);
  EXPECT_EQ(real.sigma_min, 0.5);
  EXPECT_EQ(real.sigma_max, 0.5);
  EXPECT_EQ(listing(dir / "whole" / "champions").size(), whole->champions);

  EvolveOptions part = options(dir / "part", 20min);
  part.scenario_path = scenario.string();
  part.stop_at = 10min;
  ASSERT_TRUE(run_evolution(part).ok());
  EvolveOptions resume;
  resume.scenario_path = scenario.string();
  resume.out_dir = dir / "part";
  resume.resume = true;
  auto resumed = run_evolution(resume);
  ASSERT_TRUE(resumed.ok()) << resumed.error();
  EXPECT_EQ(resumed->history_hash, whole->history_hash);
  EXPECT_EQ(read(dir / "part" / "fitness.csv"), csv);
  EXPECT_EQ(read(dir / "part" / "champion.genome"), read(dir / "whole" / "champion.genome"));
  fs::remove_all(dir);
}

TEST(Evolve, ResumeRefusesAnotherScenarioFile) {
  const fs::path dir = scratch("other"), b = dir / "run";
  fs::create_directories(dir);
  const fs::path copy = dir / "evolve_maze.yaml";
  // The same scenario with another evaluation time: the scenario hash tells.
  std::string text = read(kScenario);
  write(copy, text);
  EvolveOptions o = options(b, 10min);
  o.scenario_path = copy.string();
  o.stop_at = 5min;
  ASSERT_TRUE(run_evolution(o).ok());
  text.replace(text.find("evaluation: 20s"), 15, "evaluation: 10s");
  write(copy, text);
  o.stop_at.reset();
  o.resume = true;
  auto r = run_evolution(o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("is not the scenario file the checkpoint was made with"), std::string::npos) << r.error();
  fs::remove_all(dir);
}

// Two tasks that answer each other's every message: the node cuts the cycle (os/message.hpp,
// kMaxHops) and the evolution run stops with the error naming it, not 20 minutes later.
TEST(Evolve, AHookCycleStopsTheRunWithAnErrorNamingIt) {
  const fs::path dir = scratch("cycle");
  fs::create_directories(dir);
  const fs::path copy = dir / "evolve_maze.yaml";
  std::string text = read(kScenario);
  const std::string hooks = "    hooks:\n      - ir -> fitness\n";
  ASSERT_NE(text.find(hooks), std::string::npos);
  text.replace(text.find(hooks), hooks.size(),
               "      - {name: c, type: mlp, params: {inputs: 7, layers: \"2\"}}\n"
               "      - {name: a, type: mlp, params: {inputs: 2, layers: \"2\"}}\n"
               "      - {name: b, type: mlp, params: {inputs: 2, layers: \"2\"}}\n" +
                   hooks + "      - ir -> c\n      - c -> a\n      - a -> b\n      - b -> a\n");
  write(copy, text);
  EvolveOptions o = options(dir / "run", 20min);
  o.scenario_path = copy.string();
  auto r = run_evolution(o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("message cycle "), std::string::npos) << r.error();
  EXPECT_TRUE(r.error().find("a -> b -> a") != std::string::npos || r.error().find("b -> a -> b") != std::string::npos)
      << r.error();
  fs::remove_all(dir);
}

// The binary, killed with SIGKILL in the middle of a run (paced at 100x real time so that there
// is a middle to kill it in, seconds long even when this test is kept off its core for a while),
// then resumed: the same files as a run never interrupted.
TEST(Evolve, BinaryKilledWithSigkillResumesToTheSameResult) {
  const fs::path a = scratch("kill_a"), b = scratch("kill_b");
  pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(SYMB_BINARY, SYMB_BINARY, "evolve", kScenario.c_str(), "--out", b.c_str(), "--duration", "10min", "--seed",
            "3", "--checkpoint-every", "1min", "--speed", "100", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Kill it once a checkpoint at 3 min or later is on disk (about 1.8 s in, of 6).
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  bool ready = false;
  while (!ready && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(5ms);
    auto cp = parse_checkpoint(read(b / "checkpoint.txt"));
    ready = cp.ok() && cp->time >= kernel::Time(3min);
  }
  ASSERT_TRUE(ready);
  ::kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));  // killed, not finished
  EXPECT_FALSE(fs::exists(b / "champion.genome"));
  auto cp = parse_checkpoint(read(b / "checkpoint.txt"));
  ASSERT_TRUE(cp.ok());
  EXPECT_LT(cp->time, kernel::Time(10min));

  const std::string bin = SYMB_BINARY;
  const auto run = [&](const std::string& args) {
    return std::system(("'" + bin + "' evolve '" + kScenario + "' --quiet " + args + " >/dev/null 2>&1").c_str());
  };
  ASSERT_EQ(run("--out '" + b.string() + "' --resume"), 0);
  ASSERT_EQ(run("--out '" + a.string() + "' --duration 10min --seed 3"), 0);
  EXPECT_NE(read(a / "fitness.csv").size(), 0u);
  EXPECT_EQ(read(b / "fitness.csv"), read(a / "fitness.csv"));
  EXPECT_EQ(read(b / "champion.genome"), read(a / "champion.genome"));
  EXPECT_NE(read(b / "summary.txt").find("resumed: re-ran to the checkpoint"), std::string::npos);
  fs::remove_all(a);
  fs::remove_all(b);
}

// The mean per-step fitness the `fitness` task measured over a run (its last probe: sum, steps).
double measured_fitness(const fs::path& out) {
  std::istringstream in(read(out / "probes.csv"));
  std::string line, last;
  while (std::getline(in, line))
    if (line.find(",thymio,fitness,fitness,") != std::string::npos) last = line;
  double t = 0, sum = 0, steps = 0;
  const auto at = last.find(",fitness,fitness,");
  if (at == std::string::npos) return -1;
  t = std::stod(last);
  std::sscanf(last.c_str() + at + 17, "%lf,%lf", &sum, &steps);
  return t > 0 && steps > 0 ? sum / steps : -1;
}

// The maze with a perceptron controller and a fitness task; `weights` inline, or a placeholder
// that --genome replaces.
std::string replay_scenario(const std::string& weights) {
  std::string text = read(std::string(SYMB_SCENARIO_DIR) + "/braitenberg.yaml");
  text.replace(text.find("weights: network/braitenberg.w"), 30, "weights: \"" + weights + "\"");
  text.replace(text.find("    hooks:\n"), 11,
               "      - name: fitness\n        type: fitness\n        params: {formula: one_plus_one}\n"
               "    hooks:\n      - ir -> fitness\n      - controller -> fitness\n");
  return text;
}

// `symb run --genome champion.genome` drives the champion: the same run, to the bit, as the
// scenario with those weights written in, so the same fitness figure.
TEST(Evolve, RunReplaysTheChampionGenome) {
  const fs::path dir = scratch("replay");
  auto r = run_evolution(options(dir / "evo", 20min));
  ASSERT_TRUE(r.ok()) << r.error();
  const fs::path genome_file = dir / "evo" / "champion.genome";
  auto genome = evo::parse_genome_text(read(genome_file));
  ASSERT_TRUE(genome.ok()) << genome.error();
  const std::string weights = evo::weights_text(std::get<evo::RealGenome>(*genome));
  write(dir / "inline.yaml", replay_scenario(weights));
  write(dir / "placeholder.yaml", replay_scenario("0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0"));
  const Cli replay = symb({"run", (dir / "placeholder.yaml").string(), "--genome", genome_file.string(), "--out",
                           (dir / "replay").string(), "--print-hash", "--quiet"});
  ASSERT_EQ(replay.code, 0) << replay.err;
  const Cli direct =
      symb({"run", (dir / "inline.yaml").string(), "--out", (dir / "direct").string(), "--print-hash", "--quiet"});
  ASSERT_EQ(direct.code, 0) << direct.err;
  EXPECT_EQ(replay.out, direct.out);  // trajectory hashes
  const double replayed = measured_fitness(dir / "replay"), measured = measured_fitness(dir / "direct");
  std::printf("champion (evolution's estimate %.4f): replay fitness %.4f, with the weights written in %.4f\n",
              r->champion_fitness, replayed, measured);
  EXPECT_GT(replayed, 0.0);
  EXPECT_EQ(replayed, measured);
  // It drives: the placeholder (all zeros) would stand still.
  const Cli zeros = symb({"run", (dir / "placeholder.yaml").string(), "--out", (dir / "zeros").string(), "--quiet"});
  ASSERT_EQ(zeros.code, 0);
  EXPECT_NE(read(dir / "replay" / "summary.txt"), read(dir / "zeros" / "summary.txt"));
  EXPECT_GT(replayed, measured_fitness(dir / "zeros"));
  fs::remove_all(dir);
}

TEST(Evolve, BadCommandLinesExitWithTwo) {
  const fs::path dir = scratch("cli");
  fs::create_directories(dir);
  write(dir / "bad.genome", "genome real\nvalues 1 2 x\n");
  write(dir / "kind.genome", "genome reel\n");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"evolve"}, "missing SCENARIO"},
      {{"evolve", kScenario, "--seed", "-1"}, "--seed"},
      {{"evolve", kScenario, "--duration", "soon"}, "--duration"},
      {{"evolve", kScenario, "--checkpoint-every", "10ms"}, "at least 1s"},
      {{"evolve", kScenario, "--resume"}, "--resume needs --out DIR"},
      {{"evolve", kScenario, "--speed", "0"}, "--speed"},
      {{"evolve", kScenario, "--colour"}, "--colour"},
      {{"evolve", kScenario, "--islands", "--migrant-wait", "10ms"}, "--migrant-wait: at least 100ms"},
      {{"evolve", kScenario, "--islands", "--migrant-wait", "a while"}, "--migrant-wait"},
      {{"evolv"}, "did you mean 'evolve'"},
      {{"run", kScenario, "--genome", (dir / "missing.genome").string()}, "--genome: cannot read"},
      {{"run", kScenario, "--genome", (dir / "bad.genome").string()}, "bad.genome:2:"},
      {{"run", kScenario, "--genome", (dir / "kind.genome").string()}, "kind.genome:1:"},
      {{"run", kScenario, "--controller", "brain"}, "give --genome"},
  };
  for (const Case& c : cases) {
    const Cli r = symb(c.args);
    EXPECT_EQ(r.code, 2) << c.args.back() << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
  }
  // A scenario without an evolution task, and --resume without a checkpoint: failures (exit 1).
  Cli r = symb({"evolve", std::string(SYMB_SCENARIO_DIR) + "/maze.yaml", "--out", (dir / "o").string(), "--quiet"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no evolution task"), std::string::npos) << r.err;
  r = symb({"evolve", kScenario, "--out", (dir / "none").string(), "--resume", "--quiet"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no checkpoint to resume from"), std::string::npos) << r.err;
  // --genome into a scenario without the named task.
  write(dir / "ok.genome", "genome real\nvalues 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n");
  r = symb({"run", kScenario, "--genome", (dir / "ok.genome").string(), "--controller", "brain", "--quiet"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("has a task named 'brain'"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace symb::apps::evolve
