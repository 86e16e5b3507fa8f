// The systems `stiffbench audit` runs the methods on (private to the audit's files): small
// problems with exact solutions, each with an additive split for the methods that need one.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/ode_system.hpp"

namespace stiffbench::audit_parts {

// A system of the count checks, with the span of a run on it.
struct CountSystem {
  std::string label;
  std::unique_ptr<OdeSystem> sys;
  double span;  // fixed-step and adaptive runs cover [t0, t0 + span]
};

// The three systems of the count checks: y' = -y, Kepler (e = 0.5) and an 8×8 cloth. Methods
// that need an additive split (`split`: IMEX pairs, operator splitting, multirate) get split
// systems instead: the scalar one in halves, Kaps' problem (ε = 1e-3, its 1/ε terms implicit;
// kepler has no split) and the cloth with split=springs.
std::vector<CountSystem> count_systems(bool split);

// y' = t^q (q = 0: y' = 1), y(0) = 0, exact y = t^(q+1)/(q+1); split: each part t^q/2, so that a
// pair whose two tables have order p integrates it exactly.
std::unique_ptr<OdeSystem> monomial_system(int q, bool split);

// y' = E y + I y, a rotation E (the explicit part) and a decay I (the implicit part) that do not
// commute, with its exact solution: the local-error system of the methods that need a split.
std::unique_ptr<OdeSystem> rotation_decay_system();

}  // namespace stiffbench::audit_parts
