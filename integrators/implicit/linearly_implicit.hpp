// Forwards for one version to integrators/implicit/rosenbrock.hpp, where this header moved.
#pragma once
#include "integrators/implicit/rosenbrock.hpp"  // IWYU pragma: export
