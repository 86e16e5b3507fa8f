// `stiffbench audit [--integrators a,b,...]`: checks what every method claims against what it
// does, and writes audit.{csv,md,json} (one row per check), exit code 3 when a claim fails.
//
// Checks per integrator (default: every registered one; a user's own objects through
// resolve_inputs):
//   f_evals_fixed, jac_evals_fixed, f_evals_adaptive, jac_evals_adaptive (per system):
//     the evaluations an independent counting wrapper around the system saw (its own
//     eval_rhs / eval_acceleration / eval_jacobian / force_jacobians overrides; see
//     CountingSystem below) equal the reported SolveStats::f_evals and jac_evals exactly, on a
//     scalar linear system, Kepler (e = 0.5) and an 8×8 cloth (methods enforcing holonomic
//     constraints: a constrained pendulum chain); fixed-step runs of 16 steps, adaptive runs with
//     the method's default tolerances;
//   f_per_step (per system, explicit RK and symplectic families, fixed step): the f evaluations
//     added by 8 more steps are 8 × MethodInfo::stages (start-up costs such as an FSAL first
//     stage cancel in the difference);
//   local_error_slope (Kepler e = 0.5): the error of one step from the initial state against the
//     exact solution, on the ladder h = 0.5·2^(-k/2) (k = 0..27); the least-squares slope of
//     log(error) over log(h) on the three smallest h whose errors lie in [floor, 1e-3] is
//     order + 1 to within 0.3, where floor = max(1e-13, 100 × the largest error of the four
//     smallest h): there a high-order method's error is round-off or its solver's tolerance
//     (Newton noise), which the factor 100 keeps out of the fit;
//   adaptive_constant (adaptive methods): y' = 1, y(0) = 0 to t = 1 is exact to 1e-13 in at
//     most 30 steps (every error estimate is zero up to round-off: embedded weights that do not
//     sum to 1 make it h·(1 - Σb̂) and the run crawls);
//   adaptive_polynomial (adaptive methods): y' = t^(p-1), y(0) = 0 to t = 1 gives 1/p to 1e-13
//     (an order-p method integrates polynomials of degree p - 1 exactly);
//   tableau_order, embedded_order, stage_order, fsal (methods defined by a Butcher tableau):
//     every order condition up to the claimed order met to 1e-12 and some condition of the next
//     order not (order_defect generates the rooted trees up to order 6: a claim of 6 or more is
//     checked up to 6), the claimed stage order's C(q) and the FSAL property against the
//     coefficients;
//   tableau_order, embedded_order, w_order (Rosenbrock methods): the claimed order and embedded
//     order are exactly those of the Rosenbrock order conditions (rooted trees to order 8,
//     core/theory/method_analysis.hpp), a claimed W-order exactly that of the W-conditions (an
//     arbitrary matrix in place of J, to order 6; no claim: skip, with the W-order that holds).
// A check that does not apply is a row with status `skip` and the reason (a method that needs a
// spring network, constraints or a grid fluid on a system without one; variable-order library
// methods for the slope and exactness checks; a library's internal f count).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/ode_system.hpp"
#include "core/theory/tableau.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/output.hpp"

namespace stiffbench {

// What the counting wrapper saw. f: eval_rhs, eval_acceleration and the IMEX parts; jac: analytic
// Jacobians (eval_jacobian), force-Jacobian pairs (force_jacobians) and direct stiffness_block
// calls (the system boundary counts none of the last two: implicit methods add them to their
// SolveStats themselves, which is what this check verifies).
struct CallCounts {
  long f = 0;
  long jac = 0;
};

// A decorator around `inner` that counts its own calls and forwards everything else, so it
// offers every capability hook of the wrapped system (mechanical, Jacobians, constraints,
// springs, IMEX split, metadata, frame output). It is a MechanicalSystem when `inner` is one.
// `inner` and `counts` must outlive the wrapper.
std::unique_ptr<OdeSystem> make_counting_system(const OdeSystem& inner, CallCounts& counts);

struct AuditRow {
  std::string integrator, check, system, claimed, measured, status, reason;
};

struct AuditSpec {
  // The integrators' labels (StudyInputs::integrators); empty: every registered integrator.
  std::vector<std::string> integrators;
  void validate() const;  // BadInput: an integrator listed twice
  nlohmann::json to_json() const;
};

struct AuditResult {
  std::vector<AuditRow> rows;
  long count(const std::string& status) const;
};

// Audits `in`'s integrators (the spec's integrators are `in`'s; a user's own methods are given as
// objects to resolve_inputs), one progress line per integrator.
AuditResult run_audit(const StudyInputs& in, const AuditSpec& spec,
                      std::ostream* progress = nullptr);
// The same on the names the spec gives (resolve_inputs first).
AuditResult run_audit(const AuditSpec& spec, std::ostream* progress = nullptr);

// The checks of one integrator, in the order of the table: rows named `name`, a fresh instance
// from `create` for every run.
std::vector<AuditRow> audit_integrator(const std::string& name, const IntegratorFactory& create);

// audit.csv: integrator, check, system, claimed, measured, status (ok, fail, skip), reason.
Table audit_table(const AuditResult& r);
// One row per integrator: integrator, ok, fail, skip, failed checks.
Table audit_summary_table(const AuditResult& r);

const AuditResult& audit_result(const StudyJob& job);
// Checks with status fail in this process (every audit run adds its own); the command line exits
// with kExitRowsFailed (3) when it is not zero.
long audit_failed_checks();
// The one call for programs: check DIR, audit `in`'s integrators (none: every registered one),
// write DIR/audit.{csv,md,json}, print (ctx.out); the failed checks count in
// audit_failed_checks().
AuditResult audit_study(const StudyInputs& in, AuditSpec spec, const std::filesystem::path& dir,
                        const StudyContext& ctx = {});

}  // namespace stiffbench
