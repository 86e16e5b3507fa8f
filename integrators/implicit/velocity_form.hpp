// Forwards for one version to integrators/solvers/velocity_form.hpp, where this header moved.
#pragma once
#include "integrators/solvers/velocity_form.hpp"  // IWYU pragma: export
