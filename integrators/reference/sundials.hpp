// SUNDIALS references (CVODE 6.4, ARKODE 5.4), run on the testbed's own OdeSystem. This folder
// is the only one that includes SUNDIALS headers (here only in sundials/, not in this header),
// so a port to SUNDIALS 7 touches that folder only.
//
//   cvode_bdf, cvode_adams   CVODE, variable order/step; adaptive only. Parameters: rtol, atol,
//                            linear_solver = auto | dense | band | klu | spgmr (klu uses the
//                            model's sparse Jacobian and pattern; spgmr a Jacobian-vector
//                            product, analytic (from the sparse J) or CVODE's difference
//                            quotient; auto: see sundials_auto_linear_solver below),
//                            max_order, max_steps, jacobian = auto | analytic | dq.
//   arkode_erk               ARKStep, explicit table by ARKODE name (default
//                            ARKODE_DORMAND_PRINCE_7_4_5).
//   arkode_dirk              ARKStep, implicit table by name (default ARKODE_SDIRK_5_3_4,
//                            L-stable, order 4).
//   arkode_imex              ARKStep with the model's explicit/implicit split
//                            (OdeSystem::has_imex_split); all-implicit when the model has none.
//                            ARK pair by `tables` (ARKStepSetTableNum; default ark436l2sa =
//                            ARKODE_ARK436L2SA_ERK_6_3_4 + _DIRK_6_3_4) or, with tables=named,
//                            explicit_table/implicit_table by name. In split mode the Newton
//                            matrices come from J_I (implicit_part_view: implicit_part_jacobian,
//                            or K_I/D_I of a mechanical model), not the full J.
//   arkode_mri               MRIStep: slow f_E explicit (coupling table), fast f_I by an inner
//                            implicit ARKStep on J_I; fixed slow step only (SUNDIALS 6.4).
// ARKODE integrators run adaptive (rtol/atol) or fixed-step (ARKStepSetFixedStep: step() of the
// driver takes exactly one step of h; implicit stages still use Newton with tolerances derived
// from rtol/atol and nonlin_conv_coef/max_nonlin_iters, so tighten them for convergence studies
// and step-for-step comparisons: rtol=1e-12 atol=1e-14 nonlin_conv_coef=1e-3
// max_nonlin_iters=20).
//
// Structure (integrators/reference/sundials/): three front-ends, CvodeIntegrator (cvode.cpp:
// cvode_bdf, cvode_adams), ArkodeIntegrator (arkode.cpp: arkode_erk, arkode_dirk, arkode_imex) and
// MriIntegrator (mri.cpp: arkode_mri), implement the library calls of one SundialsFrontEnd
// (front_end.*: the Integrator face: reset, fixed steps, adaptive runs to exact stops, restarts,
// error messages, counters); all run on a shared SundialsAdapter (adapter.*), the library's user
// data: the C callbacks (f, IMEX parts, analytic Jacobian, J v, the velocity-form
// preconditioner) with their exception guard, and the linear solver with its Jacobian pattern.
// tables.* holds the ARKODE tables by name (ARK pairs, MRI coupling tables) and register.cpp the
// registry entries with their parameters.
//
// State vectors are wrapped, not copied: N_VMake_Serial on the driver's y. Library errors
// become Status::solver_error with the library's flag name and message (also on stderr).
// Counters: the library's steps, error-test failures, nonlinear iterations and failures,
// linear setups, Jacobian evaluations and Krylov iterations are mapped into SolveStats;
// library_f_evals is the library's f count, which equals the boundary f count except that
// CVODE's and ARKODE's difference-quotient Jacobians (and ARKODE's IMEX split, counted per
// part at the boundary) are reported separately by the library (NumLinRhsEvals).
//
// Analytic Jacobians (matrix solvers and SPGMR's products) live in one sparse pattern fixed at
// reset(): the pattern of J plus the whole diagonal (explicit zeros where J has none; without
// them SUNDIALS 6's SUNMatScaleAddI rebuilds the sparse matrix quadratically). Each
// Jacobian callback writes values in place through index maps computed once. On a
// MechanicalSystem with force Jacobians the values come from force_jacobians(t, x, v, K, D)
// (J = [[0, I], [K, D]]; K and D kept between calls, one evaluation counted per call); other
// models go through OdeSystem::jacobian().
#pragma once

#include <string>

#include "core/registry_types.hpp"

namespace stiffbench {

void register_sundials_integrators(IntegratorRegistry& reg);

// The version of the SUNDIALS library linked (SUNDIALSGetVersion), recorded in run metadata.
std::string sundials_library_version();

// linear_solver=auto of every SUNDIALS integrator with a linear solver (cvode_bdf, cvode_adams,
// arkode_dirk, arkode_imex): a dense matrix up to kSundialsAutoDenseMax unknowns; above, KLU
// when the run uses the model's analytic sparse Jacobian (has_jacobian() and jacobian != dq) —
// for a MechanicalSystem with force Jacobians `velocity` instead: flexible GMRES right-
// preconditioned by the testbed's velocity-form solve of I - γJ (integrators/solvers/
// velocity_form.hpp; KLU on the 2n first-order matrix of cloth 64² took 47 s to t = 0.5) —
// else matrix-free SPGMR (no n² matrix, no n difference quotients per Jacobian).
// The dense limit is 100: SUNDIALS' own dense LU (2n³/3 flops per setup, no BLAS) is the
// slowest choice well below that wherever the system is sparse. cvode_bdf to t = 0.5, 1 thread
// (wall_s; dense / klu / velocity / spgmr): cloth n = 4 (96 unknowns) 0.086 / 0.022 / 0.017 /
// 0.015 s; n = 10 (600) 7.1 / 0.27 / 0.13 / 0.09 s; n = 16 (1536, the default cloth) 74.6 /
// 1.10 / 0.56 / 0.24 s; soft_cube defaults (384) 5.3 / 0.16 / 0.10 / 0.07 s; without a
// Jacobian, sph_drop_2d defaults (1264) to t = 0.01 dense (difference quotients) 12.1 s, spgmr
// 0.027 s. Every literature problem (at most 20 unknowns) stays dense.
inline constexpr Index kSundialsAutoDenseMax = 100;
struct SundialsLinearSolverChoice {
  std::string solver;  // "dense", "klu", "spgmr" or "velocity"
  std::string rule;    // why, e.g. "24576 unknowns > 100 and an analytic sparse Jacobian""
};
SundialsLinearSolverChoice sundials_auto_linear_solver(Index unknowns, bool analytic_jacobian,
                                                       bool mechanical_blocks = false);

}  // namespace stiffbench
