// What the problems' registry entries (NAME_entry() beside each model, listed by
// models/problems/register.cpp) share.
#pragma once

#include "core/registry_types.hpp"

#include <algorithm>
#include <memory>
#include <string>

namespace stiffbench {

// The size estimate of the fixed-size problems: at most 20 unknowns (POLLU), whatever their
// parameters.
inline ModelSize fixed_problem_size(const Params&) {
  return ModelSize{20, 4096, 400, "fixed size"};
}

}  // namespace stiffbench
