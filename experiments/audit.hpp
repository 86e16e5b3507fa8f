// Forwards to experiments/studies/audit.hpp for one version (its path before experiments/ was split
// by job).
#pragma once
#include "experiments/studies/audit.hpp"
