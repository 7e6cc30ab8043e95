#include "symb/control/mdl2e/bytecode.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace symb::control::mdl2e {
namespace {

constexpr std::array<PrimitiveInfo, 5> kPrimitives{{
    {Primitive::kStop, "stop", 0, "both wheels 0"},
    {Primitive::kForward, "forward", 1, "forward(speed): both wheels at speed"},
    {Primitive::kBackward, "backward", 1, "backward(speed): both wheels at -speed"},
    {Primitive::kTurn, "turn", 1, "turn(rate): left wheel -rate, right wheel +rate (positive turns left)"},
    {Primitive::kWheels, "wheels", 2, "wheels(left, right): each wheel's speed"},
}};

kernel::Status fail(const std::string& m) { return kernel::Error{"bytecode: " + m}; }

// Checks the RPN string at `offset`: known opcodes, no underflow, one value left at kEnd.
kernel::Status verify_expr(const Program& p, std::size_t offset) {
  int depth = 0;
  std::size_t i = offset;
  for (;;) {
    if (i >= p.code.size()) return fail("expression at " + std::to_string(offset) + " runs past the code");
    const auto op = static_cast<ExprOp>(p.code[i++]);
    switch (op) {
      case ExprOp::kEnd:
        if (depth != 1)
          return fail("expression at " + std::to_string(offset) + " leaves " + std::to_string(depth) + " values");
        return {};
      case ExprOp::kBasic:
        if (i >= p.code.size()) return fail("expression at " + std::to_string(offset) + " runs past the code");
        if (p.code[i++] >= p.interrupts.size())
          return fail("expression at " + std::to_string(offset) + " names an unknown basic interrupt");
        ++depth;
        break;
      case ExprOp::kTrue:
      case ExprOp::kFalse: ++depth; break;
      case ExprOp::kNot:
        if (depth < 1) return fail("expression at " + std::to_string(offset) + " underflows");
        break;
      case ExprOp::kAnd:
      case ExprOp::kOr:
        if (depth < 2) return fail("expression at " + std::to_string(offset) + " underflows");
        --depth;
        break;
      default: return fail("expression at " + std::to_string(offset) + " has a bad opcode");
    }
    if (depth > kMaxExprStack) return fail("expression at " + std::to_string(offset) + " needs too deep a stack");
  }
}

class Writer {
 public:
  void u8(std::uint8_t v) { b.push_back(v); }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v & 0xff));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    u16(static_cast<std::uint16_t>(v & 0xffff));
    u16(static_cast<std::uint16_t>(v >> 16));
  }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  std::vector<std::uint8_t> b;
};

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  bool u8(std::uint8_t& v) {
    if (pos_ >= b_.size()) return false;
    v = b_[pos_++];
    return true;
  }
  bool u16(std::uint16_t& v) {
    std::uint8_t lo = 0, hi = 0;
    if (!u8(lo) || !u8(hi)) return false;
    v = static_cast<std::uint16_t>(lo | (hi << 8));
    return true;
  }
  bool u32(std::uint32_t& v) {
    std::uint16_t lo = 0, hi = 0;
    if (!u16(lo) || !u16(hi)) return false;
    v = static_cast<std::uint32_t>(lo) | (static_cast<std::uint32_t>(hi) << 16);
    return true;
  }
  bool f32(float& v) {
    std::uint32_t u = 0;
    if (!u32(u)) return false;
    v = std::bit_cast<float>(u);
    return true;
  }
  std::size_t pos() const { return pos_; }
  std::size_t left() const { return b_.size() - pos_; }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t pos_ = 0;
};

std::string fmt_float(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
  return buf;
}

}  // namespace

std::span<const PrimitiveInfo> primitives() { return kPrimitives; }

void primitive_wheels(Primitive p, std::span<const float> args, double& left, double& right) {
  const double a = args.size() > 0 ? static_cast<double>(args[0]) : 0.0;
  const double b = args.size() > 1 ? static_cast<double>(args[1]) : 0.0;
  switch (p) {
    case Primitive::kStop: left = right = 0; return;
    case Primitive::kForward: left = right = a; return;
    case Primitive::kBackward: left = right = -a; return;
    case Primitive::kTurn:
      left = -a;
      right = a;
      return;
    case Primitive::kWheels:
      left = a;
      right = b;
      return;
  }
  left = right = 0;
}

std::string_view task_action_name(TaskAction a) {
  switch (a) {
    case TaskAction::kStart: return "start";
    case TaskAction::kSuspend: return "suspend";
    case TaskAction::kResume: return "resume";
    case TaskAction::kDelete: return "delete";
  }
  return "?";
}

