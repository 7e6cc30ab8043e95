// An Aseba node's description: what a node says about itself when the host asks (get node
// description). It answers with one description message (its name, protocol version, the sizes
// of its bytecode, stack and variable memory, and how many named variables, local events and
// native functions follow), then one message per named variable (size in words, name), then
// the local events and native functions. A named variable's address is not sent: it is the sum of
// the sizes of the variables described before it, so the order of arrival is the memory layout.
//
// DescriptionBuilder assembles one node's answer and checks it as it comes: sizes and counts are
// bounded (kMaxNamedVariables, the declared variable memory), names are non-empty and distinct,
// and every variable ends inside the memory the node declared. A message that breaks a rule
// fails the description with the reason, so a hostile or broken node cannot make the host
// address memory the node does not have.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/aseba_message.hpp"
#include "symb/kernel/result.hpp"

namespace symb::io::aseba {

// Bounds on what a description may declare (a Thymio II: 30 named variables in 586 words).
inline constexpr std::size_t kMaxNamedVariables = 1024;
inline constexpr std::size_t kMaxVariableWords = 32768;

struct NamedVariable {
  std::string name;
  std::uint16_t address = 0;
  std::uint16_t size = 0;  // words
};

struct NodeDescription {
  std::uint16_t node = 0;
  std::string name;  // "thymio-II"
  std::uint16_t protocol_version = 0;
  std::uint16_t bytecode_size = 0;
  std::uint16_t stack_size = 0;
  std::uint16_t variables_size = 0;  // words of variable memory
  std::uint16_t local_events = 0;
  std::uint16_t native_functions = 0;
  std::vector<NamedVariable> variables;  // in address order

  const NamedVariable* find(std::string_view variable) const;
  // Whether [start, start + count) lies in the node's variable memory.
  bool holds(std::uint32_t start, std::uint32_t count) const { return start + count <= variables_size; }
};

class DescriptionBuilder {
 public:
  explicit DescriptionBuilder(std::uint16_t node) { d_.node = node; }
  // Feeds a message from the node (other types and other sources are ignored: false). Returns
  // true when the message was part of the description. After an error, error() says why and
  // nothing more is taken.
  bool take(const Message& m);
  // Every named variable announced has arrived.
  bool complete() const { return have_header_ && error_.empty() && d_.variables.size() == expected_; }
  const std::string& error() const { return error_; }
  const NodeDescription& description() const { return d_; }

 private:
  // Records the first error; true, as the message was the description's.
  bool fail(std::string why) {
    if (error_.empty()) error_ = std::move(why);
    return true;
  }
  NodeDescription d_;
  std::size_t expected_ = 0;
  std::uint32_t next_address_ = 0;
  bool have_header_ = false;
  std::string error_;
};

}  // namespace symb::io::aseba
