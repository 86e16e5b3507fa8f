// What every implicit method shares: the Jacobian (analytic, or finite differences dense /
// column-grouped over a known pattern / matrix-free products), the matrix W = I - hγJ in a
// fixed pattern, its linear solver, and Newton's method for stage equations
//     z = ψ + hγ f(t, z).
//
// Newton (parameter `newton`):
//   full      J re-evaluated and W refactored at every iterate;
//   modified  J evaluated once per step (at the first iterate of the step), reused by all stages;
//   frozen    J kept across steps, re-evaluated only when Newton fails with a stale J.
// Stopping rule (Hairer & Wanner, Solving ODEs II, §IV.8): after update k, with
// ‖·‖ = max_i |·_i| / (1 + |z_i|) and the contraction rate θ_k = ‖Δ_k‖/‖Δ_{k-1}‖,
//   converged  when θ_k/(1 - θ_k) ‖Δ_k‖ ≤ newton_tol (the predicted distance to the solution),
//              or ‖Δ_k‖ ≤ 4ε (round-off; the only way to stop after one update, which has no
//              rate), or θ_k ≥ 1 with ‖Δ_k‖ ≤ 100ε (the update is rounding noise);
//   diverging  when θ_k ≥ 1 above that;
//   too slow   when θ_k^(newton_max_iter - k)/(1 - θ_k) ‖Δ_k‖ > newton_tol (the limit would be
//              reached first; not tested with full Newton, whose convergence is not linear);
//   iteration limit after newton_max_iter updates.
// The default newton_tol = 1e-15 (a few unit round-offs) iterates to round-off, so that the
// Newton error of a fixed-step run stays at its round-off floor (about N·ε·|y| after N steps)
// and never sets the error at small h; a looser newton_tol lets each step carry an error up to
// newton_tol. The accepted iterate is z_k + Δ_k (no further f evaluation): a linear problem with
// an exact J takes two updates per stage, the second at round-off.
// A failed attempt is retried: with J from an earlier stage or step (modified, frozen), once
// with J fresh at the solve's start; with a fresh J, once with full Newton; a diverging attempt
// restarts from the predictor, a slow one continues from its iterate. Each failed attempt counts
// in stats.newton_conv_failures; after the last, Status::newton_failed with a message naming
// each attempt's reason and θ (the step is never silently accepted).
//
// Mechanical systems (system_form=auto or velocity): on a MechanicalSystem with force Jacobians K
// and D every linear system W k = r is solved in velocity form
// (integrators/solvers/velocity_form.hpp: n unknowns instead of 2n, symmetric for symmetric force
// Jacobians, pinned dofs eliminated; auto linear solver ldlt / cg); system_form=first_order keeps
// the 2n system (for comparison), with J written in place from K and D.
//
// Krylov tolerances (krylov_forcing=eisenstat_walker, the default): Newton's k-th linear solve
// stops at the relative residual η_k = 0.9 (‖G_k‖/‖G_{k-1}‖)² (Eisenstat & Walker 1996, choice
// 2, with their safeguard η_k ≥ 0.9 η_{k-1}² when that is above 0.1), η_0 = 0.01, capped at 0.1
// and floored at max(krylov_tol, 0.1 newton_tol / ‖G_k‖₂) (no accuracy beyond what the Newton
// test asks for). An inexact solve slows the contraction, which θ measures, so it costs
// iterations, not accuracy. krylov_forcing=fixed uses krylov_tol for every solve.
//
// A linear solver that fails (refuses a non-symmetric matrix, meets non-positive curvature,
// a singular factorisation, no Krylov convergence) ends the step with Status::solver_error and
// its reason, not newton_failed.
//
// Counting: every f evaluation (Newton residuals, finite-difference columns, matrix-free
// products) goes through OdeSystem::rhs and is counted there. stats.jac_evals gets +1 for each
// finite-difference Jacobian; analytic ones are counted at the system boundary.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/integrator.hpp"
#include "core/params.hpp"
#include "integrators/solvers/linear_solver.hpp"
#include "integrators/solvers/sparse_assembly.hpp"
#include "integrators/solvers/velocity_form.hpp"

