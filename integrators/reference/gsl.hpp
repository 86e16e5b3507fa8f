// GSL odeiv2 references (GSL 2.7), run on the testbed's own OdeSystem. Only gsl.cpp includes
// GSL headers.
//
//   gsl_rk4, gsl_rkf45, gsl_rkck, gsl_rk8pd      explicit Runge–Kutta (embedded pairs)
//   gsl_rk2imp, gsl_rk4imp                       implicit Gaussian (Gauss–Legendre) RK
//   gsl_bsimp                                    Bader–Deuflhard semi-implicit extrapolation
//   gsl_msadams, gsl_msbdf                       variable-order Adams / BDF (multistep)
// Adaptive mode: gsl_odeiv2_driver with the standard control (error ≤ atol + rtol |y|),
// output at requested times. Fixed-step mode (all but the multistep ones):
// gsl_odeiv2_driver_apply_fixed_step, one step of h per driver step. The Jacobian that
// rk2imp, rk4imp, bsimp and msbdf need is the model's analytic one (dense copy) or forward
// differences, with ∂f/∂t by a forward difference for non-autonomous models; all of these f
// evaluations go through the counted boundary. GSL's error handler is switched off; a failing
// status becomes Status::solver_error with gsl_strerror's text.
// GSL keeps no f counter of its own: library_f_evals is not reported (-1). Adaptive counters
// (gsl.cpp, finish()): steps = the steps the driver accepted (its n, summed over calls),
// error_test_failures = the evolve object's count (steps computed) minus the accepted ones,
// newton_conv_failures = its failed_steps minus those rejections (attempts whose stepper
// failed: the implicit steppers' solves that did not converge; GSL halves h and retries).
// GSL reports no Newton iterations, factorisations or linear solves: for the steppers that
// take a Jacobian (rk2imp, rk4imp, bsimp, msbdf) linear_setups and lin_solves, and but for the
// linearly implicit bsimp newton_iters, are SolveStats::kNotReported (empty in the CSVs, "not
// reported" in the tables), not 0; the explicit steppers and msadams (functional iteration)
// make none, and Krylov iterations are 0 for all.
#pragma once

#include <string>

#include "core/registry_types.hpp"

namespace stiffbench {

void register_gsl_integrators(IntegratorRegistry& reg);

// The version of the GSL library linked (its gsl_version), recorded in run metadata.
std::string gsl_library_version();

}  // namespace stiffbench
