// ProbeRecorder: the run's record of what the controllers publish about themselves (Task::probe:
// hormone levels per compartment, network activations, the active layer, schema vectors). Every
// sample goes to probes.csv as it comes; each series (robot, task, channel) is also kept, thinned
// to at most kMaxPoints evenly spaced samples, for a line plot per series (probe_plot.hpp).
//
// Thread-safe: under the thread executor the robots' tasks probe from their own threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include "symb/os/node.hpp"

namespace symb::apps::run {

struct ProbeSeries {
  std::string robot, task, channel;
  std::size_t width = 0;      // values per sample (the widest seen; shorter samples leave NaN)
  std::vector<double> times;  // seconds, thinned
  std::vector<std::vector<float>> values;
  std::uint64_t samples = 0;  // all samples, before thinning
  // The legend's name per value index (a module per line); past its end, "<channel>[k]".
  std::vector<std::string> labels;
};

class ProbeRecorder {
 public:
  static constexpr std::size_t kMaxPoints = 4096;
  static constexpr std::size_t kMaxValues = 64;  // per sample kept; more are cut (CSV too)

  // `csv` may be null; its header is written at the first sample.
  explicit ProbeRecorder(std::ostream* csv) : csv_(csv) {}

  // The sink to install on every node of the run (os::Node::set_probe_sink).
  os::ProbeSink sink();
  void record(const os::ProbeSample& s);

  // Series in order of first appearance. Call after the run (no sample may arrive meanwhile).
  std::vector<const ProbeSeries*> series() const;
  std::uint64_t samples() const;

 private:
  using Key = std::tuple<std::string, std::string, std::string>;
  struct Series {
    ProbeSeries data;
    std::uint64_t stride = 1;  // keep every stride-th sample
  };

  mutable std::mutex mu_;
  std::ostream* csv_;
  bool header_written_ = false;
  std::uint64_t samples_ = 0;
  std::map<Key, std::size_t> index_;
  std::vector<Series> series_;
};

}  // namespace symb::apps::run
