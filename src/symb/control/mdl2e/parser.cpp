#include "symb/control/mdl2e/parser.hpp"

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>

#include "symb/control/mdl2e/lexer.hpp"

namespace symb::control::mdl2e {
namespace {

constexpr std::string_view kKeywords[] = {"sensor", "interrupt", "behaviour", "behavior", "plan",     "atom",
                                          "do",     "task",      "until",     "for",      "loop",     "and",
                                          "or",     "not",       "true",      "false",    "external", "device"};

bool is_keyword(std::string_view s) {
  for (auto k : kKeywords)
    if (k == s) return true;
  return false;
}

std::string quote(std::string_view s) { return "'" + std::string(s) + "'"; }

class Parser {
 public:
  explicit Parser(std::vector<Token> tokens) : t_(std::move(tokens)) {}

  kernel::Result<ast::Program> run() {
    ast::Program p;
    while (!at(TokenKind::kEnd)) {
      const Token& k = peek();
      if (is_word("sensor")) {
        next();
        ast::SensorDecl s;
        s.loc = k.loc;
        if (!name(s.name, "a sensor channel name")) return err();
        if (!expect(TokenKind::kLBracket, "after the sensor name")) return err();
        if (!integer(s.size, 1, 256, "channel size")) return err();
        if (!expect(TokenKind::kRBracket, "after the channel size")) return err();
        p.sensors.push_back(std::move(s));
      } else if (is_word("interrupt")) {
        next();
        ast::InterruptDecl d;
        d.loc = k.loc;
        if (!name(d.name, "an interrupt name")) return err();
        if (!expect(TokenKind::kAssign, "after the interrupt name")) return err();
        if (is_word("external")) {
          next();
          d.external = true;
        } else {
          d.channel_loc = peek().loc;
          if (!name(d.channel, "a sensor channel name or 'external'")) return err();
          if (!expect(TokenKind::kLBracket, "after the channel name")) return err();
          d.index_loc = peek().loc;
          if (!integer(d.index, 0, 255, "sensor index")) return err();
          if (!expect(TokenKind::kRBracket, "after the sensor index")) return err();
          switch (peek().kind) {
            case TokenKind::kLt: d.op = ast::CmpOp::kLt; break;
            case TokenKind::kGt: d.op = ast::CmpOp::kGt; break;
            case TokenKind::kLe: d.op = ast::CmpOp::kLe; break;
            case TokenKind::kGe: d.op = ast::CmpOp::kGe; break;
            default: return fail(peek().loc, "expected a comparison (<, >, <=, >=), got " + describe(peek()));
          }
          next();
          if (!signed_number(d.threshold, 1e9, "threshold")) return err();
        }
        p.interrupts.push_back(std::move(d));
      } else if (is_word("behaviour") || is_word("behavior")) {
        next();
        ast::BehaviourDecl b;
        b.loc = k.loc;
        if (!name(b.name, "a behaviour name")) return err();
        if (!modifiers(b.mods)) return err();
        if (!body(b.children)) return err();
        p.behaviours.push_back(std::move(b));
      } else if (is_word("plan")) {
        if (p.plan)
          return fail(
              k.loc, "a program has exactly one plan; another was defined at line " + std::to_string(p.plan->loc.line));
        next();
        ast::BehaviourDecl b;
        b.loc = k.loc;
        if (!name(b.name, "a plan name")) return err();
        if (!modifiers(b.mods)) return err();
        if (!body(b.children)) return err();
        p.plan = std::move(b);
      } else {
        return fail(k.loc, "expected 'sensor', 'interrupt', 'behaviour' or 'plan', got " + describe(k));
      }
    }
    p.end = peek().loc;
    if (!p.plan) return fail(p.end, "the program has no plan (add 'plan NAME { ... }')");
    return p;
  }