namespace stiffbench {

enum class NewtonMode { full, modified, frozen };
enum class JacobianSource { automatic, analytic, fd_dense, fd_colored, matrix_free };
enum class SystemForm { automatic, velocity, first_order };

struct ImplicitOptions {
  NewtonMode newton = NewtonMode::modified;
  double newton_tol = 1e-15;
  int newton_max_iter = 10;
  JacobianSource jacobian = JacobianSource::automatic;
  LinearSolverOptions linear;
  bool preconditioner_given = false;
  SystemForm form = SystemForm::automatic;
  bool eisenstat_walker = true;  // Krylov tolerances follow Newton (see the header comment)
};

// The outcome of one Newton iteration sequence (one attempt of a solve).
enum class NewtonOutcome {
  converged,
  diverging,
  too_slow,
  iteration_limit,
  non_finite,
  linear_failed
};
struct NewtonAttempt {
  NewtonOutcome outcome = NewtonOutcome::iteration_limit;
  int iters = 0;       // updates made
  double theta = 0.0;  // last contraction estimate ‖Δ_k‖/‖Δ_{k-1}‖ (0 before the second)
  double dnorm = 0.0;  // ‖Δ_k‖ of the last update
  bool fresh_jacobian = false;  // J was evaluated during this attempt
};

// Round-off levels of an update, in norms relative to 1 + |z_i|: an update at most
// kNewtonRoundoff (4 unit round-offs) is accepted without a rate; one at most kNewtonNoise (100
// unit round-offs) that no longer contracts is rounding noise (converged, not diverging).
inline constexpr double kNewtonRoundoff = 4 * 2.220446049250313e-16;
inline constexpr double kNewtonNoise = 100 * 2.220446049250313e-16;

// The stopping test shared by every Newton iteration of the implicit methods, after an update
// of norm dnorm (the previous one prev_dnorm; have_rate once there are two). True when the
// iteration ends, with *outcome converged, diverging, too_slow or non_finite and *theta the rate:
//   converged   dnorm ≤ kNewtonRoundoff; or θ/(1-θ) dnorm ≤ tol; or θ ≥ 1 with dnorm ≤ kNewtonNoise
//   diverging   θ ≥ 1 above the noise level
//   too_slow    (slow_test) θ^(max_iter - iters_done)/(1-θ) dnorm > tol above the noise level
bool newton_update_converged(double dnorm, double prev_dnorm, bool have_rate, double tol,
                             int iters_done, int max_iter, bool slow_test, NewtonOutcome* outcome,
                             double* theta);
// "diverging (theta = 3.1 >= 1 at iteration 2, |dz| = 0.4)", "too slow (...)", ...
std::string describe_newton_failure(const NewtonAttempt& a, double tol);

// Parameters of the implicit family (with_newton: also the Newton keys).
std::vector<ParamSpec> implicit_param_specs(bool with_newton);
ImplicitOptions read_implicit_options(const Params& p, bool with_newton);

// The keys every Newton-based method reads alike: newton_tol (> 0) and newton_max_iter (>= 1)
// when with_iteration, then jacobian and linear_solver. read_implicit_options, gauss's and
// radau5's readers all take them from here (their ParamSpecs differ only in help texts, the
// default newton_max_iter and the values they allow).
struct NewtonOptions {
  double tol = 1e-15;
  int max_iter = 10;
  JacobianSource jacobian = JacobianSource::automatic;
  LinearSolverKind linear = LinearSolverKind::automatic;
};
NewtonOptions read_newton_options(const Params& p, bool with_iteration = true);

// ImplicitCore's options for a method that runs its own (transformed) Newton iteration and uses
// the core for the Jacobian of the first-order form only, J itself also for mechanical systems
// (gauss, radau5).
ImplicitOptions first_order_core_options(JacobianSource jacobian, LinearSolverKind linear);

// nonzeros / n² of the model's Jacobian pattern, or 1 without one (LinearSolverOptions::
// pattern_density). Evaluated only where automatic_is_dense depends on it (dense_small < n <=
// dense_max): the default pattern costs one Jacobian evaluation (not counted).
double jacobian_pattern_density(const OdeSystem& sys, const LinearSolverOptions& opt);

// Greedy column grouping for finite-difference Jacobians (Curtis, Powell & Reid 1974): columns
// that share no row get the same colour and are perturbed together.
std::vector<int> color_columns(const SparseMat& pattern, int* n_colors);

class ImplicitCore {
 public:
  explicit ImplicitCore(ImplicitOptions opt) : opt_(std::move(opt)), user_linear_(opt_.linear) {}

  // Chooses the Jacobian source and linear solver for `sys`, computes the pattern of W and
  // runs the symbolic analysis. BadInput for impossible combinations (e.g. matrix_free with a
  // direct solver).
  void reset(const OdeSystem& sys, double t0, CVecRef y0);
  // Integrator::restart: the next step evaluates J again and factorises W anew; the Jacobian
  // source, linear solver, patterns and symbolic analysis of reset() stay.
  void restart() {
    have_jac_ = jac_fresh_in_step_ = w_current_ = false;
    error_.clear();
  }
  // The system of the last reset() (nullptr before the first).
  const OdeSystem* system() const { return sys_; }

  // Marks the start of a step (modified Newton evaluates J again at its first iterate).
  void new_step() { jac_fresh_in_step_ = false; }

