// Forwards for one version to core/theory/linear_stability.hpp, where this header moved.
#pragma once
#include "core/theory/linear_stability.hpp"  // IWYU pragma: export
