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

kernel::Result<std::array<std::vector<std::string>, 5>> RoleTask::role_tasks(const RoleOptions& o) {
  std::array<std::vector<std::string>, 5> out;
  const std::array<const std::string*, 5> lists = {&o.alone, &o.head, &o.spine, &o.tail, &o.branch};
  for (std::size_t r = 0; r < lists.size(); ++r) {
    auto words = kernel::split_words(*lists[r], 1);
    if (!words) return kernel::Error{std::string(kRoleNames[r]) + ": " + words.error()};
    for (const auto& w : *words) {
      if (!os::is_valid_name(w.text))
        return kernel::Error{std::string(kRoleNames[r]) + ": '" + std::string(w.text) + "' is not a task name"};
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
                   .missing_tasks = counters_.missing_tasks.load()};
}

void RoleTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  const std::array<const std::string*, 4> faces = {&o_.front, &o_.back, &o_.left, &o_.right};
  std::optional<std::size_t> face;
  if (!m.payload.blob && v.size() == 3 && std::isfinite(v[0])) {
    for (std::size_t f = 0; f < faces.size() && !face; ++f)
      if (auto id = node().find(*faces[f]); id && *id == m.source) face = f;
  }
  if (!face) {
    counters_.ignored.bump();
    return;
  }
  counters_.readings.bump();
  docked_[*face] = v[0] >= 1.5f;
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
  if (role() != shown && t - shown_since_ >= o_.settle) take(shown);
  if (const auto r = role()) {
    send(kRolePort, {static_cast<float>(*r)});
    if (probing()) probe("role", {static_cast<float>(*r), static_cast<float>(bits)});
  }
}

void RoleTask::take(Role role) {
  os::Node& n = node();
  const auto& run = tasks_[static_cast<std::size_t>(role)];
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
  role_.store(static_cast<int>(role), std::memory_order_relaxed);
  counters_.changes.bump();
  log(os::LogLevel::kInfo, std::string("role ") +
                               (before ? std::string(kRoleNames[static_cast<std::size_t>(*before)]) + " -> " : "") +
                               std::string(kRoleNames[static_cast<std::size_t>(role)]));
  if (!missing.empty() && warning_.note(now()))
    log(os::LogLevel::kWarn, std::string("role ") + std::string(kRoleNames[static_cast<std::size_t>(role)]) +
                                 ": no task named " + missing + " on this node");
}

kernel::Status RoleTask::on_parameter_changed(std::string_view /*name*/) {
  auto lists = role_tasks(o_);
  if (!lists) return kernel::Error{lists.error()};
  tasks_ = std::move(lists).value();
  if (const auto r = role()) take(*r);  // the role's task set may have changed
  return {};
}

}  // namespace symb::control::organism