 private:
  const Token& peek(std::size_t ahead = 0) const {
    const std::size_t k = pos_ + ahead;
    return k < t_.size() ? t_[k] : t_.back();
  }
  const Token& next() {
    const Token& t = t_[pos_];
    if (pos_ + 1 < t_.size()) ++pos_;
    return t;
  }
  bool at(TokenKind k) const { return peek().kind == k; }
  bool is_word(std::string_view w) const { return at(TokenKind::kIdent) && peek().text == w; }

  static std::string describe(const Token& t) {
    if (t.kind == TokenKind::kEnd) return std::string(token_kind_name(t.kind));
    return quote(std::string(t.text) + std::string(t.suffix));
  }

  kernel::Error err() const { return kernel::Error{error_}; }
  kernel::Error fail(ast::Loc loc, const std::string& message) {
    error_ = kernel::location_prefix(loc) + message;
    return kernel::Error{error_};
  }
  bool failed(ast::Loc loc, const std::string& message) {
    (void)fail(loc, message);
    return false;
  }

  bool expect(TokenKind k, std::string_view where) {
    if (!at(k))
      return failed(peek().loc, "expected " + std::string(token_kind_name(k)) + " " + std::string(where) + ", got " +
                                    describe(peek()));
    next();
    return true;
  }

  bool name(std::string& out, std::string_view what) {
    const Token& t = peek();
    if (t.kind != TokenKind::kIdent) return failed(t.loc, "expected " + std::string(what) + ", got " + describe(t));
    if (is_keyword(t.text))
      return failed(t.loc, "expected " + std::string(what) + ", got the keyword " + quote(t.text));
    out = std::string(t.text);
    next();
    return true;
  }

  bool number_value(const Token& t, double& out) {
    const char* b = t.text.data();
    const char* e = b + t.text.size();
    auto [ptr, ec] = std::from_chars(b, e, out);
    if (ec != std::errc() || ptr != e || !std::isfinite(out)) return failed(t.loc, "bad number " + describe(t));
    return true;
  }

  bool integer(std::uint32_t& out, std::uint32_t lo, std::uint32_t hi, std::string_view what) {
    const Token& t = peek();
    if (t.kind != TokenKind::kNumber) return failed(t.loc, "expected " + std::string(what) + ", got " + describe(t));
    if (!t.suffix.empty()) return failed(t.loc, std::string(what) + " takes no unit, got " + describe(t));
    if (t.text.find('.') != std::string_view::npos)
      return failed(t.loc, std::string(what) + " must be a whole number, got " + describe(t));
    std::uint64_t v = 0;
    auto [ptr, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || ptr != t.text.data() + t.text.size() || v < lo || v > hi)
      return failed(t.loc, std::string(what) + " must be in " + std::to_string(lo) + ".." + std::to_string(hi) +
                               ", got " + describe(t));
    out = static_cast<std::uint32_t>(v);
    next();
    return true;
  }

  bool signed_number(double& out, double limit, std::string_view what) {
    const ast::Loc loc = peek().loc;
    bool neg = false;
    if (at(TokenKind::kMinus)) {
      neg = true;
      next();
    }
    const Token& t = peek();
    if (t.kind != TokenKind::kNumber) return failed(t.loc, "expected " + std::string(what) + ", got " + describe(t));
    if (!t.suffix.empty()) return failed(t.loc, std::string(what) + " takes no unit, got " + describe(t));
    if (!number_value(t, out)) return false;
    if (neg) out = -out;
    if (std::fabs(out) > limit)
      return failed(loc, std::string(what) + " must be within +-" + std::to_string(static_cast<long long>(limit)));
    next();
    return true;
  }

  bool duration(std::uint32_t& ms) {
    const Token& t = peek();
    if (t.kind != TokenKind::kNumber)
      return failed(t.loc, "expected a duration such as 500ms or 2s, got " + describe(t));
    double v = 0;
    if (!number_value(t, v)) return false;
    double scale = 0;
    if (t.suffix == "ms")
      scale = 1;
    else if (t.suffix == "s")
      scale = 1000;
    else if (t.suffix.empty())
      return failed(t.loc, "duration " + describe(t) + " needs a unit: ms or s");
    else
      return failed(t.loc, "unknown duration unit " + quote(t.suffix) + " (use ms or s)");
    const double total = v * scale;
    if (total != std::floor(total)) return failed(t.loc, "duration " + describe(t) + " is not a whole number of ms");
    if (total < 1 || total > 4e9) return failed(t.loc, "duration " + describe(t) + " must be in 1ms..4000000s");
    ms = static_cast<std::uint32_t>(total);
    next();
    return true;
  }

