// The MDL2e compiler: resolves the names of an ast::Program (sensor channels, basic interrupts,
// behaviours, primitives) and lays it out as the flat byte code of bytecode.hpp. Named behaviours
// used with `do NAME` are expanded in place (a call's own until/for/loop replace the definition's),
// so the byte code is one tree; recursion is an error. Errors read "LINE:COLUMN: message" and offer
// a "did you mean" for misspelt names.
#pragma once

#include <string_view>

#include "symb/control/mdl2e/ast.hpp"
#include "symb/control/mdl2e/bytecode.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::mdl2e {

// Most nodes one program may expand to.
inline constexpr std::size_t kMaxNodes = 4096;

kernel::Result<Program> compile(const ast::Program& program);
// parse() then compile(): program text to verified byte code.
kernel::Result<Program> compile_source(std::string_view source);

}  // namespace symb::control::mdl2e
