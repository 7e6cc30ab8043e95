#include "symb/apps/view/probe_history.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace symb::apps::view {

ProbeHistory::ProbeHistory(ProbeHistoryOptions options) : options_(options) {
  if (options_.capacity < 2 || options_.capacity % 2 != 0)
    throw std::invalid_argument("ProbeHistory: the capacity must be an even number of at least 2");
  if (options_.width == 0) throw std::invalid_argument("ProbeHistory: the width must be at least 1");
}

void ProbeHistory::record(std::string_view task, std::string_view channel, double seconds,
                          std::span<const float> values) {
  auto it = std::find_if(series_.begin(), series_.end(),
                         [&](const Series& s) { return s.task == task && s.channel == channel; });
  if (it == series_.end()) {
    if (series_.size() >= options_.max_series) {
      ++refused_series_;
      return;
    }
    Series s;
    s.task = task;
    s.channel = channel;
    s.width = std::clamp<std::size_t>(values.size(), 1, options_.width);
    s.points.reserve(std::min<std::size_t>(options_.capacity, 64) * (s.width + 1));
    it = series_.insert(series_.end(), std::move(s));
  }
  Series& s = *it;
  s.latest_time = seconds;
  s.latest.assign(values.begin(),
                  values.begin() + static_cast<std::ptrdiff_t>(std::min(values.size(), options_.max_latest)));
  if (s.seen++ % s.stride != 0) return;
  const std::size_t row = s.width + 1;
  if (s.points.size() / row >= options_.capacity) {
    // Full: keep every other point (the first, third, ...), and from now on every 2nd sample of
    // those kept so far. Points not yet handed on keep their place among the survivors.
    std::size_t kept = 0;
    std::size_t pending_kept = s.points.size() / row;
    for (std::size_t p = 0; p < s.points.size() / row; p += 2, ++kept) {
      if (p >= s.pending_from && pending_kept > kept) pending_kept = kept;
      std::copy_n(s.points.begin() + static_cast<std::ptrdiff_t>(p * row), row,
                  s.points.begin() + static_cast<std::ptrdiff_t>(kept * row));
    }
    s.points.resize(kept * row);
    s.pending_from = std::min(pending_kept, kept);
    s.stride *= 2;
    s.seen = 1;  // this sample is the first of its stride
  }
  s.points.push_back(seconds);
  for (std::size_t k = 0; k < s.width; ++k)
    s.points.push_back(k < values.size() ? static_cast<double>(values[k]) : std::numeric_limits<double>::quiet_NaN());
}

std::vector<ProbeSeriesView> ProbeHistory::take(bool all) {
  std::vector<ProbeSeriesView> out;
  out.reserve(series_.size());
  for (Series& s : series_) {
    ProbeSeriesView v;
    v.task = s.task;
    v.channel = s.channel;
    v.latest_time = s.latest_time;
    v.latest = s.latest;
    v.width = s.width;
    v.stride = s.stride;
    const std::size_t row = s.width + 1;
    const std::size_t from = all ? 0 : s.pending_from * row;
    v.points.assign(s.points.begin() + static_cast<std::ptrdiff_t>(from), s.points.end());
    s.pending_from = s.points.size() / row;
    out.push_back(std::move(v));
  }
  return out;
}

void ProbeHistory::clear() {
  series_.clear();
  refused_series_ = 0;
}

std::size_t ProbeHistory::points(std::string_view task, std::string_view channel) const {
  for (const Series& s : series_)
    if (s.task == task && s.channel == channel) return s.points.size() / (s.width + 1);
  return 0;
}

}  // namespace symb::apps::view
