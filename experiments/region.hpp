// Forwards to experiments/studies/region.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/studies/region.hpp"
