// What the graphics solvers (xpbd, projective_dynamics) need of a system: a mechanical system
// that lists its springs (core/springs.hpp). Set by field name, so a field added to Requirements
// later cannot shift these.
#pragma once

#include "core/integrator.hpp"

namespace stiffbench {

inline Requirements spring_network_requirements() {
  Requirements r;
  r.mechanical = true;
  r.spring_network = true;
  return r;
}

}  // namespace stiffbench
