#include "symb/apps/evolve/evolve_command.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "symb/apps/evolve/collect.hpp"
#include "symb/apps/evolve/evolve_run.hpp"
#include "symb/apps/evolve/islands.hpp"
#include "symb/apps/progress_line.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::evolve {

namespace {

constexpr std::string_view kCommand = "symb evolve";
constexpr kernel::Duration kMaxDuration = sim::kMaxRunDuration;  // a scenario's limit too

constexpr OptionSpec kOptions[] = {
    {"--out", "DIR", "output folder (default out/evolve/<scenario file name>)"},
    {"--seed", "S", "seed, unsigned 64-bit (default: the scenario's; with --resume: the checkpoint's)"},
    {"--duration", "D", "simulated time: 30min, 2h, ... (default: the scenario's; with --resume: the checkpoint's)"},
    {"--checkpoint-every", "D", "simulated time between checkpoints (default 10min; 0 for none)"},
    {"--resume", "", "carry on from DIR/checkpoint.txt (re-runs to it, checks it, continues)"},
    {"--speed", "X", "virtual time at X times the wall clock (default: as fast as possible)"},
    {"--view", "[ADDR:]PORT", "watch and drive the run in a browser (docs/view.md; implies --speed 1 unless given)"},
    {"--token", "T", "the web view's token (default: a random one, printed)"},
    {"--quiet", "", "no progress line and no summary"},
    {"--islands", "",
     "island model under mpirun (--enable-recovery: the others go on if one dies): an island per rank, seed + "
     "rank, OUT/island_<rank>/ (docs/cluster.md)"},
    {"--migrate-every", "D",
     "with --islands: simulated time between migrations along the ring (default 10min; 0: never)"},
    {"--migrant-wait", "D",
     "with --islands: wall clock of silence after which an island is taken as gone (default 60s)"},
    {"--help", "", "this help"},
};

constexpr OptionSpec kCollectOptions[] = {
    {"--collect", "", "merge the run folders given into one report"},
    {"--out", "DIR", "where the report goes (default out/evolve/collected)"},
    {"--quiet", "", "no summary"},
    {"--help", "", "this help"},
};

int run_collect(std::span<const std::string_view> args, const CliContext& ctx) {
  auto split = split_args(args, kCollectOptions, 100000);
  if (auto* e = std::get_if<UsageError>(&split)) return usage_error(ctx, kCommand, *e);
  const SplitArgs& a = std::get<SplitArgs>(split);
  if (a.help) {
    ctx.out << "Usage: " << kCommand << " --collect DIR... [--out DIR]\n\n"
            << "Merges evolution runs' folders (a job array's, scripts/evolve_array's, --islands' islands; a\n"
            << "folder of run folders stands for them all) into one report: collected.txt (per run and\n"
            << "the champion fitness over time across runs), fitness.svg, best.genome.\n\n"
            << "Options:\n"
            << describe_options(kCollectOptions);
    return kExitOk;
  }
  std::filesystem::path out = std::filesystem::path("out") / "evolve" / "collected";
  bool quiet = false;
  for (const ParsedOption& o : a.options) {
    if (o.name == "--out") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--out: empty folder name"});
      out = o.value;
    } else if (o.name == "--quiet") {
      quiet = true;
    }
  }
  if (a.positional.empty()) return usage_error(ctx, kCommand, UsageError{"--collect needs at least one DIR"});
  std::vector<std::filesystem::path> dirs(a.positional.begin(), a.positional.end());
  auto c = collect_runs(dirs, out);
  if (!c) {
    ctx.err << kCommand << " --collect: " << c.error() << "\n";
    return kExitFailure;
  }
  if (!quiet) {
    ctx.out << "collected " << c->runs.size() << " runs; best: " << c->runs[c->best].dir.string()
            << ", champion fitness " << fixed(c->runs[c->best].champion_fitness, 4) << "\nresults in " << out.string()
            << "/\n";
    for (const auto& f : c->files) ctx.out << "  " << f.string() << "\n";
  }
  return kExitOk;
}

void print_evolve_help(std::ostream& out) {
  out << "Usage: " << kCommand << " SCENARIO [options]\n\n"
      << "Runs an evolution experiment headless on the deterministic virtual-time executor: a\n"
      << "scenario whose robot has an evolution task (type one_plus_one: (1+1)-ONLINE, or\n"
      << "mu_plus_one: encapsulated (mu+1)-ONLINE; each replaces the controller task for every\n"
      << "candidate) and a fitness task. Shows the evaluations, the champion's (the best member's)\n"
      << "and the mean fitness and evaluations per second while it runs.\n\n"
      << "Options:\n"
      << describe_options(kOptions) << "\n"
      << "Writes into the output folder: fitness.csv (one row per evaluation), fitness.svg,\n"
      << "champion.genome (the final champion), champions/ (every new champion), checkpoint.txt,\n"
      << "summary.txt. A checkpoint holds the seed, the scenario's hash, the time reached and a hash\n"
      << "of the evaluations so far: --resume re-runs deterministically to that time, refuses if the\n"
      << "history differs, and continues, giving the same files as a run never interrupted.\n\n"
      << "Example: symb evolve scenarios/evolve_maze.yaml --out out/evo\n"
      << "         symb run scenarios/braitenberg.yaml --genome out/evo/champion.genome\n";
}

