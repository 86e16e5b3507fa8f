// Forwards to experiments/output/plotting.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/output/plotting.hpp"