kernel::Status verify(const Program& p) {
  if (p.strings.size() >= kNoIndex) return fail("too many strings");
  for (const auto& s : p.strings)
    if (s.size() > 255) return fail("a string is longer than 255 bytes");
  if (p.nodes.empty() || p.nodes.size() >= kNoIndex) return fail("node count out of range");
  if (p.code.size() >= kNoIndex || p.params.size() >= kNoIndex) return fail("pool too large");
  if (p.interrupts.size() > static_cast<std::size_t>(kMaxInterrupts)) return fail("too many basic interrupts");
  for (std::size_t i = 0; i < p.channels.size(); ++i) {
    const Channel& c = p.channels[i];
    if (c.name >= p.strings.size() || c.size == 0 || c.offset + c.size > p.sensor_count)
      return fail("channel " + std::to_string(i) + " is out of range");
  }
  for (std::size_t i = 0; i < p.interrupts.size(); ++i) {
    const BasicInterrupt& b = p.interrupts[i];
    if (b.name >= p.strings.size() || static_cast<std::uint8_t>(b.cmp) > 3 || b.external > 1 ||
        (b.external ? b.slot >= 64 : b.slot >= p.sensor_count) || !std::isfinite(b.threshold))
      return fail("basic interrupt " + std::to_string(i) + " is out of range");
  }
  const std::size_t n = p.nodes.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Node& d = p.nodes[i];
    const std::string at = "node " + std::to_string(i);
    if (d.name >= p.strings.size()) return fail(at + " has a bad name");
    if (d.expr != kNoIndex) {
      if (auto s = verify_expr(p, d.expr); !s) return s;
    }
    if (static_cast<std::size_t>(d.param_offset) + d.param_count > p.params.size()) return fail(at + " has bad params");
    if ((d.flags & ~kFlagLoop) != 0 || (!(d.flags & kFlagLoop) && d.loop_count != 0))
      return fail(at + " has bad flags");
    if (d.first_child != kNoIndex && d.first_child >= n) return fail(at + " has a bad child");
    if (d.next_sibling != kNoIndex && d.next_sibling >= n) return fail(at + " has a bad sibling");
    switch (d.op) {
      case Op::kAtom:
        if (d.arg >= kPrimitives.size() || d.param_count != kPrimitives[d.arg].arity)
          return fail(at + " has a bad primitive or arity");
        if (d.first_child != kNoIndex || d.flags != 0) return fail(at + ": an atom has no children and no loop");
        for (std::size_t k = 0; k < d.param_count; ++k)
          if (!std::isfinite(p.params[d.param_offset + k])) return fail(at + " has a non-finite argument");
        break;
      case Op::kBehaviour:
        if (d.first_child == kNoIndex) return fail(at + ": a behaviour needs children");
        if (d.param_count != 0 || d.arg != 0) return fail(at + ": a behaviour takes no arguments");
        break;
      case Op::kTask:
        if (d.arg > 3 || d.first_child != kNoIndex || d.flags != 0 || d.param_count != 0 || d.expr != kNoIndex ||
            d.duration_ms != 0)
          return fail(at + " is a bad task action");
        break;
      case Op::kDevice:
        if (d.arg >= p.strings.size() || d.param_count > 1 || d.first_child != kNoIndex || d.flags != 0 ||
            d.expr != kNoIndex || d.duration_ms != 0)
          return fail(at + " is a bad device action");
        if (d.param_count == 1 && !std::isfinite(p.params[d.param_offset]))
          return fail(at + " has a non-finite argument");
        break;
      default: return fail(at + " has a bad opcode");
    }
  }
  if (p.root >= n || p.nodes[p.root].op != Op::kBehaviour || p.nodes[p.root].parent != kNoIndex ||
      p.nodes[p.root].next_sibling != kNoIndex)
    return fail("bad root");
  // Walk the tree: every node exactly once, parents consistent, depth bounded.
  std::vector<std::uint8_t> seen(n, 0);
  struct Item {
    std::uint16_t node;
    int depth;
  };
  std::vector<Item> stack{{p.root, 1}};
  seen[p.root] = 1;
  std::size_t visited = 1;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    if (it.depth > kMaxDepth) return fail("tree deeper than " + std::to_string(kMaxDepth));
    for (std::uint16_t c = p.nodes[it.node].first_child; c != kNoIndex; c = p.nodes[c].next_sibling) {
      if (seen[c]) return fail("node " + std::to_string(c) + " is reached twice");
      if (p.nodes[c].parent != it.node) return fail("node " + std::to_string(c) + " has a wrong parent");
      seen[c] = 1;
      ++visited;
      stack.push_back({c, it.depth + 1});
    }
  }
  if (visited != n) return fail("unreachable nodes");
  return {};
}