  bool modifiers(ast::Modifiers& m) {
    bool have_until = false, have_for = false, have_loop = false;
    for (;;) {
      const Token& t = peek();
      if (is_word("until")) {
        if (have_until) return failed(t.loc, "'until' given twice");
        have_until = true;
        next();
        ast::Expr e;
        if (!expr_or(e)) return false;
        m.until = std::move(e);
      } else if (is_word("for")) {
        if (have_for) return failed(t.loc, "'for' given twice");
        have_for = true;
        next();
        m.duration_loc = peek().loc;
        std::uint32_t ms = 0;
        if (!duration(ms)) return false;
        m.duration_ms = ms;
      } else if (is_word("loop")) {
        if (have_loop) return failed(t.loc, "'loop' given twice");
        have_loop = true;
        m.loop = true;
        m.loop_loc = t.loc;
        next();
        if (at(TokenKind::kNumber) && !integer(m.loop_count, 1, 65535, "loop count")) return false;
      } else {
        return true;
      }
    }
  }

  bool body(std::vector<ast::Item>& items) {
    const auto level = body_nesting_.enter();
    if (!level) return failed(peek().loc, "behaviours nested too deeply");
    if (!expect(TokenKind::kLBrace, "to open the body")) return false;
    while (!at(TokenKind::kRBrace)) {
      if (at(TokenKind::kEnd)) return failed(peek().loc, "expected '}' to close the body, got the end of the program");
      ast::Item it;
      if (!item(it)) return false;
      items.push_back(std::move(it));
    }
    if (items.empty()) return failed(peek().loc, "a body needs at least one atom, behaviour, 'do', 'task' or 'device'");
    next();
    return true;
  }

  bool item(ast::Item& it) {
    const Token& k = peek();
    it.loc = k.loc;
    if (is_word("atom")) {
      next();
      it.kind = ast::Item::Kind::kAtom;
      it.name_loc = peek().loc;
      if (!name(it.name, "a primitive behaviour name (forward, backward, turn, wheels, stop)")) return false;
      if (at(TokenKind::kLParen)) {
        it.args_loc = peek().loc;
        next();
        if (!at(TokenKind::kRParen)) {
          for (;;) {
            if (it.args.size() >= 8) return failed(peek().loc, "too many arguments");
            double v = 0;
            if (!signed_number(v, 1e6, "argument")) return false;
            it.args.push_back(v);
            if (at(TokenKind::kComma)) {
              next();
              continue;
            }
            break;
          }
        }
        if (!expect(TokenKind::kRParen, "to close the arguments")) return false;
      }
      return modifiers(it.mods);
    }
    if (is_word("behaviour") || is_word("behavior")) {
      next();
      it.kind = ast::Item::Kind::kBehaviour;
      it.name_loc = peek().loc;
      if (at(TokenKind::kIdent) && !is_keyword(peek().text)) it.name = std::string(next().text);
      if (!modifiers(it.mods)) return false;
      return body(it.children);
    }
    if (is_word("do")) {
      next();
      it.kind = ast::Item::Kind::kCall;
      it.name_loc = peek().loc;
      if (!name(it.name, "a behaviour name")) return false;
      return modifiers(it.mods);
    }
    if (is_word("task")) {
      next();
      it.kind = ast::Item::Kind::kTask;
      const Token& op = peek();
      if (op.kind == TokenKind::kIdent && op.text == "start")
        it.task_op = ast::TaskOp::kStart;
      else if (op.kind == TokenKind::kIdent && op.text == "suspend")
        it.task_op = ast::TaskOp::kSuspend;
      else if (op.kind == TokenKind::kIdent && op.text == "resume")
        it.task_op = ast::TaskOp::kResume;
      else if (op.kind == TokenKind::kIdent && op.text == "delete")
        it.task_op = ast::TaskOp::kDelete;
      else
        return failed(op.loc, "expected start, suspend, resume or delete after 'task', got " + describe(op));
      next();
      it.name_loc = peek().loc;
      return name(it.name, "a task name");
    }
    if (is_word("device")) {
      next();
      it.kind = ast::Item::Kind::kDevice;
      it.name_loc = peek().loc;
      if (!name(it.name, "a device name")) return false;
      it.command_loc = peek().loc;
      if (!name(it.command, "a command of device '" + it.name + "'")) return false;
      if (at(TokenKind::kNumber) || at(TokenKind::kMinus)) {
        it.args_loc = peek().loc;
        double v = 0;
        if (!signed_number(v, 1e6, "argument")) return false;
        it.args.push_back(v);
      }
      return true;
    }
    return failed(k.loc, "expected 'atom', 'behaviour', 'do', 'task', 'device' or '}', got " + describe(k));
  }

