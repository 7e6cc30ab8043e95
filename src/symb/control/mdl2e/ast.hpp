// The MDL2e abstract syntax tree: what the parser reads from program text, before any names are
// resolved. Every node keeps the line and column it came from, so the compiler's errors (unknown
// interrupt, wrong number of arguments, recursion) point at the right place in the source.
// Plain data; the compiler turns it into the compact byte code of bytecode.hpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "symb/kernel/source_text.hpp"

namespace symb::control::mdl2e::ast {

// A position in the source: both 1-based.
using Loc = kernel::TextLocation;

// An interrupt expression over named basic interrupts: AND, OR, NOT, TRUE, FALSE, parentheses.
struct Expr {
  enum class Kind : std::uint8_t { kRef, kTrue, kFalse, kNot, kAnd, kOr };
  Kind kind = Kind::kTrue;
  std::string name;            // kRef: the basic interrupt's name
  Loc loc;                     // where the (first) operator or name starts
  std::vector<Expr> operands;  // kNot: 1; kAnd, kOr: 2 or more, a chain's terms in order
};

// `until EXPR`, `for DURATION`, `loop [N]` after an atom, behaviour, call or plan.
struct Modifiers {
  std::optional<Expr> until;
  std::optional<std::uint32_t> duration_ms;  // as written; 0 is rejected by the parser
  Loc duration_loc;
  bool loop = false;
  std::uint32_t loop_count = 0;  // 0: forever
  Loc loop_loc;
};

enum class TaskOp : std::uint8_t { kStart, kSuspend, kResume, kDelete };
enum class CmpOp : std::uint8_t { kLt, kGt, kLe, kGe };

// One entry in a behaviour's or plan's body.
struct Item {
  enum class Kind : std::uint8_t { kAtom, kBehaviour, kCall, kTask, kDevice };
  Kind kind = Kind::kAtom;
  Loc loc;
  // kAtom: primitive; kBehaviour: label (may be empty); kCall: behaviour; kTask: task; kDevice: device
  std::string name;
  Loc name_loc;
  std::vector<double> args;  // kAtom: primitive arguments; kDevice: the command's argument, if any
  std::string command;       // kDevice: the ioctl command
  Loc command_loc;
  Loc args_loc;
  TaskOp task_op = TaskOp::kStart;
  Modifiers mods;
  std::vector<Item> children;  // kBehaviour: its body
};

// `sensor ir[7]`: a channel of 7 values in the interpreter's flat sensor vector.
struct SensorDecl {
  std::string name;
  Loc loc;
  std::uint32_t size = 0;
};

// `interrupt obstacle_left = ir[0] > 2000` or `interrupt bumped = external`.
struct InterruptDecl {
  std::string name;
  Loc loc;
  bool external = false;
  std::string channel;
  Loc channel_loc;
  std::uint32_t index = 0;
  Loc index_loc;
  CmpOp op = CmpOp::kGt;
  double threshold = 0.0;
};

// A named behaviour (`behaviour NAME ... { ... }`) or the plan (`plan NAME ... { ... }`).
struct BehaviourDecl {
  std::string name;
  Loc loc;
  Modifiers mods;
  std::vector<Item> children;
};

struct Program {
  std::vector<SensorDecl> sensors;
  std::vector<InterruptDecl> interrupts;
  std::vector<BehaviourDecl> behaviours;
  std::optional<BehaviourDecl> plan;
  Loc end;  // the end of the text
};

}  // namespace symb::control::mdl2e::ast
