// Forwards for one version to core/theory/tableau.hpp, where this header moved.
#pragma once
#include "core/theory/tableau.hpp"  // IWYU pragma: export