std::string progress_text(const EvolveProgress& p) {
  std::string s = (p.replaying ? "evolve (replaying to the checkpoint): " : "evolve: ") +
                  fixed(p.simulated_seconds / 60, 1) + " / " + fixed(p.total_seconds / 60, 1) + " min (" +
                  fixed(100 * p.fraction(), 0) + "%), " + std::to_string(p.evaluations) + " evaluations, best " +
                  fixed(p.best, 3) + ", mean " + fixed(p.mean, 3);
  if (p.wall_seconds > 0) s += ", " + fixed(p.per_second, 0) + " eval/s";
  return s;
}

}  // namespace

int run_evolve_command(std::span<const std::string_view> args, const CliContext& ctx) {
  if (std::find(args.begin(), args.end(), std::string_view("--collect")) != args.end()) return run_collect(args, ctx);
  EvolveOptions options;
  bool islands = false;
  IslandOptions island_options;
  auto split = scenario_command_args(args, kOptions, ctx, kCommand, print_evolve_help);
  if (const int* status = std::get_if<int>(&split)) return *status;
  const SplitArgs& parsed = std::get<SplitArgs>(split);
  options.scenario_path = std::string(parsed.positional.front());
  bool quiet = false, speed_given = false;
  std::optional<std::string> token;
  for (const ParsedOption& o : parsed.options) {
    if (o.name == "--out") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--out: empty folder name"});
      options.out_dir = o.value;
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--duration") {
      auto v = parse_duration("--duration", o.value, kMaxDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.duration = std::get<kernel::Duration>(v);
    } else if (o.name == "--checkpoint-every") {
      if (o.value == "0") {
        options.checkpoint_every = kernel::Duration{0};
        continue;
      }
      auto v = parse_duration("--checkpoint-every", o.value, kMaxDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.checkpoint_every = std::get<kernel::Duration>(v);
      if (options.checkpoint_every < std::chrono::seconds(1))
        return usage_error(ctx, kCommand, UsageError{"--checkpoint-every: at least 1s (or 0 for none)"});
    } else if (o.name == "--resume") {
      options.resume = true;
    } else if (o.name == "--speed") {
      auto v = parse_speed("--speed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.speed = std::get<double>(v);
      speed_given = true;
    } else if (o.name == "--view") {
      auto v = view::parse_view(o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.view = std::get<view::ViewRequest>(v);
    } else if (o.name == "--token") {
      token = o.value;
    } else if (o.name == "--quiet") {
      quiet = true;
    } else if (o.name == "--islands") {
      islands = true;
    } else if (o.name == "--migrate-every") {
      if (o.value == "0") {
        island_options.every = kernel::Duration{0};
        continue;
      }
      auto v = parse_duration("--migrate-every", o.value, kMaxDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      island_options.every = std::get<kernel::Duration>(v);
    } else if (o.name == "--migrant-wait") {
      auto v = parse_duration("--migrant-wait", o.value, std::chrono::hours(24));
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      island_options.wait = std::get<kernel::Duration>(v);
      if (island_options.wait < std::chrono::milliseconds(100))
        return usage_error(ctx, kCommand, UsageError{"--migrant-wait: at least 100ms"});
    }
  }
  if (islands && (options.resume || options.view.on))
    return usage_error(ctx, kCommand, UsageError{"--islands runs without --resume and --view"});
  if (options.out_dir.empty()) {
    if (options.resume) return usage_error(ctx, kCommand, UsageError{"--resume needs --out DIR (the run's folder)"});
    options.out_dir = std::filesystem::path("out") / "evolve" / std::filesystem::path(options.scenario_path).stem();
  }

  if (token && !options.view.on) return usage_error(ctx, kCommand, UsageError{"--token is for --view"});
  if (token) options.view.token = *token;
  if (options.view.on && !speed_given) options.speed = 1.0;

  ProgressLine progress(ctx.err, !quiet, ctx.err_is_terminal);
  options.on_progress = [&](const EvolveProgress& p) { progress.update(p.fraction(), progress_text(p)); };
  options.on_notice = [&ctx](const std::string& line) { ctx.err << line << "\n" << std::flush; };
  if (islands) {
    if (options.seed) {
      island_options.base_seed = *options.seed;
    } else {
      auto scenario = sim::load_scenario(options.scenario_path);
      if (!scenario) {
        ctx.err << kCommand << ": " << scenario.error() << "\n";
        return kExitFailure;
      }
      island_options.base_seed = scenario->seed;
    }
    island_options.quiet = quiet;
    return run_islands(options, island_options, ctx);
  }
  auto result = run_evolution(options);
  if (!result) {
    progress.finish("evolve: stopped");
    ctx.err << kCommand << ": " << result.error() << "\n";
    return kExitFailure;
  }
  const EvolveResult& r = *result;
  progress.finish("evolve: done, " + std::to_string(r.evaluations) + " evaluations");
  if (!quiet) {
    ctx.out << "evolve: " << r.scenario << ", seed " << r.seed << ", " << fixed(r.simulated_seconds / 60, 1)
            << " min simulated in " << fixed(r.wall_seconds, 2) << " s: " << r.evaluations << " evaluations ("
            << fixed(r.wall_seconds > 0 ? static_cast<double>(r.evaluations) / r.wall_seconds : 0, 0)
            << " per second), " << r.champions << " new champions, champion fitness " << fixed(r.champion_fitness, 4)
            << "\n";
    if (r.resumed) ctx.out << "  resumed from the checkpoint at " << fixed(r.resumed_from_seconds, 1) << " s\n";
    ctx.out << "results in " << options.out_dir.string() << "/\n";
    for (const auto& f : r.files) ctx.out << "  " << f.string() << "\n";
    ctx.out << std::flush;
  }
  return kExitOk;
}

}  // namespace symb::apps::evolve
