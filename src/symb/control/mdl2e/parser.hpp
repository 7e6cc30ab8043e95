// The MDL2e parser: program text to an ast::Program, or the first error as
// "LINE:COLUMN: message". Recursive descent over the tokens of lexer.hpp with bounded nesting, so
// no input (however deep or long) can exhaust the stack. The grammar is in docs/mdl2e.md:
//
//   sensor ir[7]
//   interrupt obstacle = ir[0] > 2000
//   behaviour avoid for 800ms { atom backward(80) for 300ms  atom turn(60) for 500ms }
//   plan main loop { atom forward(100) until obstacle  do avoid }
#pragma once

#include <string_view>

#include "symb/control/mdl2e/ast.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::mdl2e {

// Deepest nesting of behaviours the parser accepts (the compiler's limit is lower, see bytecode.hpp).
inline constexpr int kMaxParseNesting = 32;
// Deepest nesting of an interrupt expression (parentheses and NOT).
inline constexpr int kMaxExprNesting = 32;

// Parses a whole program. Syntax only: names are resolved by the compiler.
kernel::Result<ast::Program> parse(std::string_view source);

}  // namespace symb::control::mdl2e
