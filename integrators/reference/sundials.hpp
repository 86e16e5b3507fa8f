// SUNDIALS references (CVODE 6.4, ARKODE 5.4), run on the testbed's own OdeSystem. This folder
// is the only one that includes SUNDIALS headers (here only in sundials.cpp), so a port to
// SUNDIALS 7 touches one file.
//
//   cvode_bdf, cvode_adams   CVODE, variable order/step; adaptive only. Parameters: rtol, atol,
//                            linear_solver = dense | band | klu | spgmr (klu uses the model's
//                            sparse Jacobian and pattern; spgmr a Jacobian-vector product,
//                            analytic (from the sparse J) or CVODE's difference quotient),
//                            max_order, max_steps, jacobian = auto | analytic | dq.
//   arkode_erk               ARKStep, explicit table by ARKODE name (default
//                            ARKODE_DORMAND_PRINCE_7_4_5).
//   arkode_dirk              ARKStep, implicit table by name (default ARKODE_SDIRK_5_3_4,
//                            L-stable, order 4).
//   arkode_imex              ARKStep with the model's explicit/implicit split
//                            (OdeSystem::has_imex_split); all-implicit when the model has none.
//                            Tables by name (default ARKODE_ARK436L2SA_ERK_6_3_4 /
//                            ARKODE_ARK436L2SA_DIRK_6_3_4).
// ARKODE integrators run adaptive (rtol/atol) or fixed-step (ARKStepSetFixedStep: step() of the
// driver takes exactly one step of h; implicit stages still use Newton with tolerances derived
// from rtol/atol, so tighten rtol for convergence studies).
//
// State vectors are wrapped, not copied: N_VMake_Serial on the driver's y. Library errors
// become Status::solver_error with the library's flag name and message (also on stderr).
// Counters: the library's steps, error-test failures, nonlinear iterations and failures,
// linear setups, Jacobian evaluations and Krylov iterations are mapped into SolveStats;
// library_f_evals is the library's f count, which equals the boundary f count except that
// CVODE's and ARKODE's difference-quotient Jacobians (and ARKODE's IMEX split, counted per
// part at the boundary) are reported separately by the library (NumLinRhsEvals).
#pragma once

#include "core/catalog.hpp"

namespace stiffbench {

void register_sundials_integrators(IntegratorRegistry& reg);

}  // namespace stiffbench
