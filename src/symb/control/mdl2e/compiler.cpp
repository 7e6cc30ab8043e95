#include "symb/control/mdl2e/compiler.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "symb/control/mdl2e/parser.hpp"
#include "symb/os/param.hpp"

namespace symb::control::mdl2e {
namespace {

std::string at(ast::Loc loc) { return kernel::location_prefix(loc); }

std::string hint(std::string_view name, const std::vector<std::string_view>& candidates) {
  const std::string c = os::closest_name(name, candidates);
  return c.empty() ? std::string() : " (did you mean '" + c + "'?)";
}

class Compiler {
 public:
  explicit Compiler(const ast::Program& a) : a_(a) {}

  kernel::Result<Program> run() {
    // Sensor channels, in declaration order, packed into one flat vector.
    for (const auto& s : a_.sensors) {
      if (find_channel(s.name) >= 0) return kernel::Error{at(s.loc) + "sensor '" + s.name + "' is declared twice"};
      if (p_.sensor_count + s.size > 4096) return kernel::Error{at(s.loc) + "more than 4096 sensor values in all"};
      p_.channels.push_back({intern(s.name), p_.sensor_count, static_cast<std::uint16_t>(s.size)});
      p_.sensor_count = static_cast<std::uint16_t>(p_.sensor_count + s.size);
    }
    std::uint16_t external_bits = 0;
    for (const auto& d : a_.interrupts) {
      if (find_interrupt(d.name) >= 0) return kernel::Error{at(d.loc) + "interrupt '" + d.name + "' is defined twice"};
      if (p_.interrupts.size() >= static_cast<std::size_t>(kMaxInterrupts))
        return kernel::Error{at(d.loc) + "more than " + std::to_string(kMaxInterrupts) + " basic interrupts"};
      BasicInterrupt b;
      b.name = intern(d.name);
      if (d.external) {
        b.external = 1;
        b.slot = external_bits++;
      } else {
        const int ch = find_channel(d.channel);
        if (ch < 0) {
          std::vector<std::string_view> names;
          for (const auto& s : a_.sensors) names.push_back(s.name);
          return kernel::Error{at(d.channel_loc) + "unknown sensor channel '" + d.channel + "'" +
                               hint(d.channel, names) +
                               (names.empty() ? " (declare it first: sensor " + d.channel + "[N])" : "")};
        }
        const Channel& c = p_.channels[static_cast<std::size_t>(ch)];
        if (d.index >= c.size)
          return kernel::Error{at(d.index_loc) + "index " + std::to_string(d.index) + " is out of range for " +
                               d.channel + "[" + std::to_string(c.size) + "]"};
        b.slot = static_cast<std::uint16_t>(c.offset + d.index);
        b.cmp = static_cast<Cmp>(d.op);
        b.threshold = static_cast<float>(d.threshold);
      }
      p_.interrupts.push_back(b);
    }
    for (std::size_t i = 0; i < a_.behaviours.size(); ++i) {
      const auto& b = a_.behaviours[i];
      for (std::size_t j = 0; j < i; ++j)
        if (a_.behaviours[j].name == b.name)
          return kernel::Error{at(b.loc) + "behaviour '" + b.name + "' is defined twice (first at line " +
                               std::to_string(a_.behaviours[j].loc.line) + ")"};
      if (b.name == a_.plan->name)
        return kernel::Error{at(b.loc) + "behaviour '" + b.name + "' has the same name as the plan"};
    }
    // Check every behaviour definition, used or not, by expanding it once into a scratch table.
    for (const auto& b : a_.behaviours) {
      Compiler scratch(a_);
      scratch.p_.interrupts = p_.interrupts;
      scratch.p_.strings = p_.strings;
      scratch.stack_.push_back(&b);
      std::uint16_t id = 0;
      if (auto s = scratch.behaviour(b.name, b.mods, b.children, b.loc, 1, id); !s) return kernel::Error{s.error()};
    }
    std::uint16_t root = 0;
    if (auto s = behaviour(a_.plan->name, a_.plan->mods, a_.plan->children, a_.plan->loc, 1, root); !s)
      return kernel::Error{s.error()};
    p_.root = root;
    if (auto s = verify(p_); !s) return kernel::Error{at(a_.plan->loc) + "internal error: " + s.error()};
    return std::move(p_);
  }

