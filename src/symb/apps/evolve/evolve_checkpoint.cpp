#include "symb/apps/evolve/evolve_checkpoint.hpp"

#include <bit>
#include <charconv>
#include <set>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::evolve {

namespace {

bool parse_digits(std::string_view text, std::uint64_t& out, int base) {
  if (text.empty()) return false;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out, base);
  return ec == std::errc{} && end == text.data() + text.size();
}

}  // namespace

void EvaluationHistory::mix(std::uint64_t v) {
  for (int i = 0; i < 8; ++i) {
    hash_ ^= (v >> (8 * i)) & 0xffu;
    hash_ *= 0x100000001b3ULL;
  }
}

void EvaluationHistory::add(const EvaluationRow& r) {
  mix(static_cast<std::uint64_t>(r.time.count()));
  mix(static_cast<std::uint64_t>(r.kind));
  mix(std::bit_cast<std::uint32_t>(r.fitness));
  mix(std::bit_cast<std::uint32_t>(r.champion_fitness));
  mix(std::bit_cast<std::uint32_t>(r.sigma));
  mix(r.evaluations);
  ++size_;
}

std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string to_text(const EvolveCheckpoint& c) {
  std::string s =
      "# symb evolve checkpoint: resume with `symb evolve SCENARIO --out DIR --resume` (re-runs\n"
      "# deterministically to time_ns, checks the evaluation history, then carries on)\n"
      "symb-evolve-checkpoint 1\n";
  s += "scenario " + c.scenario + "\n";
  s += "scenario_hash " + hex64(c.scenario_hash) + "\n";
  s += "seed " + std::to_string(c.seed) + "\n";
  s += "duration_ns " + std::to_string(c.duration.count()) + "\n";
  s += "time_ns " + std::to_string(c.time.count()) + "\n";
  s += "evaluations " + std::to_string(c.evaluations) + "\n";
  s += "history_hash " + hex64(c.history_hash) + "\n";
  return s;
}

kernel::Result<EvolveCheckpoint> parse_checkpoint(std::string_view text) {
  EvolveCheckpoint c;
  std::set<std::string> seen;
  bool header = false;
  int line_no = 0;
  while (!text.empty()) {
    ++line_no;
    const auto nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r' || line.back() == '\t')) line.remove_suffix(1);
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
    if (line.empty()) continue;
    const auto space = line.find(' ');
    const std::string key(line.substr(0, space));
    const std::string_view value = space == std::string_view::npos ? std::string_view{} : line.substr(space + 1);
    const auto fail = [&](const std::string& why) { return kernel::Error{std::to_string(line_no) + ": " + why}; };
    if (!header) {
      if (key != "symb-evolve-checkpoint" || value != "1")
        return fail("expected 'symb-evolve-checkpoint 1' (not a checkpoint of this version)");
      header = true;
      continue;
    }
    if (!seen.insert(key).second) return fail("'" + key + "' given twice");
    std::uint64_t v = 0;
    if (key == "scenario") {
      c.scenario = std::string(value);
    } else if (key == "scenario_hash" || key == "history_hash") {
      if (value.size() != 16 || !parse_digits(value, v, 16)) return fail(key + ": expected 16 hex digits");
      (key == "scenario_hash" ? c.scenario_hash : c.history_hash) = v;
    } else if (key == "seed" || key == "evaluations" || key == "duration_ns" || key == "time_ns") {
      if (!parse_digits(value, v, 10)) return fail(key + ": expected a whole number");
      if ((key == "duration_ns" || key == "time_ns") && v > static_cast<std::uint64_t>(INT64_MAX))
        return fail(key + ": too large");
      if (key == "seed") c.seed = v;
      if (key == "evaluations") c.evaluations = v;
      if (key == "duration_ns") c.duration = kernel::Duration(static_cast<std::int64_t>(v));
      if (key == "time_ns") c.time = kernel::Time(static_cast<std::int64_t>(v));
    } else {
      return fail("unknown key '" + key + "'");
    }
  }
  if (!header) return kernel::Error{"1: empty checkpoint"};
  for (const char* k : {"scenario_hash", "seed", "duration_ns", "time_ns", "evaluations", "history_hash"})
    if (!seen.count(k)) return kernel::Error{std::to_string(line_no) + ": missing '" + std::string(k) + "'"};
  if (c.time > c.duration) return kernel::Error{std::to_string(line_no) + ": time_ns beyond duration_ns"};
  return c;
}

}  // namespace symb::apps::evolve
