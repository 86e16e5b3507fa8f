// Forwards to experiments/studies/energy.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/studies/energy.hpp"
