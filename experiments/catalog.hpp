// Forwards to experiments/framework/catalog.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/framework/catalog.hpp"