std::vector<std::uint8_t> encode(const Program& p) {
  Writer w;
  for (char c : std::string_view("MDL2")) w.u8(static_cast<std::uint8_t>(c));
  w.u8(kBytecodeVersion);
  w.u8(0);
  w.u16(p.root);
  w.u16(p.sensor_count);
  w.u16(static_cast<std::uint16_t>(p.nodes.size()));
  w.u16(static_cast<std::uint16_t>(p.code.size()));
  w.u16(static_cast<std::uint16_t>(p.params.size()));
  w.u16(static_cast<std::uint16_t>(p.interrupts.size()));
  w.u16(static_cast<std::uint16_t>(p.channels.size()));
  w.u16(static_cast<std::uint16_t>(p.strings.size()));
  for (const Node& d : p.nodes) {
    w.u8(static_cast<std::uint8_t>(d.op));
    w.u8(d.flags);
    w.u16(d.name);
    w.u16(d.arg);
    w.u16(d.expr);
    w.u32(d.duration_ms);
    w.u16(d.first_child);
    w.u16(d.next_sibling);
    w.u16(d.parent);
    w.u16(d.loop_count);
    w.u16(d.param_offset);
    w.u8(d.param_count);
  }
  for (auto b : p.code) w.u8(b);
  for (float f : p.params) w.f32(f);
  for (const auto& b : p.interrupts) {
    w.u16(b.name);
    w.u8(b.external);
    w.u8(static_cast<std::uint8_t>(b.cmp));
    w.u16(b.slot);
    w.f32(b.threshold);
  }
  for (const auto& c : p.channels) {
    w.u16(c.name);
    w.u16(c.offset);
    w.u16(c.size);
  }
  for (const auto& s : p.strings) {
    w.u8(static_cast<std::uint8_t>(s.size()));
    for (char c : s) w.u8(static_cast<std::uint8_t>(c));
  }
  return std::move(w.b);
}

kernel::Result<Program> decode(std::span<const std::uint8_t> bytes) {
  Reader r(bytes);
  auto truncated = [&] { return kernel::Error{"bytecode: truncated at byte " + std::to_string(r.pos())}; };
  if (bytes.size() < 4 || std::memcmp(bytes.data(), "MDL2", 4) != 0)
    return kernel::Error{"bytecode: byte 0: not MDL2e byte code (magic 'MDL2' missing)"};
  std::uint8_t skip = 0;
  for (int i = 0; i < 4; ++i) (void)r.u8(skip);
  std::uint8_t version = 0, reserved = 0;
  if (!r.u8(version) || !r.u8(reserved)) return truncated();
  if (version != kBytecodeVersion)
    return kernel::Error{"bytecode: byte 4: version " + std::to_string(version) + " is not supported"};
  Program p;
  std::uint16_t nn = 0, nc = 0, np = 0, ni = 0, nch = 0, ns = 0;
  if (!r.u16(p.root) || !r.u16(p.sensor_count) || !r.u16(nn) || !r.u16(nc) || !r.u16(np) || !r.u16(ni) || !r.u16(nch) ||
      !r.u16(ns))
    return truncated();
  // Size check before allocating, so a hostile header cannot ask for a lot of memory.
  const std::size_t need =
      std::size_t{nn} * 23 + nc + std::size_t{np} * 4 + std::size_t{ni} * 10 + std::size_t{nch} * 6 + ns;
  if (need > r.left())
    return kernel::Error{"bytecode: counts in the header need " + std::to_string(need) + " bytes but " +
                         std::to_string(r.left()) + " follow"};
  p.nodes.resize(nn);
  for (Node& d : p.nodes) {
    std::uint8_t op = 0;
    if (!r.u8(op) || !r.u8(d.flags) || !r.u16(d.name) || !r.u16(d.arg) || !r.u16(d.expr) || !r.u32(d.duration_ms) ||
        !r.u16(d.first_child) || !r.u16(d.next_sibling) || !r.u16(d.parent) || !r.u16(d.loop_count) ||
        !r.u16(d.param_offset) || !r.u8(d.param_count))
      return truncated();
    d.op = static_cast<Op>(op);
  }
  p.code.resize(nc);
  for (auto& b : p.code)
    if (!r.u8(b)) return truncated();
  p.params.resize(np);
  for (auto& f : p.params)
    if (!r.f32(f)) return truncated();
  p.interrupts.resize(ni);
  for (auto& b : p.interrupts) {
    std::uint8_t cmp = 0;
    if (!r.u16(b.name) || !r.u8(b.external) || !r.u8(cmp) || !r.u16(b.slot) || !r.f32(b.threshold)) return truncated();
    b.cmp = static_cast<Cmp>(cmp);
  }
  p.channels.resize(nch);
  for (auto& c : p.channels)
    if (!r.u16(c.name) || !r.u16(c.offset) || !r.u16(c.size)) return truncated();
  p.strings.resize(ns);
  for (auto& s : p.strings) {
    std::uint8_t len = 0;
    if (!r.u8(len)) return truncated();
    if (len > r.left()) return truncated();
    for (int k = 0; k < len; ++k) {
      std::uint8_t c = 0;
      (void)r.u8(c);
      s.push_back(static_cast<char>(c));
    }
  }
  if (r.left() != 0) return kernel::Error{"bytecode: byte " + std::to_string(r.pos()) + ": trailing bytes"};
  if (auto s = verify(p); !s) return kernel::Error{s.error()};
  return p;
}

