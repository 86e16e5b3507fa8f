// Kept for source compatibility of user code: the registry types are in core/registry_types.hpp.
#pragma once
#include "core/registry_types.hpp"  // IWYU pragma: export
