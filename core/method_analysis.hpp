// Forwards for one version to core/theory/method_analysis.hpp, where this header moved.
#pragma once
#include "core/theory/method_analysis.hpp"  // IWYU pragma: export
