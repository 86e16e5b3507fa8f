// Forwards to experiments/framework/study.hpp for one version (its path before experiments/ was
// split by job).
#pragma once
#include "experiments/framework/study.hpp"
