#include "symb/control/organism/role_task.hpp"

#include <algorithm>
#include <cmath>

#include "symb/kernel/source_text.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::control::organism {

Role role_of(unsigned docked) {
  if (docked & (kLeft | kRight)) return Role::kBranch;
  const bool front = docked & kFront, back = docked & kBack;
  if (front && back) return Role::kSpine;
  if (back) return Role::kHead;
  if (front) return Role::kTail;
  return Role::kAlone;
}

kernel::Result<std::array<std::vector<std::string>, 6>> RoleTask::role_tasks(const RoleOptions& o) {
  std::array<std::vector<std::string>, 6> out;
  const std::array<const std::string*, 6> lists = {&o.alone, &o.head, &o.spine, &o.tail, &o.branch, &o.complete};
  for (std::size_t r = 0; r < lists.size(); ++r) {
    const std::string list_name = r < kRoleNames.size() ? std::string(kRoleNames[r]) : "complete";
    auto words = kernel::split_words(*lists[r], 1);
    if (!words) return kernel::Error{list_name + ": " + words.error()};
    for (const auto& w : *words) {
      if (!os::is_valid_name(w.text))
        return kernel::Error{list_name + ": '" + std::string(w.text) + "' is not a task name"};
      out[r].emplace_back(w.text);
    }
  }
  return out;
}

kernel::Result<std::unique_ptr<RoleTask>> RoleTask::create(RoleOptions options) {
  if (auto lists = role_tasks(options); !lists) return kernel::Error{lists.error()};
  return std::unique_ptr<RoleTask>(new RoleTask(std::move(options)));
}

RoleTask::RoleTask(RoleOptions options) : o_(std::move(options)), tasks_(*role_tasks(o_)) { bind_parameters(o_); }

std::optional<Role> RoleTask::role() const {
  const int r = role_.load(std::memory_order_relaxed);
  return r < 0 ? std::nullopt : std::optional<Role>(static_cast<Role>(r));
}

RoleStats RoleTask::stats() const {
  return RoleStats{.changes = counters_.changes.load(),
                   .readings = counters_.readings.load(),
                   .ignored = counters_.ignored.load(),
                   .missing_tasks = counters_.missing_tasks.load(),
                   .heartbeats = counters_.heartbeats.load()};
}

void RoleTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  if (m.port == kRoleHeartbeatPort && !m.payload.blob && v.size() == 2 && std::isfinite(v[0]) && std::isfinite(v[1]) &&
      v[0] >= 0 && v[0] < 16777216.0f && v[0] != static_cast<float>(o_.module)) {
    const int module = static_cast<int>(v[0]);
    auto it = std::find_if(heard_.begin(), heard_.end(), [&](const auto& h) { return h.first == module; });
    if (it == heard_.end()) {
      if (heard_.size() >= 4096) {  // more modules than any organism here: keep memory bounded
        counters_.ignored.bump();
        return;
      }
      heard_.push_back({module, {}});
      it = heard_.end() - 1;
    }
    it->second = Heard{m.time, static_cast<int>(v[1])};
    counters_.heartbeats.bump();
    return;
  }
  const std::array<const std::string*, 4> faces = {&o_.front, &o_.back, &o_.left, &o_.right};
  std::optional<std::size_t> face;
  if (!m.payload.blob && v.size() >= 3 && std::isfinite(v[0])) {
    for (std::size_t f = 0; f < faces.size() && !face; ++f)
      if (auto id = node().find(*faces[f]); id && *id == m.source) face = f;
  }
  if (!face) {
    counters_.ignored.bump();
    return;
  }
  counters_.readings.bump();
  docked_[*face] = v[0] >= 1.5f;
  if (*face == 0) front_peer_ = docked_[0] && std::isfinite(v[2]) && v[2] >= 0 ? static_cast<int>(v[2]) : -1;
}

