// Forwards for one version to integrators/solvers/linear_solver.hpp, where this header moved.
#pragma once
#include "integrators/solvers/linear_solver.hpp"  // IWYU pragma: export
