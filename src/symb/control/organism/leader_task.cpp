#include "symb/control/organism/leader_task.hpp"

#include <cmath>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::control::organism {

kernel::Result<std::unique_ptr<LeaderTask>> LeaderTask::create(LeaderOptions options) {
  if (!os::is_valid_name(options.service))
    return kernel::Error{"service: name the task this module runs while it leads"};
  if (options.timeout.count() <= 0) return kernel::Error{"timeout must be positive"};
  return std::unique_ptr<LeaderTask>(new LeaderTask(std::move(options)));
}

LeaderStats LeaderTask::stats() const {
  return LeaderStats{.heartbeats = counters_.heartbeats.load(),
                     .ignored = counters_.ignored.load(),
                     .took_lead = counters_.took_lead.load(),
                     .yielded = counters_.yielded.load()};
}

void LeaderTask::on_start() {
  started_ = now();
  // Until it leads, the service does not run here.
  if (auto id = node().find(o_.service); id)
    if (auto info = node().info(*id); info && info->state == os::TaskState::kRunning) (void)node().suspend(*id);
}

void LeaderTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  const bool ok = !m.payload.blob && m.port == kHeartbeatPort && v.size() == 3 && std::isfinite(v[0]) &&
                  v[0] == std::round(v[0]) && v[0] != static_cast<float>(o_.rank);
  if (!ok) {
    counters_.ignored.bump();
    return;
  }
  const auto rank = static_cast<std::int64_t>(v[0]);
  if (!heard_.contains(rank) && heard_.size() >= kMaxCandidates) {
    auto oldest = heard_.begin();
    for (auto it = heard_.begin(); it != heard_.end(); ++it)
      if (it->second.at < oldest->second.at) oldest = it;
    heard_.erase(oldest);
  }
  heard_[rank] = Heard{now(), v[1] >= 0.5f, v[2] >= 0.5f};
  counters_.heartbeats.bump();
}

bool LeaderTask::service_ok() const {
  const auto id = node().find(o_.service);
  const auto info = id ? node().info(*id) : std::nullopt;
  return info && info->state != os::TaskState::kFaulted;
}

void LeaderTask::lead(bool on, const std::string& why) {
  os::Node& n = node();
  if (auto id = n.find(o_.service)) {
    const auto info = n.info(*id);
    if (on && info && info->state == os::TaskState::kCreated) (void)n.start(*id);
    if (on && info && info->state == os::TaskState::kSuspended) (void)n.resume(*id);
    if (!on && info && info->state == os::TaskState::kRunning) (void)n.suspend(*id);
  }
  leading_.store(on, std::memory_order_relaxed);
  (on ? counters_.took_lead : counters_.yielded).bump();
  log(on ? os::LogLevel::kInfo : os::LogLevel::kWarn,
      (on ? "leads: runs " : "steps down: stops ") + o_.service + " (" + why + ")");
}

void LeaderTask::on_tick() {
  const kernel::Time t = now();
  const bool eligible = service_ok();
  std::size_t leaders = 0;
  std::optional<std::int64_t> lower_leader;
  bool lower_eligible = false;
  for (const auto& [rank, h] : heard_) {
    if (t - h.at > o_.timeout) continue;
    if (h.leading) ++leaders;
    if (h.leading && rank < o_.rank && !lower_leader) lower_leader = rank;
    if (h.eligible && rank < o_.rank) lower_eligible = true;
  }
  if (leading()) {
    if (!eligible)
      lead(false, "its service has faulted or is gone");
    else if (lower_leader)
      lead(false, "rank " + std::to_string(*lower_leader) + " leads");
  } else if (eligible && leaders == 0 && !lower_eligible && t - started_ >= o_.timeout) {
    lead(true, "no leader heard for " +
                   std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(o_.timeout).count()) + " ms");
  }
  send(kHeartbeatPort, {static_cast<float>(o_.rank), leading() ? 1.0f : 0.0f, eligible ? 1.0f : 0.0f});
  if (probing()) probe("leader", {leading() ? 1.0f : 0.0f, eligible ? 1.0f : 0.0f, static_cast<float>(leaders)});
}

}  // namespace symb::control::organism