void RoleTask::count_heard(kernel::Time t) {
  int count = 1, place = front_peer_ < 0 ? 0 : -1;
  for (const auto& [module, h] : heard_) {
    if (t - h.at > o_.heard_timeout) continue;
    ++count;
    if (module == front_peer_ && h.place >= 0) place = h.place + 1;
  }
  heard_count_.store(count, std::memory_order_relaxed);
  if (place != place_.load(std::memory_order_relaxed)) {
    place_.store(place, std::memory_order_relaxed);
    if (place >= 0 && !o_.place_param.empty()) {
      const auto dot = o_.place_param.find('.');
      const auto id = dot == std::string::npos ? std::nullopt : node().find(o_.place_param.substr(0, dot));
      if (!id) {
        if (warning_.note(t)) log(os::LogLevel::kWarn, "place_param: no task '" + o_.place_param + "'");
      } else if (auto st = node().set_parameter(*id, o_.place_param.substr(dot + 1), std::to_string(place)); !st) {
        if (warning_.note(t)) log(os::LogLevel::kWarn, "place_param " + o_.place_param + ": " + st.error());
      }
    }
  }
}

void RoleTask::on_tick() {
  unsigned bits = 0;
  for (std::size_t f = 0; f < docked_.size(); ++f)
    if (docked_[f]) bits |= 1u << f;
  const Role shown = role_of(bits);
  const kernel::Time t = now();
  if (shown_ != shown) {
    shown_ = shown;
    shown_since_ = t;
  }
  bool complete = false;
  if (o_.size > 0) {
    count_heard(t);
    complete = shown != Role::kAlone && heard_count_.load(std::memory_order_relaxed) >= o_.size;
    send(kRoleHeartbeatPort, {static_cast<float>(o_.module), static_cast<float>(place_.load())});
  }
  if ((role() != shown || running_complete_ != complete) && t - shown_since_ >= o_.settle) take(shown, complete);
  if (const auto r = role()) {
    send(kRolePort, {static_cast<float>(*r)});
    if (probing()) probe("role", {static_cast<float>(*r), static_cast<float>(bits)});
  }
}

void RoleTask::take(Role role, bool complete) {
  os::Node& n = node();
  const auto& run = tasks_[complete ? tasks_.size() - 1 : static_cast<std::size_t>(role)];
  std::string missing;
  // Suspend what the new role does not run first, so two roles' controllers never run together.
  for (std::size_t r = 0; r < tasks_.size(); ++r) {
    for (const auto& name : tasks_[r]) {
      if (std::find(run.begin(), run.end(), name) != run.end()) continue;
      const auto id = n.find(name);
      if (!id) continue;  // warned about below if the new role needs it, else irrelevant
      if (auto info = n.info(*id); info && info->state == os::TaskState::kRunning) (void)n.suspend(*id);
    }
  }
  for (const auto& name : run) {
    const auto id = n.find(name);
    const auto info = id ? n.info(*id) : std::nullopt;
    if (!info) {
      counters_.missing_tasks.bump();
      missing += (missing.empty() ? "" : ", ") + name;
      continue;
    }
    if (info->state == os::TaskState::kCreated) (void)n.start(*id);
    if (info->state == os::TaskState::kSuspended) (void)n.resume(*id);
  }
  const auto before = this->role();
  const bool was_complete = running_complete_;
  role_.store(static_cast<int>(role), std::memory_order_relaxed);
  running_complete_ = complete;
  complete_.store(complete, std::memory_order_relaxed);
  if (before != role) counters_.changes.bump();
  if (before != role)
    log(os::LogLevel::kInfo, std::string("role ") +
                                 (before ? std::string(kRoleNames[static_cast<std::size_t>(*before)]) + " -> " : "") +
                                 std::string(kRoleNames[static_cast<std::size_t>(role)]));
  if (was_complete != complete)
    log(os::LogLevel::kInfo, complete ? "organism complete: " + std::to_string(heard_count_.load()) + " modules"
                                      : std::string("organism no longer complete"));
  if (!missing.empty() && warning_.note(now()))
    log(os::LogLevel::kWarn, std::string("role ") + std::string(kRoleNames[static_cast<std::size_t>(role)]) +
                                 ": no task named " + missing + " on this node");
}

kernel::Status RoleTask::on_parameter_changed(std::string_view /*name*/) {
  auto lists = role_tasks(o_);
  if (!lists) return kernel::Error{lists.error()};
  tasks_ = std::move(lists).value();
  if (const auto r = role()) take(*r, running_complete_);  // the role's task set may have changed
  return {};
}

}  // namespace symb::control::organism
