// The explicit Runge–Kutta tableaux of the testbed. They are defined by their method files
// (methods/*.toml with kind = "explicit_rk": coefficients, description, kind, reference, order
// and, for the embedded pairs, embedded_order and fsal), compiled into the library and parsed by
// built_in_methods() (integrators/method_file.hpp); these lookups only select from them.
//   fixed-step methods  euler, heun, midpoint, ralston, kutta3, ssprk3, rk4, rk38
//                       (ExplicitRungeKutta)
//   embedded pairs      bs3, dopri5, cash_karp, rkf45: b propagates the solution, b_embedded
//                       gives the error estimate y - ŷ; run fixed-step or adaptively by
//                       integrators/adaptive/embedded_rk.hpp
// Their order conditions are checked for both weight rows in tests/integrators/test_adaptive.cpp.
#pragma once

#include <vector>

#include "core/theory/tableau.hpp"

namespace stiffbench {

// The built-in explicit tableaux without embedded weights, and the embedded pairs, in the order
// of built_in_methods() (file name).
const std::vector<ButcherTableau>& explicit_tableaux();
const std::vector<ButcherTableau>& embedded_tableaux();

}  // namespace stiffbench
