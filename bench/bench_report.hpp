// Shared by the bench programs: a console reporter that also keeps every repetition's counters, so
// that a program can print its own summary (ratios against a baseline measured in the same run)
// after Google Benchmark's table, and a main() prologue that turns on repetitions interleaved at
// random. The box the numbers come from is a shared, noisy 2-core machine: interleaving spreads
// a burst of noise over both sides of a ratio instead of over one, and medians shrug off outliers.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace symb::bench {

class CollectingReporter : public benchmark::ConsoleReporter {
 public:
  // With show_repetitions false the console gets only the aggregates (mean, median, ...) of a
  // repeated benchmark, while every repetition is still kept here. Benchmark's own
  // DisplayAggregatesOnly() would hide the repetitions from this reporter too.
  // Colour only on a terminal: a custom reporter does not get --benchmark_color applied, and escape
  // codes in a saved log make it unreadable.
  explicit CollectingReporter(bool show_repetitions = true)
      : ConsoleReporter(isatty(fileno(stdout)) != 0 ? OO_ColorTabular : OO_Tabular),
        show_repetitions_(show_repetitions) {}

  void ReportRuns(const std::vector<Run>& reports) override {
    for (const Run& r : reports) {
      if (r.run_type != Run::RT_Iteration) continue;
      if (r.error_occurred) {
        errors_.push_back(key(r) + ": " + r.error_message);
        continue;
      }
      auto& per_counter = runs_[key(r)];
      for (const auto& [name, counter] : r.counters) per_counter[name].push_back(counter.value);
      per_counter["real_time_s"].push_back(r.real_accumulated_time / static_cast<double>(r.iterations));
    }
    if (show_repetitions_) {
      ConsoleReporter::ReportRuns(reports);
      return;
    }
    std::vector<Run> shown;
    for (const Run& r : reports)
      if (r.run_type == Run::RT_Aggregate || r.repetitions <= 1) shown.push_back(r);
    if (!shown.empty()) ConsoleReporter::ReportRuns(shown);
  }

  // Median over the repetitions of `benchmark` (function name, plus "/arg" when it has one); 0 when
  // it did not run, so a filtered run prints zeros instead of crashing.
  double median(const std::string& benchmark, const std::string& counter) const {
    std::vector<double> v = samples(benchmark, counter);
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }
  // Largest and smallest value over the repetitions (0 when it did not run).
  double best(const std::string& benchmark, const std::string& counter) const {
    const std::vector<double> v = samples(benchmark, counter);
    return v.empty() ? 0 : *std::max_element(v.begin(), v.end());
  }
  double lowest(const std::string& benchmark, const std::string& counter) const {
    const std::vector<double> v = samples(benchmark, counter);
    return v.empty() ? 0 : *std::min_element(v.begin(), v.end());
  }
  // Every repetition's value of `counter` (none when it did not run).
  std::vector<double> samples(const std::string& benchmark, const std::string& counter) const {
    auto b = runs_.find(benchmark);
    if (b == runs_.end()) return {};
    auto c = b->second.find(counter);
    return c == b->second.end() ? std::vector<double>{} : c->second;
  }
  std::size_t repetitions(const std::string& benchmark) const {
    auto b = runs_.find(benchmark);
    if (b == runs_.end() || b->second.empty()) return 0;
    return b->second.begin()->second.size();
  }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  static std::string key(const Run& r) {
    return r.run_name.args.empty() ? r.run_name.function_name : r.run_name.function_name + "/" + r.run_name.args;
  }

  std::map<std::string, std::map<std::string, std::vector<double>>> runs_;
  std::vector<std::string> errors_;
  bool show_repetitions_;
};

// Puts our defaults in front of the user's flags; Google Benchmark lets a later flag win, so any
// of them can still be overridden on the command line.
inline std::vector<char*> with_default_flags(int argc, char** argv, std::vector<const char*> defaults) {
  std::vector<char*> out;
  out.push_back(argv[0]);
  for (const char* d : defaults) out.push_back(const_cast<char*>(d));
  for (int i = 1; i < argc; ++i) out.push_back(argv[i]);
  return out;
}

// The usual main(): our default flags (repetitions interleaved at random), Google Benchmark's
// own flags, every registered benchmark into `reporter`. False on an unknown flag.
inline bool run_interleaved(int argc, char** argv, CollectingReporter& reporter) {
  auto args = with_default_flags(argc, argv, {"--benchmark_enable_random_interleaving=true"});
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return false;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return true;
}

}  // namespace symb::bench
