// EvolveCheckpoint: what `symb evolve` writes so that a killed run can be resumed with the same
// result as an uninterrupted one. The simulator is deterministic, so a checkpoint holds no
// simulator or task state at all: it holds how to get there again and how to tell it got there:
// the scenario file's hash, the seed, the run's duration, the virtual time reached, and the number
// and hash of the evaluations finished by then (the evolution history). `--resume` re-runs from
// the start to that time (virtual time: about a thousand times faster than the robot would),
// checks the history against the hash, and carries on. A history that differs (another scenario
// file, another build) is refused, never silently continued.
//
// Text form (one "key value" per line, '#' comments):
//   symb-evolve-checkpoint 1
//   scenario evolve_maze.yaml
//   scenario_hash 89ab...        (16 hex digits, FNV-1a of the scenario file's bytes)
//   seed 1
//   duration_ns 7200000000000
//   time_ns 600000000000
//   evaluations 28
//   history_hash 0123...         (16 hex digits, EvaluationHistory::hash)
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::apps::evolve {

struct EvaluationRow {
  kernel::Time time{0};
  int kind = 0;  // 0 first, 1 challenger, 2 re-evaluation (the task's "fitness" probe)
  float fitness = 0;
  float champion_fitness = 0;
  float sigma = 0;
  std::uint64_t evaluations = 0;
};

// FNV-1a over every row's fields (floats by their bits): equal hashes, equal histories.
class EvaluationHistory {
 public:
  void add(const EvaluationRow& row);
  std::uint64_t hash() const { return hash_; }
  std::uint64_t size() const { return size_; }

 private:
  void mix(std::uint64_t v);
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;
  std::uint64_t size_ = 0;
};

struct EvolveCheckpoint {
  std::string scenario;  // the path as given, for people
  std::uint64_t scenario_hash = 0;
  std::uint64_t seed = 0;
  kernel::Duration duration{0};
  kernel::Time time{0};
  std::uint64_t evaluations = 0;
  std::uint64_t history_hash = 0;
  bool operator==(const EvolveCheckpoint&) const = default;
};

std::uint64_t fnv1a(std::string_view bytes);
std::string to_text(const EvolveCheckpoint& c);
// "LINE: message" on a malformed text.
kernel::Result<EvolveCheckpoint> parse_checkpoint(std::string_view text);

}  // namespace symb::apps::evolve