 private:
  int find_channel(std::string_view name) const {
    for (std::size_t i = 0; i < p_.channels.size(); ++i)
      if (p_.string(p_.channels[i].name) == name) return static_cast<int>(i);
    return -1;
  }
  int find_interrupt(std::string_view name) const {
    for (std::size_t i = 0; i < p_.interrupts.size(); ++i)
      if (p_.string(p_.interrupts[i].name) == name) return static_cast<int>(i);
    return -1;
  }
  std::uint16_t intern(std::string_view s) {
    for (std::size_t i = 0; i < p_.strings.size(); ++i)
      if (p_.strings[i] == s) return static_cast<std::uint16_t>(i);
    p_.strings.emplace_back(s);
    return static_cast<std::uint16_t>(p_.strings.size() - 1);
  }

  kernel::Status new_node(ast::Loc loc, std::uint16_t& id) {
    if (p_.nodes.size() >= kMaxNodes)
      return kernel::Error{at(loc) + "the program expands to more than " + std::to_string(kMaxNodes) + " nodes"};
    id = static_cast<std::uint16_t>(p_.nodes.size());
    p_.nodes.emplace_back();
    return {};
  }

  // Emits the RPN for `root` with an explicit stack, so a chain of any length (one node with an
  // operand per term) or a hand-built tree of any depth uses no native stack. A chain's first
  // operand sits at the chain's own operand depth, each next one a slot higher until its operator
  // folds it in: an and/or chain needs two slots however long it is.
  kernel::Status expr(const ast::Expr& root) {
    using K = ast::Expr::Kind;
    struct Frame {
      const ast::Expr* e;
      int depth;  // operand stack slots in use below this subexpression's value
      std::size_t next = 0;
    };
    std::vector<Frame> stack{{&root, 0}};
    const auto emit = [&](ExprOp op, const ast::Expr& at_node) -> kernel::Status {
      p_.code.push_back(static_cast<std::uint8_t>(op));
      if (p_.code.size() >= 60000) return kernel::Error{at(at_node.loc) + "interrupt expressions are too large in all"};
      return {};
    };
    while (!stack.empty()) {
      Frame& f = stack.back();
      const ast::Expr& e = *f.e;
      if (e.kind == K::kRef || e.kind == K::kTrue || e.kind == K::kFalse) {
        if (f.depth + 1 > kMaxExprStack)
          return kernel::Error{at(e.loc) + "interrupt expression needs more than " + std::to_string(kMaxExprStack) +
                               " stack slots (use fewer nested parentheses)"};
        if (e.kind == K::kRef) {
          const int k = find_interrupt(e.name);
          if (k < 0) {
            std::vector<std::string_view> names;
            for (const auto& d : a_.interrupts) names.push_back(d.name);
            return kernel::Error{at(e.loc) + "unknown interrupt '" + e.name + "'" + hint(e.name, names)};
          }
          if (auto s = emit(ExprOp::kBasic, e); !s) return s;
          p_.code.push_back(static_cast<std::uint8_t>(k));
        } else if (auto s = emit(e.kind == K::kTrue ? ExprOp::kTrue : ExprOp::kFalse, e); !s) {
          return s;
        }
        stack.pop_back();
        continue;
      }
      const bool chain = e.kind == K::kAnd || e.kind == K::kOr;
      if ((chain && e.operands.size() < 2) || (!chain && e.operands.size() != 1))
        return kernel::Error{at(e.loc) + "internal error: bad interrupt expression"};
      if (chain && f.next >= 2)
        if (auto s = emit(e.kind == K::kAnd ? ExprOp::kAnd : ExprOp::kOr, e); !s) return s;
      if (f.next < e.operands.size()) {
        const std::size_t i = f.next++;
        const int depth = f.depth + (i == 0 ? 0 : 1);
        stack.push_back({&e.operands[i], depth});  // invalidates f
        continue;
      }
      if (e.kind == K::kNot)
        if (auto s = emit(ExprOp::kNot, e); !s) return s;
      stack.pop_back();
    }
    return {};
  }

