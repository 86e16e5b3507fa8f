#include "integrators/coefficient_expr.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "core/types.hpp"

namespace stiffbench {

namespace {

class Parser {
 public:
  Parser(const std::string& text, const CoefficientConstants& constants)
      : s_(text), constants_(constants) {}

  long double run() {
    skip_space();
    if (pos_ == s_.size()) fail(pos_, "empty expression");
    const long double v = expr();
    skip_space();
    if (pos_ != s_.size()) fail(pos_, "unexpected '" + std::string(1, s_[pos_]) + "'");
    if (!std::isfinite(v)) fail(0, "the value is not finite");
    // Evaluated in long double, used in double: a value that is finite only in long double
    // (e.g. 1e400) is as unusable as an infinite one, for every kind of coefficient.
    if (!std::isfinite(static_cast<double>(v)))
      fail(0, "the value is outside the range of double (|x| > 1.8e308)");
    return v;
  }

  // The nesting depth: parentheses, function calls and chains of unary signs each recurse; past
  // kMaxCoefficientDepth the expression is refused instead of overflowing the stack.
  struct Nest {
    Parser& p;
    explicit Nest(Parser& parser) : p(parser) {
      if (++p.depth_ > kMaxCoefficientDepth)
        p.fail(p.pos_, "nested deeper than " + std::to_string(kMaxCoefficientDepth) +
                           " levels (parentheses, function calls or signs)");
    }
    ~Nest() { --p.depth_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;
  };

 private:
  [[noreturn]] void fail(std::size_t at, const std::string& what) const {
    // A long expression is shown by its beginning and length (the position locates the fault).
    const std::string shown =
        s_.size() <= 80 ? s_
                        : s_.substr(0, 60) + "...\" (" + std::to_string(s_.size()) + " characters";
    throw BadInput("expression \"" + shown + (s_.size() <= 80 ? "\"" : ")") + ": at position " +
                   std::to_string(at + 1) + ": " + what);
  }

  void skip_space() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }

  bool accept(char c) {
    skip_space();
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  void expect(char c) {
    if (!accept(c))
      fail(pos_, std::string("expected '") + c + "'" +
                     (pos_ < s_.size() ? std::string(", found '") + s_[pos_] + "'"
                                       : std::string(" at the end")));
  }

  long double expr() {
    long double v = term();
    for (;;) {
      if (accept('+'))
        v += term();
      else if (accept('-'))
        v -= term();
      else
        return v;
    }
  }

  long double term() {
    long double v = unary();
    for (;;) {
      if (accept('*')) {
        v *= unary();
      } else if (accept('/')) {
        skip_space();
        const std::size_t at = pos_;
        const long double d = unary();
        if (d == 0.0L) fail(at, "division by zero");
        v /= d;
      } else {
        return v;
      }
    }
  }

  long double unary() {
    const Nest nest(*this);
    if (accept('-')) return -unary();
    if (accept('+')) return unary();
    return power();
  }

  long double power() {
    const long double base = primary();
    if (!accept('^')) return base;
    skip_space();
    const std::size_t at = pos_;
    const long double e = unary();
    if (e != std::floor(e) || std::fabs(e) > 64.0L)
      fail(at, "the exponent must be an integer between -64 and 64");
    long n = std::lround(static_cast<double>(e));
    if (n < 0 && base == 0.0L) fail(at, "zero to a negative power");
    const bool invert = n < 0;
    if (invert) n = -n;
    long double r = 1.0L;
    for (long k = 0; k < n; ++k) r *= base;
    return invert ? 1.0L / r : r;
  }

  long double primary() {
    skip_space();
    if (pos_ >= s_.size()) fail(pos_, "expected a number, a name or '(' at the end");
    const char c = s_[pos_];
    if (c == '(') {
      ++pos_;
      const long double v = expr();
      expect(')');
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
    fail(pos_, "expected a number, a name or '(', found '" + std::string(1, c) + "'");
  }

  long double number() {
    const std::size_t start = pos_;
    auto digits = [&] {
      const std::size_t from = pos_;
      while (pos_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      return pos_ - from;
    };
    std::size_t n = digits();
    if (pos_ < s_.size() && s_[pos_] == '.') {
      ++pos_;
      n += digits();
    }
    if (n == 0) fail(start, "malformed number");
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      ++pos_;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      if (digits() == 0) fail(start, "malformed number (exponent without digits)");
    }
    const std::string text = s_.substr(start, pos_ - start);
    return std::strtold(text.c_str(), nullptr);
  }

  long double name() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() &&
           (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      ++pos_;
    const std::string id = s_.substr(start, pos_ - start);
    if (id == "sqrt" || id == "cbrt") {
      expect('(');
      skip_space();
      const std::size_t at = pos_;
      const long double v = expr();
      expect(')');
      if (id == "cbrt") return std::cbrt(v);
      if (v < 0.0L) fail(at, "the square root of a negative number");
      return std::sqrt(v);
    }
    const auto it = constants_.find(id);
    if (it != constants_.end()) return it->second;
    std::vector<std::string> known;
    for (const auto& [k, v] : constants_) known.push_back(k);
    fail(start, "unknown name '" + id + "'" + did_you_mean(id, known) +
                    (known.empty() ? std::string("; functions: sqrt, cbrt; no [constants] defined")
                                   : "; functions: sqrt, cbrt; constants: " + join(known)));
  }

  const std::string& s_;
  const CoefficientConstants& constants_;
  std::size_t pos_ = 0;
  int depth_ = 0;
};

}  // namespace

long double evaluate_coefficient(const std::string& expression,
                                 const CoefficientConstants& constants) {
  return Parser(expression, constants).run();
}

}  // namespace stiffbench
