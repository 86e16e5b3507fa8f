// Forwards to experiments/studies/work_precision.hpp for one version (its path before experiments/
// was split by job).
#pragma once
#include "experiments/studies/work_precision.hpp"
