// fuzz/targets.hpp's method_file_one: parse_method_file on arbitrary text.
#include <string>

#include "core/types.hpp"
#include "fuzz/targets.hpp"
#include "integrators/method_file.hpp"

namespace stiffbench::fuzz {

void method_file_one(std::string_view data) {
  try {
    const MethodDefinition m = parse_method_file(std::string(data), "fuzz.toml");
    if (m.name.empty()) fail("a method file without a name was accepted");
    if (m.order < 1) fail("a method file without an order was accepted");
  } catch (const BadInput&) {
  }
}

}  // namespace stiffbench::fuzz