namespace {

std::string expr_text(const Program& p, std::size_t offset) {
  std::string out;
  for (std::size_t i = offset; i < p.code.size();) {
    const auto op = static_cast<ExprOp>(p.code[i++]);
    if (op == ExprOp::kEnd) break;
    if (!out.empty()) out += ' ';
    switch (op) {
      case ExprOp::kBasic: {
        const std::uint8_t k = i < p.code.size() ? p.code[i++] : 0;
        out += k < p.interrupts.size() ? std::string(p.string(p.interrupts[k].name)) : "?";
        break;
      }
      case ExprOp::kTrue: out += "TRUE"; break;
      case ExprOp::kFalse: out += "FALSE"; break;
      case ExprOp::kNot: out += "NOT"; break;
      case ExprOp::kAnd: out += "AND"; break;
      case ExprOp::kOr: out += "OR"; break;
      default: out += "?"; break;
    }
  }
  return out;
}

void dis_node(const Program& p, std::uint16_t id, int depth, std::string& out) {
  if (depth > kMaxDepth + 1) return;
  const Node& d = p.nodes[id];
  out += std::string(static_cast<std::size_t>(depth) * 2, ' ');
  out += std::to_string(id) + ": ";
  switch (d.op) {
    case Op::kAtom: {
      out += "ATOM " + std::string(p.string(d.name));
      out += '(';
      for (std::size_t k = 0; k < d.param_count; ++k) {
        if (k) out += ", ";
        out += fmt_float(p.params[d.param_offset + k]);
      }
      out += ')';
      break;
    }
    case Op::kBehaviour: out += (id == p.root ? "PLAN " : "BEHAVIOUR ") + std::string(p.string(d.name)); break;
    case Op::kTask:
      out +=
          "TASK " + std::string(task_action_name(static_cast<TaskAction>(d.arg))) + " " + std::string(p.string(d.name));
      break;
    case Op::kDevice:
      out += "DEVICE " + std::string(p.string(d.name)) + " " + std::string(p.string(d.arg));
      if (d.param_count == 1) out += " " + fmt_float(p.params[d.param_offset]);
      break;
  }
  if (d.duration_ms) out += " duration=" + std::to_string(d.duration_ms) + "ms";
  if (d.expr != kNoIndex) out += " interrupt=[" + expr_text(p, d.expr) + "]@" + std::to_string(d.expr);
  if (d.flags & kFlagLoop) out += d.loop_count ? " loop=" + std::to_string(d.loop_count) : std::string(" loop");
  out += '\n';
  for (std::uint16_t c = d.first_child; c != kNoIndex && c < p.nodes.size(); c = p.nodes[c].next_sibling)
    dis_node(p, c, depth + 1, out);
}

}  // namespace

std::string disassemble(const Program& p) {
  std::string out = "MDL2e byte code v" + std::to_string(kBytecodeVersion) + ": " + std::to_string(p.nodes.size()) +
                    " nodes, " + std::to_string(p.code.size()) + " code bytes, " + std::to_string(p.params.size()) +
                    " params, " + std::to_string(encode(p).size()) + " bytes encoded\n";
  for (const auto& c : p.channels)
    out += "SENSOR " + std::string(p.string(c.name)) + "[" + std::to_string(c.size) + "] slots " +
           std::to_string(c.offset) + ".." + std::to_string(c.offset + c.size - 1) + "\n";
  static constexpr std::string_view kCmp[] = {"<", ">", "<=", ">="};
  for (std::size_t i = 0; i < p.interrupts.size(); ++i) {
    const auto& b = p.interrupts[i];
    out += "INTERRUPT " + std::to_string(i) + " " + std::string(p.string(b.name)) + " = ";
    if (b.external)
      out += "external bit " + std::to_string(b.slot);
    else
      out += "sensor[" + std::to_string(b.slot) + "] " + std::string(kCmp[static_cast<std::size_t>(b.cmp) & 3]) + " " +
             fmt_float(b.threshold);
    out += '\n';
  }
  if (p.root < p.nodes.size()) dis_node(p, p.root, 0, out);
  return out;
}

}  // namespace symb::control::mdl2e
