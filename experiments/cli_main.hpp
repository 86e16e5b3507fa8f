// Forwards to cli/cli_main.hpp for one version (its path before experiments/ was split by job).
#pragma once
#include "cli/cli_main.hpp"
