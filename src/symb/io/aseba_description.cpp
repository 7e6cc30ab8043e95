#include "symb/io/aseba_description.hpp"

#include <algorithm>

namespace symb::io::aseba {

const NamedVariable* NodeDescription::find(std::string_view variable) const {
  for (const NamedVariable& v : variables)
    if (v.name == variable) return &v;
  return nullptr;
}

bool DescriptionBuilder::take(const Message& m) {
  if (m.source != d_.node) return false;
  if (m.type != type::kDescription && m.type != type::kNamedVariableDescription) return false;
  if (!error_.empty()) return true;
  AsebaReader r(m.payload);
  if (m.type == type::kDescription) {
    if (have_header_) {
      return fail("a second description message");
    }
    auto name = r.string();
    if (!name) return fail("description: " + name.error());
    std::uint16_t fields[7];
    for (auto& f : fields) {
      auto w = r.word();
      if (!w) return fail("description: " + w.error());
      f = *w;
    }
    d_.name = std::move(name).value();
    d_.protocol_version = fields[0];
    d_.bytecode_size = fields[1];
    d_.stack_size = fields[2];
    d_.variables_size = fields[3];
    expected_ = fields[4];
    d_.local_events = fields[5];
    d_.native_functions = fields[6];
    have_header_ = true;
    if (d_.name.empty()) fail("description: the node has no name");
    if (d_.variables_size > kMaxVariableWords)
      fail("description: " + std::to_string(d_.variables_size) + " words of variables is more than " +
           std::to_string(kMaxVariableWords));
    if (expected_ > kMaxNamedVariables)
      fail("description: " + std::to_string(expected_) + " named variables is more than " +
           std::to_string(kMaxNamedVariables));
    if (expected_ > d_.variables_size)
      fail("description: " + std::to_string(expected_) + " named variables in " + std::to_string(d_.variables_size) +
           " words");
    return true;
  }
  // A named variable.
  const std::size_t index = d_.variables.size();
  if (!have_header_) return fail("variable description before the node's description");
  if (index >= expected_) return fail("more named variables than the " + std::to_string(expected_) + " announced");
  auto size = r.word();
  if (!size) return fail("variable " + std::to_string(index) + ": " + size.error());
  auto name = r.string();
  if (!name) return fail("variable " + std::to_string(index) + ": " + name.error());
  if (name->empty()) return fail("variable " + std::to_string(index) + " has no name");
  if (*size == 0) return fail("variable '" + *name + "' has size 0");
  if (next_address_ + *size > d_.variables_size)
    return fail("variable '" + *name + "' (" + std::to_string(*size) + " words at " + std::to_string(next_address_) +
                ") ends past the node's " + std::to_string(d_.variables_size) + " words");
  if (d_.find(*name) != nullptr) return fail("variable '" + *name + "' described twice");
  d_.variables.push_back({std::move(name).value(), static_cast<std::uint16_t>(next_address_), *size});
  next_address_ += *size;
  return true;
}

}  // namespace symb::io::aseba
