// What a 2D run records per step and how (`symb run --record`, `--record-every`,
// `--record-robots`): the format of the step file (steps.csv, steps.h5, both or none), which steps
// (every N-th), which robots (a list of names and name ranges), and the robot count above which a
// run counts as a crowd: HDF5 by default, and pictures that stay readable with thousands of robots
// (a density map, a sample of trails, per-robot statistics) instead of a path per robot.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::apps::run {

// More robots than this make a crowd: `--record auto` writes steps.h5 instead of steps.csv (a
// minute of 1,000 robots is 168 MB of CSV), and the pictures are density.svg, trails.svg and
// robot_stats.svg instead of trajectory.svg (a polyline per robot is unreadable long before).
// Every shipped scenario has 20 robots or fewer: their outputs stay as they were.
inline constexpr std::size_t kCrowdRobots = 100;
// How many robots' trails a crowd's trails.svg draws (chosen by the run's seed).
inline constexpr std::size_t kTrailSample = 24;

enum class RecordFormat { kAuto, kCsv, kHdf5, kBoth, kNone };

struct RecordOptions {
  RecordFormat format = RecordFormat::kAuto;
  // `--record-robots`: empty records every robot; else the list as given, resolved against the
  // world's robots when the run starts (resolve_record_robots).
  std::string robots;
};

// "csv", "hdf5", "both", "none" or "auto"; the error lists them.
kernel::Result<RecordFormat> parse_record_format(std::string_view text);
std::string_view record_format_name(RecordFormat f);
// What `auto` means for a world of `robots` robots: kCsv up to kCrowdRobots, kHdf5 above.
RecordFormat resolve_record_format(RecordFormat f, std::size_t robots);
bool writes_csv(RecordFormat resolved);
bool writes_hdf5(RecordFormat resolved);

// `--record-robots` text: comma-separated items, each a robot's name (`t3`) or an inclusive range
// of two names in the scenario's order (`t0..t99`). Returns the indices of `names` it picks, in
// the world's order, each once. An error names the item and its column in the text (1-based):
// "--record-robots: column 5: no robot named 'x7'".
kernel::Result<std::vector<std::size_t>> resolve_record_robots(std::string_view text,
                                                               std::span<const std::string> names);

// `k` of the indices 0..n-1 (all of them when n <= k), chosen by `seed` (the same seed, the same
// sample), in increasing order.
std::vector<std::size_t> sample_robots(std::size_t n, std::size_t k, std::uint64_t seed);

}  // namespace symb::apps::run
