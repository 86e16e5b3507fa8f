// Forwards for one version to integrators/solvers/sparse_refactor_lu.hpp, where this header moved.
#pragma once
#include "integrators/solvers/sparse_refactor_lu.hpp"  // IWYU pragma: export