  kernel::Status modifiers(const ast::Modifiers& m, Node& d) {
    if (m.duration_ms) d.duration_ms = *m.duration_ms;
    if (m.loop) {
      d.flags |= kFlagLoop;
      d.loop_count = static_cast<std::uint16_t>(m.loop_count);
    }
    if (m.until) {
      const std::size_t offset = p_.code.size();
      if (auto s = expr(*m.until); !s) return s;
      p_.code.push_back(static_cast<std::uint8_t>(ExprOp::kEnd));
      d.expr = static_cast<std::uint16_t>(offset);
    }
    return {};
  }

  // Does this subtree contain an atom (something that waits for time or an interrupt)?
  bool waits(std::uint16_t id) const {
    const Node& d = p_.nodes[id];
    if (d.op == Op::kAtom) return true;
    for (std::uint16_t c = d.first_child; c != kNoIndex; c = p_.nodes[c].next_sibling)
      if (waits(c)) return true;
    return false;
  }

  kernel::Status behaviour(const std::string& label, const ast::Modifiers& mods, const std::vector<ast::Item>& body,
                           ast::Loc loc, int depth, std::uint16_t& id) {
    if (depth > kMaxDepth)
      return kernel::Error{at(loc) + "nested deeper than " + std::to_string(kMaxDepth) + " levels"};
    if (auto s = new_node(loc, id); !s) return s;
    {
      Node d;
      d.op = Op::kBehaviour;
      d.name = intern(label);
      if (auto s = modifiers(mods, d); !s) return s;
      p_.nodes[id] = d;
    }
    std::uint16_t prev = kNoIndex;
    for (const auto& it : body) {
      std::uint16_t child = 0;
      if (auto s = item(it, depth + 1, child); !s) return s;
      p_.nodes[child].parent = id;
      if (prev == kNoIndex)
        p_.nodes[id].first_child = child;
      else
        p_.nodes[prev].next_sibling = child;
      prev = child;
    }
    if ((p_.nodes[id].flags & kFlagLoop) && p_.nodes[id].loop_count == 0 && !waits(id))
      return kernel::Error{at(mods.loop_loc) + "'" + label +
                           "' loops forever but contains no atom, so it would never wait"};
    return {};
  }

