// LeaderTask: one module of an organism runs a service that only one should run (the vision task
// of the paper's camera modules, section VI-B), and another takes it over when that module leaves
// or its service fails. Every module able to run the service has a leader task; they tell each
// other, by heartbeats over the organism bus, who they are and whether they lead:
//
//   in/out port 1: [rank, leading (0/1), eligible (0/1)]   sent at every tick (the heartbeat)
//
// Ranks are unique numbers (the module's place, or any fixed order); the lowest rank wins. Rules,
// applied at every tick from what was heard within `timeout`:
//   - a leader that hears a leader of a lower rank yields (its service is suspended);
//   - a module that is not leading takes the lead (its service is started or resumed) when it is
//     eligible, it has heard no leader, it has listened for at least `timeout` since it started
//     (so it knows who is there), and no eligible module of a lower rank was heard;
//   - a module whose service has faulted, or is gone, is not eligible: a leader steps down at once
//     and says so in its heartbeat, so the next one takes over at its next tick, not after a
//     timeout.
// A leader that is undocked simply goes silent for the others: after `timeout` the lowest eligible
// rank that is left takes over (so a failover takes at most timeout + one period). The undocked
// module keeps leading on its own, which is right: it is an organism of one now.
// Probe "leader": [leading, eligible, leaders heard].
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "symb/kernel/counter.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"

namespace symb::control::organism {

inline constexpr os::Port kHeartbeatPort = 1;
// At most this many other candidates are remembered; the one heard least recently goes first.
inline constexpr std::size_t kMaxCandidates = 64;

struct LeaderOptions {
  std::int64_t rank = 0;
  std::string service;  // the task this module runs while it leads
  kernel::Duration timeout = std::chrono::milliseconds(350);
};

struct LeaderStats {
  std::uint64_t heartbeats = 0;  // heard from others
  std::uint64_t ignored = 0;     // malformed, or our own rank
  std::uint64_t took_lead = 0;
  std::uint64_t yielded = 0;  // to a lower rank, or because our service failed
};

class LeaderTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<LeaderTask>> create(LeaderOptions options);
  bool leading() const { return leading_.load(std::memory_order_relaxed); }  // any thread
  LeaderStats stats() const;

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;

 private:
  explicit LeaderTask(LeaderOptions options) : o_(std::move(options)) { bind_parameters(o_); }
  struct Heard {
    kernel::Time at{0};
    bool leading = false;
    bool eligible = false;
  };
  bool service_ok() const;  // the service exists and has not faulted
  void lead(bool on, const std::string& why);

  LeaderOptions o_;
  std::map<std::int64_t, Heard> heard_;  // by rank
  kernel::Time started_{0};
  std::atomic<bool> leading_{false};
  struct Counters {
    kernel::Counter heartbeats, ignored, took_lead, yielded;
  } counters_;
};

}  // namespace symb::control::organism
