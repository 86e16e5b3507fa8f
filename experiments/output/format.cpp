// Number formats of the output files and tables (declared in experiments/output/output.hpp), in a
// file of their own so the spec-file parser's fuzz target links them without the rest of the
// library.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

#include "experiments/output/output.hpp"

namespace stiffbench {

std::string format_full(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  // Shortest representation that round-trips.
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, res.ptr);
}

std::string format_short(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, x);
  return buf;
}

std::string format_fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

}  // namespace stiffbench