  kernel::Status item(const ast::Item& it, int depth, std::uint16_t& id) {
    using K = ast::Item::Kind;
    switch (it.kind) {
      case K::kAtom: {
        if (depth > kMaxDepth)
          return kernel::Error{at(it.loc) + "nested deeper than " + std::to_string(kMaxDepth) + " levels"};
        const PrimitiveInfo* info = nullptr;
        std::vector<std::string_view> names;
        for (const auto& pi : primitives()) {
          names.push_back(pi.name);
          if (pi.name == it.name) info = &pi;
        }
        if (!info)
          return kernel::Error{at(it.name_loc) + "unknown primitive behaviour '" + it.name + "'" +
                               hint(it.name, names)};
        if (it.args.size() != info->arity)
          return kernel::Error{at(it.name_loc) + "'" + it.name + "' takes " + std::to_string(info->arity) +
                               (info->arity == 1 ? " argument" : " arguments") + ", got " +
                               std::to_string(it.args.size()) + " (" + std::string(info->help) + ")"};
        if (it.mods.loop) return kernel::Error{at(it.mods.loop_loc) + "an atom cannot loop (put it in a behaviour)"};
        if (auto s = new_node(it.loc, id); !s) return s;
        Node d;
        d.op = Op::kAtom;
        d.name = intern(it.name);
        d.arg = static_cast<std::uint16_t>(info->id);
        d.param_offset = static_cast<std::uint16_t>(p_.params.size());
        d.param_count = info->arity;
        if (p_.params.size() + it.args.size() >= 60000) return kernel::Error{at(it.loc) + "too many arguments in all"};
        for (double v : it.args) p_.params.push_back(static_cast<float>(v));
        if (auto s = modifiers(it.mods, d); !s) return s;
        p_.nodes[id] = d;
        return {};
      }
      case K::kBehaviour: return behaviour(it.name, it.mods, it.children, it.loc, depth, id);
      case K::kCall: {
        const ast::BehaviourDecl* def = nullptr;
        std::vector<std::string_view> names;
        for (const auto& b : a_.behaviours) {
          names.push_back(b.name);
          if (b.name == it.name) def = &b;
        }
        if (!def) {
          if (it.name == a_.plan->name) return kernel::Error{at(it.name_loc) + "a plan cannot be called with 'do'"};
          return kernel::Error{at(it.name_loc) + "unknown behaviour '" + it.name + "'" + hint(it.name, names)};
        }
        if (std::find(stack_.begin(), stack_.end(), def) != stack_.end())
          return kernel::Error{at(it.name_loc) + "behaviour '" + it.name + "' calls itself (recursion is not allowed)"};
        ast::Modifiers m = def->mods;
        if (it.mods.until) m.until = it.mods.until;
        if (it.mods.duration_ms) m.duration_ms = it.mods.duration_ms;
        if (it.mods.loop) {
          m.loop = true;
          m.loop_count = it.mods.loop_count;
          m.loop_loc = it.mods.loop_loc;
        }
        stack_.push_back(def);
        auto s = behaviour(def->name, m, def->children, it.loc, depth, id);
        stack_.pop_back();
        return s;
      }
      case K::kTask: {
        if (depth > kMaxDepth)
          return kernel::Error{at(it.loc) + "nested deeper than " + std::to_string(kMaxDepth) + " levels"};
        if (auto s = new_node(it.loc, id); !s) return s;
        Node d;
        d.op = Op::kTask;
        d.name = intern(it.name);
        d.arg = static_cast<std::uint16_t>(it.task_op);
        p_.nodes[id] = d;
        return {};
      }
      case K::kDevice: {
        if (depth > kMaxDepth)
          return kernel::Error{at(it.loc) + "nested deeper than " + std::to_string(kMaxDepth) + " levels"};
        if (auto s = new_node(it.loc, id); !s) return s;
        Node d;
        d.op = Op::kDevice;
        d.name = intern(it.name);
        d.arg = intern(it.command);
        d.param_offset = static_cast<std::uint16_t>(p_.params.size());
        d.param_count = static_cast<std::uint8_t>(it.args.size());
        if (p_.params.size() + it.args.size() >= 60000) return kernel::Error{at(it.loc) + "too many arguments in all"};
        for (double v : it.args) p_.params.push_back(static_cast<float>(v));
        p_.nodes[id] = d;
        return {};
      }
    }
    return kernel::Error{at(it.loc) + "internal error: bad item"};
  }

  const ast::Program& a_;
  Program p_;
  std::vector<const ast::BehaviourDecl*> stack_;
};

}  // namespace

kernel::Result<Program> compile(const ast::Program& program) {
  if (!program.plan) return kernel::Error{at(program.end) + "the program has no plan"};
  return Compiler(program).run();
}

kernel::Result<Program> compile_source(std::string_view source) {
  auto ast = parse(source);
  if (!ast) return kernel::Error{ast.error()};
  return compile(*ast);
}

}  // namespace symb::control::mdl2e
