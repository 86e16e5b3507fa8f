// Forwards to experiments/commands/profile.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/commands/profile.hpp"
