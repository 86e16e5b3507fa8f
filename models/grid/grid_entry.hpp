// What the grid models' registry entries (NAME_entry() beside each model, listed by
// models/grid/register.cpp) share.
#pragma once

#include "core/registry_types.hpp"

#include <algorithm>
#include <memory>
#include <string>

namespace stiffbench {

// Integer parameter `key` of `model`, checked to lie in [lo, hi].
inline int grid_int(const Params& p, const std::string& key, const std::string& model, long lo,
                    long hi) {
  const long v = p.integer(key);
  require_input(v >= lo && v <= hi, model + ": parameter '" + key + "' must be in [" +
                                        std::to_string(lo) + ", " + std::to_string(hi) + "] (got " +
                                        std::to_string(v) + ")");
  return static_cast<int>(v);
}

}  // namespace stiffbench
