// Forwards to experiments/commands/compare.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/commands/compare.hpp"
