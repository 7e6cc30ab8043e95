// The compiled MDL2e program: a flat, immutable table the interpreter walks without allocating.
// Nodes (atoms, behaviours, task actions) form a tree through first-child / next-sibling indices;
// interrupt conditions are RPN byte strings in one code pool; atom arguments are floats in one
// pool; names live in a string table. encode()/decode() turn it into the compact little-endian byte
// form (the JaMOS idea: byte code for a small controller), verify() checks every index and every
// RPN string so the interpreter can trust what it is given. Layout: docs/mdl2e.md.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::control::mdl2e {

inline constexpr std::uint16_t kNoIndex = 0xFFFF;
// Deepest chain of active components (plan, behaviours, atom) the interpreter tracks.
inline constexpr int kMaxDepth = 16;
// Largest operand stack an interrupt expression may need.
inline constexpr int kMaxExprStack = 16;
// Most basic interrupts a program may define (one bit each).
inline constexpr int kMaxInterrupts = 64;
inline constexpr std::uint8_t kBytecodeVersion = 1;

enum class Op : std::uint8_t { kAtom = 1, kBehaviour = 2, kTask = 3, kDevice = 4 };
// Task and device actions happen in an instant: entered, carried out, left.
constexpr bool is_action(Op op) { return op == Op::kTask || op == Op::kDevice; }
enum class TaskAction : std::uint8_t { kStart = 0, kSuspend = 1, kResume = 2, kDelete = 3 };
enum class Cmp : std::uint8_t { kLt = 0, kGt = 1, kLe = 2, kGe = 3 };
// One RPN instruction byte; kBasic is followed by one byte, the basic interrupt's index.
enum class ExprOp : std::uint8_t { kEnd = 0, kBasic = 1, kTrue = 2, kFalse = 3, kNot = 4, kAnd = 5, kOr = 6 };

// The primitive behaviours an atom can run, and how each maps to wheel speeds (left, right).
enum class Primitive : std::uint8_t { kStop = 0, kForward = 1, kBackward = 2, kTurn = 3, kWheels = 4 };
struct PrimitiveInfo {
  Primitive id;
  std::string_view name;
  std::uint8_t arity;
  std::string_view help;
};
// The table of primitives: stop; forward(speed); backward(speed); turn(rate) (positive turns left:
// left wheel -rate, right +rate); wheels(left, right).
std::span<const PrimitiveInfo> primitives();
// Wheel speeds for a primitive with its arguments (missing arguments read as 0).
void primitive_wheels(Primitive p, std::span<const float> args, double& left, double& right);
std::string_view task_action_name(TaskAction a);

struct Node {
  Op op = Op::kAtom;
  std::uint8_t flags = 0;  // kFlagLoop
  // string id: behaviour label, primitive name, (kTask) the task's name or (kDevice) the device's
  std::uint16_t name = 0;
  std::uint16_t arg = 0;          // kAtom: Primitive; kTask: TaskAction; kDevice: the command's string id
  std::uint16_t expr = kNoIndex;  // offset of the interrupt's RPN in Program::code, or none
  std::uint32_t duration_ms = 0;  // 0: no timer
  std::uint16_t first_child = kNoIndex;
  std::uint16_t next_sibling = kNoIndex;
  std::uint16_t parent = kNoIndex;
  std::uint16_t loop_count = 0;  // with kFlagLoop: 0 forever, else how many passes over the body
  std::uint16_t param_offset = 0;
  std::uint8_t param_count = 0;
  friend bool operator==(const Node&, const Node&) = default;
};
inline constexpr std::uint8_t kFlagLoop = 1;

// A basic interrupt: sensor slot `slot` compared with `threshold`, or external input bit `slot`.
struct BasicInterrupt {
  std::uint16_t name = 0;
  std::uint8_t external = 0;
  Cmp cmp = Cmp::kGt;
  std::uint16_t slot = 0;
  float threshold = 0;
  friend bool operator==(const BasicInterrupt&, const BasicInterrupt&) = default;
};

// A sensor channel: values [offset, offset + size) of the flat sensor vector.
struct Channel {
  std::uint16_t name = 0;
  std::uint16_t offset = 0;
  std::uint16_t size = 0;
  friend bool operator==(const Channel&, const Channel&) = default;
};

struct Program {
  std::vector<Node> nodes;  // nodes[root] is the plan
  std::vector<std::uint8_t> code;
  std::vector<float> params;
  std::vector<BasicInterrupt> interrupts;
  std::vector<Channel> channels;
  std::vector<std::string> strings;
  std::uint16_t root = 0;
  std::uint16_t sensor_count = 0;  // length of the flat sensor vector

  std::string_view string(std::uint16_t id) const {
    return id < strings.size() ? std::string_view(strings[id]) : std::string_view();
  }
  friend bool operator==(const Program&, const Program&) = default;
};

// Checks every index, the tree shape (each node reached once from the root, parents consistent,
// depth <= kMaxDepth), each RPN string (balanced, stack <= kMaxExprStack, known basic interrupts)
// and each atom's arity. The interpreter relies on a verified program.
kernel::Status verify(const Program& program);
// The compact byte form (magic "MDL2", version, counts, sections; little-endian).
std::vector<std::uint8_t> encode(const Program& program);
// Reads the byte form back and verifies it; errors name the byte offset.
kernel::Result<Program> decode(std::span<const std::uint8_t> bytes);
// A readable listing: channels, interrupts, then the node tree (interrupts shown as RPN).
// `program` must be verified.
std::string disassemble(const Program& program);

}  // namespace symb::control::mdl2e
