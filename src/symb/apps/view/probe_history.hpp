// ProbeHistory: probe series over a whole run in bounded memory, for the web view's time plots
// (probes of the robot shown, fitness of an evolution run). A series is one (task, channel); it
// keeps the time and the first `width` values of its samples. When a series holds `capacity`
// points, every other point goes and from then on only every 2nd (then 4th, ...) sample is kept:
// a plot always spans the run from its start, at a resolution that halves as the run grows, and
// memory stays at most max_series x capacity x (width + 2) numbers. Series beyond `max_series`
// are counted and not kept.
//
// Besides the points, each series keeps its latest sample whole (the page's bars and numbers) and
// the points kept since the last take() (what the page has not had yet): take(false) hands those
// on; take(true) hands on every point (a page that just opened). Pure: no threads, no time; the
// live view takes its lock around it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace symb::apps::view {

struct ProbeHistoryOptions {
  std::size_t capacity = 256;    // points per series (an even number, at least 2): a plot's width
  std::size_t width = 8;         // values per point
  std::size_t max_series = 32;   // series kept
  std::size_t max_latest = 256;  // values kept of the latest sample
};

// One series as handed on: `points` is flat, (time, width values) per point, a missing value NaN.
struct ProbeSeriesView {
  std::string task, channel;
  double latest_time = 0;
  std::vector<float> latest;  // the latest sample, whole (up to max_latest values)
  std::size_t width = 0;
  std::vector<double> points;  // time, then `width` values, per point
  std::uint64_t stride = 1;    // samples per point kept now
};

class ProbeHistory {
 public:
  // Throws std::invalid_argument for a capacity below 2 or odd, or a zero width.
  explicit ProbeHistory(ProbeHistoryOptions options = {});

  // One sample of (task, channel) at `seconds`.
  void record(std::string_view task, std::string_view channel, double seconds, std::span<const float> values);
  // Every series, with its points kept since the last take (or all of them), in the order the
  // series first came; the points of the last take are then marked as handed on.
  std::vector<ProbeSeriesView> take(bool all);
  void clear();

  std::size_t series() const { return series_.size(); }
  std::uint64_t refused_series() const { return refused_series_; }
  // Points held by the series (task, channel), or 0.
  std::size_t points(std::string_view task, std::string_view channel) const;

 private:
  struct Series {
    std::string task, channel;
    std::size_t width = 0;  // values per point: the first sample's count, at most options.width
    std::uint64_t stride = 1, seen = 0;
    std::vector<double> points;    // (time, width values) per point
    std::size_t pending_from = 0;  // points from here on have not been handed on
    double latest_time = 0;
    std::vector<float> latest;
  };
  ProbeHistoryOptions options_;
  std::vector<Series> series_;
  std::uint64_t refused_series_ = 0;
};

}  // namespace symb::apps::view