  // A chain `a or b or c ...` is one flat node with an operand per term, however long; only
  // parentheses and 'not' nest, and those are bounded by kMaxExprNesting.
  bool expr_or(ast::Expr& out) { return chain(out, "or", ast::Expr::Kind::kOr); }
  bool expr_and(ast::Expr& out) { return chain(out, "and", ast::Expr::Kind::kAnd); }

  bool chain(ast::Expr& out, std::string_view op, ast::Expr::Kind kind) {
    ast::Expr first;
    if (!term(first, kind)) return false;
    if (!is_word(op)) {
      out = std::move(first);
      return true;
    }
    out = ast::Expr{};
    out.kind = kind;
    out.loc = peek().loc;
    out.operands.push_back(std::move(first));
    while (is_word(op)) {
      next();
      ast::Expr rhs;
      if (!term(rhs, kind)) return false;
      out.operands.push_back(std::move(rhs));
    }
    return true;
  }
  bool term(ast::Expr& out, ast::Expr::Kind kind) {
    return kind == ast::Expr::Kind::kOr ? expr_and(out) : expr_not(out);
  }

  bool expr_not(ast::Expr& out) {
    const Token& t = peek();
    if (is_word("not")) {
      const auto level = expr_nesting_.enter();
      if (!level) return failed(t.loc, "interrupt expression nested too deeply");
      next();
      out.kind = ast::Expr::Kind::kNot;
      out.loc = t.loc;
      ast::Expr inner;
      if (!expr_not(inner)) return false;
      out.operands.push_back(std::move(inner));
      return true;
    }
    if (at(TokenKind::kLParen)) {
      const auto level = expr_nesting_.enter();
      if (!level) return failed(t.loc, "interrupt expression nested too deeply");
      next();
      if (!expr_or(out)) return false;
      return expect(TokenKind::kRParen, "to close the interrupt expression");
    }
    if (is_word("true") || is_word("false")) {
      out.kind = t.text == "true" ? ast::Expr::Kind::kTrue : ast::Expr::Kind::kFalse;
      out.loc = t.loc;
      next();
      return true;
    }
    out.kind = ast::Expr::Kind::kRef;
    out.loc = t.loc;
    return name(out.name, "an interrupt name, 'not', 'true', 'false' or '('");
  }

  std::vector<Token> t_;
  std::size_t pos_ = 0;
  std::string error_;
  // Only bodies and parenthesised or negated interrupt expressions recurse; and/or chains loop.
  kernel::NestingBound body_nesting_{kMaxParseNesting};
  kernel::NestingBound expr_nesting_{kMaxExprNesting};
};

}  // namespace

kernel::Result<ast::Program> parse(std::string_view source) {
  auto tokens = lex(source);
  if (!tokens) return kernel::Error{tokens.error()};
  return Parser(std::move(tokens).value()).run();
}

}  // namespace symb::control::mdl2e
