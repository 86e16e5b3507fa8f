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
    "explicit_rk", "dirk", "irk", "rosenbrock", "kick_drift", "imex_ark"};

// The old name of kick_drift, still accepted in method files for one version.
inline constexpr std::string_view kOldKickDriftKind = "splitting";

// A method file's kind with the old name replaced by the current one.
inline std::string_view current_method_kind(std::string_view kind) {
  return kind == kOldKickDriftKind ? std::string_view("kick_drift") : kind;
}

inline bool is_method_kind(std::string_view kind) {
  kind = current_method_kind(kind);
  return std::find(kMethodKindNames.begin(), kMethodKindNames.end(), kind) !=
         kMethodKindNames.end();
}

}  // namespace stiffbench
