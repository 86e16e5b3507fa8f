// The explicit Runge–Kutta methods of the testbed, as data: one entry per method (coefficients,
// description, kind, reference, step modes; integrators/method_entry.hpp). Coefficients from
// Butcher, Numerical Methods for ODEs (2016) §23 and Hairer–Nørsett–Wanner I,
// Table II.1.1–1.2; SSPRK3 from Shu & Osher (1988).
#pragma once

#include <vector>

#include "core/tableau.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {

using ExplicitRkMethod = MethodEntry<ButcherTableau>;

// In registration order: the fixed-step methods euler, heun, midpoint, ralston, kutta3,
// ssprk3, rk4, rk38 (ExplicitRungeKutta), then the embedded pairs (b propagates the solution,
// b_embedded gives the error estimate y - ŷ), run fixed-step or adaptively by
// integrators/adaptive/embedded_rk.hpp:
//   bs3        Bogacki & Shampine (1989) 3(2), FSAL, 4 stages (3 f evaluations per step)
//   dopri5     Dormand & Prince (1980) 5(4), FSAL, 7 stages (6 per step); HNW I Table II.5.2
//   cash_karp  Cash & Karp (1990) 5(4), 6 stages; propagates the fifth-order solution
//   rkf45      Fehlberg (1969) 4(5), 6 stages; propagates the fourth-order solution (Fehlberg's
//              choice; local extrapolation would give order 5), HNW I Table II.5.1
// Their order conditions are checked for both weight rows in tests/test_adaptive.cpp.
const std::vector<ExplicitRkMethod>& explicit_rk_methods();

// The tableaux of the table above: the fixed-step methods, and the embedded pairs.
const std::vector<ButcherTableau>& explicit_tableaux();
const std::vector<ButcherTableau>& embedded_tableaux();

}  // namespace stiffbench
