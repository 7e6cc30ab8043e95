// The MDL2e lexer: program text to tokens. Identifiers, keywords (lower case), numbers with an
// optional unit suffix (`500ms`, `2s`), punctuation, and `#` comments to the end of the line.
// Any other byte is an error naming its line and column. No exceptions, no OS calls.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "symb/control/mdl2e/ast.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::mdl2e {

enum class TokenKind : std::uint8_t {
  kIdent,     // names and keywords
  kNumber,    // 12, 3.5, 500ms (the suffix is in Token::suffix)
  kLBrace,    // {
  kRBrace,    // }
  kLParen,    // (
  kRParen,    // )
  kLBracket,  // [
  kRBracket,  // ]
  kComma,     // ,
  kAssign,    // =
  kLt,        // <
  kGt,        // >
  kLe,        // <=
  kGe,        // >=
  kMinus,     // -
  kEnd,       // end of text
};

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string_view text;    // the token as written (views the source)
  std::string_view suffix;  // kNumber: letters written right after the digits, e.g. "ms"
  ast::Loc loc;
};

// A short human name of a token kind for error messages ("'{'", "a number").
std::string_view token_kind_name(TokenKind kind);

// Largest program text accepted, in bytes.
inline constexpr std::size_t kMaxSourceBytes = 1 << 20;

// Splits `source` into tokens, ending with one kEnd token. Errors read "LINE:COLUMN: message".
kernel::Result<std::vector<Token>> lex(std::string_view source);

}  // namespace symb::control::mdl2e
