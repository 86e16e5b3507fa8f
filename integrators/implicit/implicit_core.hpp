// Forwards for one version to integrators/solvers/newton.hpp, where this header moved.
#pragma once
#include "integrators/solvers/newton.hpp"  // IWYU pragma: export