  // J at (t, y); fy = f(t, y) (finite differences reuse it).
  void update_jacobian(const OdeSystem& sys, double t, CVecRef y, CVecRef fy, SolveStats& stats);

  // W = I - hγ J with the current J, factored (or set up for Krylov). False if singular.
  bool prepare(double hg, SolveStats& stats);

  // Solves W x = b. x is the initial guess for Krylov solvers. On failure error() says why.
  bool solve(CVecRef b, VecRef x, SolveStats& stats);
  const std::string& error() const { return error_; }
  // Relative residual of the following Krylov solves (Eisenstat–Walker forcing).
  void set_krylov_tolerance(double tol);

  // out = J v with the current J (assembled) or a finite-difference product (matrix-free).
  void jacobian_times(CVecRef v, VecRef out, SolveStats& stats);

  // Newton tolerance of the following solves (adaptive DIRK pairs set it per trial).
  void set_newton_tol(double tol) { opt_.newton_tol = tol; }

  // Newton on z = ψ + hγ f(t, z). z holds the initial guess; fz is work space (f at the last
  // iterate but one on success).
  Status solve_stage(const OdeSystem& sys, double t, CVecRef psi, double hg, VecRef z, VecRef fz,
                     SolveStats& stats);

  JacobianSource jacobian_source() const { return source_; }
  LinearSolverKind linear_solver() const {
    return velocity_ ? velocity_->kind() : solver_ ? solver_->kind() : opt_.linear.kind;
  }
  bool velocity_form() const { return velocity_ != nullptr; }
  const VelocityFormSolver* velocity_solver() const { return velocity_.get(); }
  const SparseMat& jacobian_matrix() const { return jac_; }
  const ImplicitOptions& options() const { return opt_; }

 private:
  // reset() in steps: the Jacobian source (automatic resolved, combinations checked) and the
  // linear-solver options it implies; the restrictions of matrix-free products; the
  // velocity-form solver, or the first-order W = I - hγJ with J's pattern, its finite-difference
  // colouring and (mechanical systems) the positions of K and D in J; the work vectors.
  LinearSolverOptions resolve_jacobian_source(const OdeSystem& sys);
  void restrict_to_matrix_free(LinearSolverOptions& lin) const;
  void setup_velocity_form(const MechanicalSystem& mech, LinearSolverOptions lin, double t0,
                           CVecRef y0);
  void setup_first_order(const OdeSystem& sys, LinearSolverOptions lin, double t0, CVecRef y0);
  void map_force_jacobians(const MechanicalSystem& mech, double t0, CVecRef y0);
  void allocate_workspaces(Index n);
  void fd_jacobian(const OdeSystem& sys, double t, CVecRef y, CVecRef fy);
  void rebuild_w_pattern();
  bool is_krylov_run() const;
  Status linear_failure(double t, SolveStats& stats);
  // One Newton iteration sequence from z: J as configured (configured), evaluated at the start
  // and then reused (fresh), or at every iterate (full).
  enum class JacobianUse { configured, fresh, full };
  NewtonAttempt newton_attempt(const OdeSystem& sys, double t, CVecRef psi, double hg, VecRef z,
                               VecRef fz, SolveStats& stats, JacobianUse use);

  ImplicitOptions opt_;
  // The linear-solver options as the user gave them: every reset() resolves `automatic` choices
  // from these (opt_.linear holds the resolved ones of the current run).
  LinearSolverOptions user_linear_;
  JacobianSource source_ = JacobianSource::analytic;
  std::unique_ptr<LinearSolver> solver_;
  std::unique_ptr<VelocityFormSolver> velocity_;
  const OdeSystem* sys_ = nullptr;
  const MechanicalSystem* mech_inplace_ = nullptr;  // first-order J filled in place from K, D
  SparseMat jac_, identity_, k_, d_;
  std::vector<int> k_in_jac_, d_in_jac_;
  SparseCombination w_;
  std::vector<SparseTerm> w_terms_;  // {I, -hγ J}: kept so that prepare() does not allocate
  KrylovWorkspace krylov_ws_;
  double krylov_tol_ = 0.0;  // matrix-free solves
  std::string error_;
  std::vector<int> colors_;
  int n_colors_ = 0;
  bool have_jac_ = false, jac_fresh_in_step_ = false, w_current_ = false;
  double w_hg_ = 0.0;
  // Linearisation point of the matrix-free product.
  double lin_t_ = 0.0;
  Vec lin_y_, lin_f_, tmp_, tmp2_, g_, delta_, z0_;
  // fd_jacobian()'s f(y - δ): not g_, which holds the Newton residual when the Jacobian is
  // refreshed inside the iteration.
  Vec fd_minus_;
};

}  // namespace stiffbench
