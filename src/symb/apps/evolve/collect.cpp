#include "symb/apps/evolve/collect.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>

#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/text_file.hpp"

namespace symb::apps::evolve {
namespace {

namespace fs = std::filesystem;
using kernel::Error;

constexpr std::size_t kReportInstants = 20;
constexpr std::size_t kPlotPoints = 400;

bool is_run(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "fitness.csv", ec);
}

kernel::Result<CollectedRun> read_run(const fs::path& dir) {
  CollectedRun run;
  run.dir = dir;
  auto summary = read_file(dir / "summary.txt");
  if (!summary) return Error{summary.error() + " (not a finished run of symb evolve)"};
  bool seed = false, fitness = false;
  std::istringstream s(*summary);
  for (std::string line; std::getline(s, line);) {
    unsigned long long v = 0;
    double d = 0;
    if (std::sscanf(line.c_str(), "seed: %llu", &v) == 1) run.seed = v, seed = true;
    if (std::sscanf(line.c_str(), "evaluations: %llu", &v) == 1) run.evaluations = v;
    if (std::sscanf(line.c_str(), "champion fitness: %lf", &d) == 1) run.champion_fitness = d, fitness = true;
  }
  if (!seed || !fitness) return Error{(dir / "summary.txt").string() + ": no 'seed:' or 'champion fitness:' line"};
  auto csv = read_file(dir / "fitness.csv");
  if (!csv) return Error{csv.error()};
  std::istringstream in(*csv);
  std::string line;
  std::getline(in, line);
  if (!line.starts_with("time_s,"))
    return Error{(dir / "fitness.csv").string() + ":1: not a fitness.csv header: '" + line.substr(0, 60) + "'"};
  for (std::size_t n = 2; std::getline(in, line); ++n) {
    double t = 0, f = 0, c = 0;
    int kind = 0;
    if (std::sscanf(line.c_str(), "%lf,%d,%lf,%lf", &t, &kind, &f, &c) != 4)
      return Error{(dir / "fitness.csv").string() + ":" + std::to_string(n) + ": not a row of four numbers"};
    run.times.push_back(t);
    run.champion.push_back(c);
  }
  return run;
}

// The run's champion fitness at time t: after the last evaluation that ended by t (NaN before).
double at(const CollectedRun& r, double t) {
  const auto it = std::upper_bound(r.times.begin(), r.times.end(), t);
  if (it == r.times.begin()) return std::numeric_limits<double>::quiet_NaN();
  return r.champion[static_cast<std::size_t>(it - r.times.begin()) - 1];
}

}  // namespace

kernel::Result<Collected> collect_runs(const std::vector<fs::path>& dirs, const fs::path& out) {
  Collected c;
  for (const fs::path& d : dirs) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) return Error{d.string() + ": no such folder"};
    std::vector<fs::path> runs;
    if (is_run(d)) {
      runs.push_back(d);
    } else {
      for (const auto& e : fs::directory_iterator(d, ec))
        if (e.is_directory() && is_run(e.path())) runs.push_back(e.path());
      std::sort(runs.begin(), runs.end());
      if (runs.empty()) return Error{d.string() + ": neither a run's folder (fitness.csv) nor a folder of runs"};
    }
    for (const fs::path& r : runs) {
      auto run = read_run(r);
      if (!run) return Error{run.error()};
      c.runs.push_back(std::move(run).value());
    }
  }
  if (c.runs.empty()) return Error{"no runs to collect"};
  for (std::size_t i = 1; i < c.runs.size(); ++i)
    if (c.runs[i].champion_fitness > c.runs[c.best].champion_fitness) c.best = i;
  double end = 0;
  for (const CollectedRun& r : c.runs)
    if (!r.times.empty()) end = std::max(end, r.times.back());

  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return Error{"cannot create " + out.string() + ": " + ec.message()};
  std::ostringstream text;
  text << "collected " << c.runs.size() << " runs\n"
       << "run  seed  evaluations  champion_fitness  folder\n";
  double mean = 0;
  for (std::size_t i = 0; i < c.runs.size(); ++i) {
    const CollectedRun& r = c.runs[i];
    text << i << "  " << r.seed << "  " << r.evaluations << "  " << fixed(r.champion_fitness, 6) << "  "
         << r.dir.string() << "\n";
    mean += r.champion_fitness / static_cast<double>(c.runs.size());
  }
  double var = 0;
  for (const CollectedRun& r : c.runs) var += (r.champion_fitness - mean) * (r.champion_fitness - mean);
  const double sd = c.runs.size() > 1 ? std::sqrt(var / static_cast<double>(c.runs.size() - 1)) : 0.0;
  text << "final champion fitness: mean " << fixed(mean, 6) << ", sd " << fixed(sd, 6) << "\n"
       << "best run: " << c.best << " (" << c.runs[c.best].dir.string() << "), champion fitness "
       << fixed(c.runs[c.best].champion_fitness, 6) << "\n"
       << "champion fitness over time across runs:\ntime_s  runs  mean  min  max\n";
  for (std::size_t k = 1; k <= kReportInstants; ++k) {
    const double t = end * static_cast<double>(k) / kReportInstants;
    double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t n = 0;
    for (const CollectedRun& r : c.runs) {
      const double v = at(r, t);
      if (std::isnan(v)) continue;
      sum += v, lo = std::min(lo, v), hi = std::max(hi, v), ++n;
    }
    text << fixed(t, 0) << "  " << n << "  " << (n ? fixed(sum / n, 6) : "-") << "  " << (n ? fixed(lo, 6) : "-")
         << "  " << (n ? fixed(hi, 6) : "-") << "\n";
  }
  if (auto st = write_file(out / "collected.txt", text.str()); !st) return Error{st.error()};
  c.files.push_back(out / "collected.txt");

  run::ProbeSeries series;
  series.robot = "runs";
  series.task = "champion";
  series.channel = "champion fitness per run";
  series.width = std::min<std::size_t>(c.runs.size(), run::ProbeRecorder::kMaxValues);
  for (std::size_t i = 0; i < series.width; ++i) series.labels.push_back(c.runs[i].dir.filename().string());
  for (std::size_t k = 0; k <= kPlotPoints && end > 0; ++k) {
    const double t = end * static_cast<double>(k) / kPlotPoints;
    std::vector<float> v;
    for (std::size_t i = 0; i < series.width; ++i) v.push_back(static_cast<float>(at(c.runs[i], t)));
    series.times.push_back(t);
    series.values.push_back(std::move(v));
    ++series.samples;
  }
  std::ostringstream svg;
  run::write_probe_svg(svg, series);
  if (auto st = write_file(out / "fitness.svg", svg.str()); !st) return Error{st.error()};
  c.files.push_back(out / "fitness.svg");
  if (auto genome = read_file(c.runs[c.best].dir / "champion.genome"); genome.ok()) {
    if (auto st = write_file(out / "best.genome", *genome); !st) return Error{st.error()};
    c.files.push_back(out / "best.genome");
  }
  return c;
}

}  // namespace symb::apps::evolve
