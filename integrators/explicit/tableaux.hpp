// The explicit Runge–Kutta tableaux of the testbed, as data. Coefficients from Butcher,
// Numerical Methods for ODEs (2016) §23 and Hairer–Nørsett–Wanner I, Table II.1.1–1.2;
// SSPRK3 from Shu & Osher (1988).
#pragma once

#include <vector>

#include "core/tableau.hpp"

namespace stiffbench {

// euler, heun, midpoint, ralston, kutta3, ssprk3, rk4, rk38 (registration order).
const std::vector<ButcherTableau>& explicit_tableaux();

}  // namespace stiffbench
