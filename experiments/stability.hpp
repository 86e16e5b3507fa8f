// Forwards to experiments/studies/stability.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/studies/stability.hpp"
