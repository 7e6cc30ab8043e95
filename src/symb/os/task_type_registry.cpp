#include "symb/os/task_type_registry.hpp"

#include <algorithm>

namespace symb::os {

using kernel::Error;

const ParamSpec* TaskType::param(std::string_view param_name) const {
  for (const auto& p : params)
    if (p.name == param_name) return &p;
  return nullptr;
}

kernel::Status TaskTypeRegistry::add(TaskType type) {
  if (!is_valid_name(type.name)) return Error{"task type name '" + type.name + "' is not a valid name"};
  if (types_.contains(type.name) || (shared_ && shared_->find(type.name)))
    return Error{"task type '" + type.name + "' is already registered"};
  if (!type.make) return Error{"task type '" + type.name + "' has no factory"};
  if (!type.live.empty() && type.live.size() != type.params.size())
    return Error{"task type '" + type.name + "': live parameters do not match its parameters"};
  for (std::size_t i = 0; i < type.params.size(); ++i) {
    const ParamSpec& p = type.params[i];
    if (!is_valid_name(p.name)) return Error{"task type '" + type.name + "': invalid parameter name '" + p.name + "'"};
    for (std::size_t j = 0; j < i; ++j)
      if (type.params[j].name == p.name)
        return Error{"task type '" + type.name + "': parameter '" + p.name + "' twice"};
    if (auto st = check_param_value(p, p.default_value); !st)
      return Error{"task type '" + type.name + "': default of " + st.error()};
  }
  std::string name = type.name;
  types_.emplace(std::move(name), std::move(type));
  return {};
}

const TaskType* TaskTypeRegistry::find(std::string_view name) const {
  auto it = types_.find(name);
  if (it != types_.end()) return &it->second;
  return shared_ ? shared_->find(name) : nullptr;
}

std::vector<const TaskType*> TaskTypeRegistry::list() const {
  std::vector<const TaskType*> out = shared_ ? shared_->list() : std::vector<const TaskType*>{};
  for (const auto& [n, t] : types_) out.push_back(&t);
  std::sort(out.begin(), out.end(), [](const TaskType* a, const TaskType* b) { return a->name < b->name; });
  return out;
}

std::string TaskTypeRegistry::unknown_type_error(std::string_view name) const {
  std::vector<std::string_view> names;
  for (const TaskType* t : list()) names.push_back(t->name);
  std::string msg = "unknown task type '" + std::string(name.substr(0, 63)) + "'";
  if (auto hint = closest_name(name, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
  return msg;
}

kernel::Result<ParamSet> TaskTypeRegistry::resolve(const TaskType& type, std::span<const ParamAssignment> given) const {
  std::vector<std::pair<std::string, ParamValue>> values;
  values.reserve(type.params.size());
  for (const auto& p : type.params) values.emplace_back(p.name, p.default_value);
  std::vector<bool> seen(type.params.size(), false);
  for (const auto& a : given) {
    std::size_t k = 0;
    while (k < type.params.size() && type.params[k].name != a.name) ++k;
    const std::string where = "column " + std::to_string(a.column) + ": ";
    if (k == type.params.size()) {
      std::vector<std::string_view> names;
      for (const auto& p : type.params) names.push_back(p.name);
      std::string msg = where + "task type '" + type.name + "' has no parameter '" + a.name + "'";
      if (auto hint = closest_name(a.name, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
      return Error{msg};
    }
    if (seen[k]) return Error{where + "parameter '" + a.name + "' given twice"};
    seen[k] = true;
    auto v = parse_param_value(type.params[k], a.value);
    if (!v) return Error{where + v.error()};
    values[k].second = std::move(v).value();
  }
  return ParamSet(std::move(values));
}

}  // namespace symb::os
