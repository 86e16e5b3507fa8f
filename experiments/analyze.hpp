// Forwards to experiments/studies/analyze.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/studies/analyze.hpp"
