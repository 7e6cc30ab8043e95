#include "symb/apps/run/probe_recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::run {

os::ProbeSink ProbeRecorder::sink() {
  return [this](const os::ProbeSample& s) { record(s); };
}

void ProbeRecorder::record(const os::ProbeSample& s) {
  const double t = std::chrono::duration<double>(s.time).count();
  const std::size_t n = std::min(s.values.size(), kMaxValues);
  std::lock_guard lock(mu_);
  ++samples_;
  if (csv_ != nullptr) {
    if (!header_written_) {
      *csv_ << "time_s,robot,task,channel,values...\n";
      header_written_ = true;
    }
    *csv_ << fixed(t, 3) << ',' << s.node << ',' << s.task << ',' << s.channel;
    for (std::size_t i = 0; i < n; ++i) *csv_ << ',' << s.values[i];
    *csv_ << '\n';
  }
  Key key{std::string(s.node), std::string(s.task), std::string(s.channel)};
  auto [it, added] = index_.try_emplace(std::move(key), series_.size());
  if (added) {
    Series fresh;
    fresh.data.robot = s.node;
    fresh.data.task = s.task;
    fresh.data.channel = s.channel;
    series_.push_back(std::move(fresh));
  }
  Series& series = series_[it->second];
  ProbeSeries& d = series.data;
  if (d.samples++ % series.stride != 0) return;
  d.width = std::max(d.width, n);
  d.times.push_back(t);
  d.values.emplace_back(s.values.begin(), s.values.begin() + static_cast<std::ptrdiff_t>(n));
  if (d.times.size() >= kMaxPoints) {
    // Keep every other point and from now on every other sample: still evenly spaced in samples.
    std::size_t w = 0;
    for (std::size_t r = 0; r < d.times.size(); r += 2, ++w) {
      if (w == r) continue;  // a vector moved onto itself would come out empty
      d.times[w] = d.times[r];
      d.values[w] = std::move(d.values[r]);
    }
    d.times.resize(w);
    d.values.resize(w);
    series.stride *= 2;
  }
}

std::vector<const ProbeSeries*> ProbeRecorder::series() const {
  std::lock_guard lock(mu_);
  std::vector<const ProbeSeries*> out;
  for (const Series& s : series_) out.push_back(&s.data);
  return out;
}

std::uint64_t ProbeRecorder::samples() const {
  std::lock_guard lock(mu_);
  return samples_;
}

}  // namespace symb::apps::run
