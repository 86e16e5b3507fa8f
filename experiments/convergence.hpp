// Forwards to experiments/studies/convergence.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/studies/convergence.hpp"
