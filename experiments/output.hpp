// Forwards to experiments/output/output.hpp for one version (its path before experiments/ was split
// by job).
#pragma once
#include "experiments/output/output.hpp"
