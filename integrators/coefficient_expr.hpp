// Exact coefficient expressions of method files (integrators/method_file.hpp): a coefficient
// is a TOML number or a string such as "1/3", "(3 - sqrt(3))/6" or "1 - 1/sqrt(2)", evaluated
// in long double, so that a coefficient written as an expression reaches the double the
// integrator uses correctly rounded (or within an ulp of it) rather than through a decimal
// transcription.
//
// Grammar (usual precedence; ^ binds tighter than unary minus, so -2^2 = -4, and is right
// associative):
//   expr    := term (('+' | '-') term)*
//   term    := unary (('*' | '/') unary)*
//   unary   := ('+' | '-') unary | power
//   power   := primary ('^' unary)?          exponent: an integer value (|n| <= 64)
//   primary := number | name | func '(' expr ')' | '(' expr ')'
//   number  := digits ['.' digits] [('e' | 'E') ['+' | '-'] digits]   (or '.' digits ...)
//   func    := sqrt | cbrt
//   name    := [A-Za-z_][A-Za-z0-9_]*         a constant of the file's [constants] table
// A bad expression (a syntax error, an unknown name, a division by zero, the square root of a
// negative number, a non-integer exponent, a result that is not finite or not finite as a double,
// nesting deeper than kMaxCoefficientDepth) is BadInput naming the expression and the 1-based
// position of the fault.
#pragma once

#include <map>
#include <string>

namespace stiffbench {

using CoefficientConstants = std::map<std::string, long double>;

// The deepest nesting an expression may have: every '(' , function call and unary sign is a
// level (a hand-written coefficient needs a handful; 20,000 nested parentheses would otherwise
// overflow the parser's stack).
inline constexpr int kMaxCoefficientDepth = 200;

long double evaluate_coefficient(const std::string& expression,
                                 const CoefficientConstants& constants = {});

}  // namespace stiffbench
