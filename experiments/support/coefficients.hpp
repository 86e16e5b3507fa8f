// A method's coefficients analysed (core/method_analysis.hpp), for the studies that show them:
// analyze, region, and the convergence orders table's achieved order.
#pragma once

#include <optional>
#include <string>

#include "core/integrator.hpp"
#include "core/method_analysis.hpp"
#include "core/tableau.hpp"

namespace stiffbench {

// "explicit_rk" (A strictly lower triangular), "dirk" (lower triangular) or "irk".
std::string tableau_kind(const ButcherTableau& t);
// The analysis of an integrator's own coefficients (butcher_tableau(), rosenbrock_tableau() or
// kick_drift_coefficients()); empty when it has none. Convergence and local-error orders tables
// show its achieved order beside the claimed one.
std::optional<MethodAnalysis> coefficient_analysis(const Integrator& integ);
// The name of an additive pair's table analysed alone ("ark324l2sa:explicit"; part "explicit"
// or "implicit"): run_analyze puts these two rows right after the pair's.
std::string additive_part_name(const std::string& integrator, const std::string& part);

}  // namespace stiffbench
