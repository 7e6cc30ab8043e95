#include "symb/apps/run/record_options.hpp"

#include <algorithm>
#include <numeric>

#include "symb/kernel/random_stream.hpp"

namespace symb::apps::run {

namespace {

constexpr std::pair<std::string_view, RecordFormat> kFormats[] = {{"auto", RecordFormat::kAuto},
                                                                  {"csv", RecordFormat::kCsv},
                                                                  {"hdf5", RecordFormat::kHdf5},
                                                                  {"both", RecordFormat::kBoth},
                                                                  {"none", RecordFormat::kNone}};

// The stream of a run's seed the trail sample draws from: apart from every node's streams.
constexpr std::uint64_t kSampleStream = 0x7261696c73ULL;  // "trails"

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

}  // namespace

kernel::Result<RecordFormat> parse_record_format(std::string_view text) {
  for (const auto& [name, f] : kFormats)
    if (text == name) return f;
  return kernel::Error{"--record: expected csv, hdf5, both, none or auto, not " + quoted(text)};
}

std::string_view record_format_name(RecordFormat f) {
  for (const auto& [name, g] : kFormats)
    if (g == f) return name;
  return "?";
}

RecordFormat resolve_record_format(RecordFormat f, std::size_t robots) {
  if (f != RecordFormat::kAuto) return f;
  return robots > kCrowdRobots ? RecordFormat::kHdf5 : RecordFormat::kCsv;
}

bool writes_csv(RecordFormat f) { return f == RecordFormat::kCsv || f == RecordFormat::kBoth; }
bool writes_hdf5(RecordFormat f) { return f == RecordFormat::kHdf5 || f == RecordFormat::kBoth; }

kernel::Result<std::vector<std::size_t>> resolve_record_robots(std::string_view text,
                                                               std::span<const std::string> names) {
  const auto find = [&](std::string_view name) -> std::size_t {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const auto fail = [&](std::size_t column, const std::string& what) {
    return kernel::Error{"--record-robots: column " + std::to_string(column + 1) + ": " + what};
  };
  std::vector<bool> picked(names.size(), false);
  std::size_t at = 0;
  for (;;) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string_view item = text.substr(at, comma - at);
    if (item.empty()) return fail(at, "empty item (expected a robot's name or FIRST..LAST)");
    const std::size_t dots = item.find("..");
    if (dots == std::string_view::npos) {
      const std::size_t i = find(item);
      if (i == names.size()) return fail(at, "no robot named " + quoted(item));
      picked[i] = true;
    } else {
      const std::string_view first = item.substr(0, dots), last = item.substr(dots + 2);
      const std::size_t a = find(first), b = find(last);
      if (a == names.size()) return fail(at, "no robot named " + quoted(first));
      if (b == names.size()) return fail(at + dots + 2, "no robot named " + quoted(last));
      if (b < a) return fail(at, quoted(last) + " comes before " + quoted(first) + " in the scenario");
      for (std::size_t i = a; i <= b; ++i) picked[i] = true;
    }
    if (comma == text.size()) break;
    at = comma + 1;
  }
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < picked.size(); ++i)
    if (picked[i]) out.push_back(i);
  return out;
}

std::vector<std::size_t> sample_robots(std::size_t n, std::size_t k, std::uint64_t seed) {
  std::vector<std::size_t> all(n);
  std::iota(all.begin(), all.end(), std::size_t{0});
  if (n <= k) return all;
  // The first k steps of a Fisher-Yates shuffle.
  kernel::RandomStream random(seed, kSampleStream);
  for (std::size_t i = 0; i < k; ++i) std::swap(all[i], all[i + random.below(n - i)]);
  all.resize(k);
  std::sort(all.begin(), all.end());
  return all;
}

}  // namespace symb::apps::run
