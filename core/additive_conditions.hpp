// Forwards for one version to core/theory/additive_conditions.hpp, where this header moved.
#pragma once
#include "core/theory/additive_conditions.hpp"  // IWYU pragma: export
