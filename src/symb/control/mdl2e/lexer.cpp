#include "symb/control/mdl2e/lexer.hpp"

#include <cstdio>
#include <string>

namespace symb::control::mdl2e {
namespace {

bool is_alpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

std::string_view token_kind_name(TokenKind kind) {
  switch (kind) {
    case TokenKind::kIdent: return "a name";
    case TokenKind::kNumber: return "a number";
    case TokenKind::kLBrace: return "'{'";
    case TokenKind::kRBrace: return "'}'";
    case TokenKind::kLParen: return "'('";
    case TokenKind::kRParen: return "')'";
    case TokenKind::kLBracket: return "'['";
    case TokenKind::kRBracket: return "']'";
    case TokenKind::kComma: return "','";
    case TokenKind::kAssign: return "'='";
    case TokenKind::kLt: return "'<'";
    case TokenKind::kGt: return "'>'";
    case TokenKind::kLe: return "'<='";
    case TokenKind::kGe: return "'>='";
    case TokenKind::kMinus: return "'-'";
    case TokenKind::kEnd: return "the end of the program";
  }
  return "a token";
}

kernel::Result<std::vector<Token>> lex(std::string_view source) {
  std::vector<Token> out;
  ast::Loc loc{1, 1};
  if (source.size() > kMaxSourceBytes)
    return kernel::located_error(loc, "program is longer than " + std::to_string(kMaxSourceBytes) + " bytes");
  std::size_t i = 0;
  auto advance = [&](std::size_t n) {
    for (std::size_t k = 0; k < n; ++k, ++i) {
      if (source[i] == '\n') {
        ++loc.line;
        loc.column = 1;
      } else {
        ++loc.column;
      }
    }
  };
  while (i < source.size()) {
    const char c = source[i];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      advance(1);
      continue;
    }
    if (c == '#') {
      while (i < source.size() && source[i] != '\n') advance(1);
      continue;
    }
    Token t;
    t.loc = loc;
    const std::size_t start = i;
    if (is_alpha(c)) {
      std::size_t j = i;
      while (j < source.size() && (is_alpha(source[j]) || is_digit(source[j]))) ++j;
      if (j - i > 63) return kernel::located_error(loc, "name is longer than 63 characters");
      t.kind = TokenKind::kIdent;
      t.text = source.substr(i, j - i);
      advance(j - i);
      out.push_back(t);
      continue;
    }
    if (is_digit(c)) {
      std::size_t j = i;
      while (j < source.size() && is_digit(source[j])) ++j;
      if (j < source.size() && source[j] == '.') {
        ++j;
        if (j >= source.size() || !is_digit(source[j])) {
          ast::Loc at = loc;
          at.column += j - i;
          return kernel::located_error(at, "expected a digit after the decimal point");
        }
        while (j < source.size() && is_digit(source[j])) ++j;
      }
      std::size_t k = j;
      while (k < source.size() && (is_alpha(source[k]) || is_digit(source[k]))) ++k;
      if (k - i > 40) return kernel::located_error(loc, "number is too long");
      t.kind = TokenKind::kNumber;
      t.text = source.substr(i, j - i);
      t.suffix = source.substr(j, k - j);
      advance(k - i);
      out.push_back(t);
      continue;
    }
    std::size_t len = 1;
    switch (c) {
      case '{': t.kind = TokenKind::kLBrace; break;
      case '}': t.kind = TokenKind::kRBrace; break;
      case '(': t.kind = TokenKind::kLParen; break;
      case ')': t.kind = TokenKind::kRParen; break;
      case '[': t.kind = TokenKind::kLBracket; break;
      case ']': t.kind = TokenKind::kRBracket; break;
      case ',': t.kind = TokenKind::kComma; break;
      case '=': t.kind = TokenKind::kAssign; break;
      case '-': t.kind = TokenKind::kMinus; break;
      case '<':
      case '>': {
        const bool eq = i + 1 < source.size() && source[i + 1] == '=';
        t.kind = c == '<' ? (eq ? TokenKind::kLe : TokenKind::kLt) : (eq ? TokenKind::kGe : TokenKind::kGt);
        len = eq ? 2 : 1;
        break;
      }
      default: {
        char buf[48];
        const auto u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f)
          std::snprintf(buf, sizeof buf, "unexpected character '%c'", c);
        else
          std::snprintf(buf, sizeof buf, "unexpected byte 0x%02x", u);
        return kernel::located_error(loc, buf);
      }
    }
    t.text = source.substr(start, len);
    advance(len);
    out.push_back(t);
  }
  Token end;
  end.kind = TokenKind::kEnd;
  end.loc = loc;
  out.push_back(end);
  return out;
}

}  // namespace symb::control::mdl2e
