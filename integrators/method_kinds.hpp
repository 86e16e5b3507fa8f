// The kinds of method file (docs/method-files.md), in MethodKind's order: one list
// for the method-file reader (integrators/method_file.cpp) and for readers of other TOML files
// (the spec parser) that must tell a method file apart. Header-only, so that the spec parser,
// which the fuzz targets build on their own (scripts/fuzz.sh), needs no integrator code.
#pragma once

#include <algorithm>
#include <array>
#include <string_view>

namespace stiffbench {

inline constexpr std::array<std::string_view, 6> kMethodKindNames = {
    "explicit_rk", "dirk", "irk", "rosenbrock", "splitting", "imex_ark"};

inline bool is_method_kind(std::string_view kind) {
  return std::find(kMethodKindNames.begin(), kMethodKindNames.end(), kind) !=
         kMethodKindNames.end();
}

}  // namespace stiffbench
