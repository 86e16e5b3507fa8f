// Forwards for one version to integrators/solvers/sparse_assembly.hpp, where this header moved.
#pragma once
#include "integrators/solvers/sparse_assembly.hpp"  // IWYU pragma: export
