// Radau IIA of order 5 (three stages, c = (4-√6)/10, (4+√6)/10, 1; stiffly accurate, L-stable,
// stage order 3), fixed-step and adaptive, after Hairer & Wanner, Solving ODEs II, §IV.8 and
// their code RADAU5.
//
// The class takes its tableau (radau5_tableau() for the built-in radau5, the method file
// methods/radau5.toml; a user's file with kind = "irk", solver = "radau5") and derives every
// constant below from it at construction. What RADAU5's iteration and error estimate rely on is
// checked, BadInput naming the tableau: ButcherTableau::validate (sizes, c = row sums, the claimed
// order); 3 stages; A invertible with A⁻¹ having one real eigenvalue and one complex-conjugate pair
// (diagonalised to round-off: T Λ⁻¹ T⁻¹ equals A to 1e-12 relative); c_3 = 1 and stiffly accurate,
// b = the last row of A (to 1e-14; y_{n+1} = y_n + Z_3); three distinct nodes (the embedded weights
// solve a Vandermonde system in c). A node at 0 (a Lobatto IIIC tableau) changes only the starting
// values: the previous stages are interpolated at the nodes without the point q(0) = 0.
//
// Stage equations for Z_i = Y_i - y_n:  Z = h (A ⊗ I) F(Z),  y_{n+1} = y_n + Z_3.
// Simplified Newton with J = ∂f/∂y at (t_n, y_n), in the transformed variables W = (T⁻¹ ⊗ I) Z
// where T⁻¹ A⁻¹ T = Λ = diag(γ̂, [[a, b], [-b, a]]) (A⁻¹ has one real eigenvalue γ̂ ≈ 3.6378 and
// a pair a ± ib ≈ 2.6811 ± 3.0504i; T is built from its eigenvectors at start-up):
//   (h⁻¹Λ ⊗ I - I ⊗ J) ΔW = (T⁻¹ ⊗ I) F((T ⊗ I) W) - h⁻¹ (Λ ⊗ I) W,
// which splits into one real system (γ̂/h I - J) ΔW_1 = r_1 and one complex system
// ((a - ib)/h I - J)(ΔW_2 + iΔW_3) = r_2 + i r_3 (HW IV.8, eq. (8.16)–(8.18)): two LU
// factorisations per new h or J instead of one of size 3n.
// Linear solvers: dense LU (Eigen PartialPivLU, real and std::complex<double>) up to 200
// unknowns or with linear_solver=dense_lu; SparseRefactorLu (sparse_refactor_lu.hpp: COLAMD,
// pivoting once, then numeric refactorisation) over the pattern of J ∪ diagonal otherwise or with
// linear_solver=sparse_lu (symbolic analysis once per run). J comes from the
// shared ImplicitCore (analytic, or finite differences dense / column-grouped; always the
// first-order form of mechanical systems).
//
// Newton: starting values from the previous step's collocation polynomial (zero at the start),
// θ_k = ‖ΔW_k‖/‖ΔW_{k-1}‖ in a weighted RMS norm.
//   adaptive:   RADAU5's rule (HW IV.8, "stopping criterion"): scale atol + rtol |y_n,i|,
//               η_k = θ_k/(1 - θ_k) (η_0 = max(η_old, ε)^0.8, the rate carried over from the last
//               step), converged when η_k ‖ΔW_k‖ ≤ κ = max(10 ε/rtol, min(0.03, rtol^½)) (FNEWT),
//               failed when θ_k ≥ 0.99 or when θ_k^(newton_max_iter-1-k)/(1 - θ_k) ‖ΔW_k‖ > κ;
//               the trial is retried with h/2 (a rejected step and a Newton failure), with a fresh
//               J when the failed one was from an earlier step (newton=frozen).
//   fixed step: scale 1 + |y_n,i| and the stopping test of every implicit method
//               (integrators/solvers/newton.hpp): converged when θ_k/(1 - θ_k) ‖ΔW_k‖ ≤
//               newton_tol (default 1e-15: round-off) or the update is at round-off; diverging,
//               too slow or iteration limit otherwise. A failed step is retried with a fresh J
//               and refactorised matrices: J from an earlier step (newton=frozen) is
//               re-evaluated at (t_n, y_n); a failure with that J is retried once more with J at
//               the end point (t_n + h, y_n + Z_3) of the last iterate (where a stiff solution
//               has moved to within the step), continuing from that iterate. After the last
//               failure the run ends with newton_failed and a message naming every attempt's
//               reason and θ; each failed attempt counts in newton_conv_failures.
// Jacobian reuse (newton): modified (default) evaluates J at every step's (t_n, y_n); frozen
// keeps it across steps (refactorising only when h changes) until a Newton failure.
// newton_max_iter defaults to 20 (RADAU5: 7 with its loose adaptive tolerance; iterating to
// round-off in fixed-step mode needs more at large steps).
//
// Error estimate (HW IV.8, eq. (8.19)–(8.20)): an embedded method of order 3 with
// b̂_0 = γ_0 = 1/γ̂ on f(t_n, y_n) gives
//   err = (I - hγ_0 J)⁻¹ [γ_0 h f(t_n, y_n) + e_1 Z_1 + e_2 Z_2 + e_3 Z_3],  e = (b̂ - b)ᵀ A⁻¹,
// where the factor (I - hγ_0 J)⁻¹ (the real matrix already factored) filters the stiff
// components; at the first step and after a rejection, when err > 1, it is recomputed once with
// f(t_n, y_n + err) in place of f(t_n, y_n) (HW's second filtering; one more f evaluation). The
// estimate is O(h⁴), so the shared controller (integrators/adaptive/controller.hpp) uses k = 4.
//
// Counting: f evaluations at the system boundary (3 per Newton iteration, f(t_n, y_n) once per
// new point, finite-difference Jacobian columns); jac_evals; newton_iters; newton_conv_failures;
// linear_setups +2 per factorisation pair; lin_solves +2 per Newton iteration (+1 per error
// estimate); steps and error_test_failures. Neither path allocates in a step after the first
// (tests/integrators/test_allocations.cpp).
#pragma once

#include <Eigen/LU>
#include <complex>
#include <string>

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"
#include "integrators/adaptive/controller.hpp"
#include "integrators/solvers/newton.hpp"
#include "integrators/solvers/sparse_refactor_lu.hpp"

namespace stiffbench {

const ButcherTableau& radau5_tableau();

struct Radau5Options {
  ControllerOptions control;
  double newton_tol = 1e-15;  // fixed-step mode (see above)
  int newton_max_iter = 20;
  bool frozen = false;  // newton=frozen: J kept across steps until a Newton failure
  JacobianSource jacobian = JacobianSource::automatic;
  LinearSolverKind linear = LinearSolverKind::automatic;
};

std::vector<ParamSpec> radau5_param_specs();
Radau5Options read_radau5_options(const Params& p);

// The constants of the transformed Newton iteration and of the error estimate, derived from the
// tableau (exposed for the tests).
struct Radau5Constants {
  Eigen::Matrix3d t, t_inv;  // T and T⁻¹
  double gamma_hat = 0;      // real eigenvalue of A⁻¹
  double a = 0, b = 0;       // Λ's 2×2 block [[a, b], [-b, a]]
  Eigen::Vector3d e;         // error weights e = (b̂ - b)ᵀ A⁻¹
};
// From a tableau, with the checks above (BadInput naming the tableau).
Radau5Constants radau5_constants(const ButcherTableau& tableau);
// Those of radau5_tableau().
const Radau5Constants& radau5_constants();

// M = shift·I - J factored, for a real or complex shift; dense (Eigen PartialPivLU) or sparse
// (SparseRefactorLu: the pattern of J ∪ diagonal analysed once, later factorisations numeric
// into the same storage, values written into sm_'s fixed pattern; no allocation after the
// first factorisation while J's pattern stays).
template <class Scalar>
class ShiftedSolver {
 public:
  using CVector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  void reset(Index n, bool dense);
  bool factor(Scalar shift, const SparseMat& jac);
  void solve(const CVector& rhs, CVector& out);

 private:
  using DenseM = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using SparseM = Eigen::SparseMatrix<Scalar>;
  bool dense_ = true;
  Index n_ = 0;
  DenseM m_;
  Eigen::PartialPivLU<DenseM> lu_;
  SparseM sm_;
  std::vector<int> jac_pos_, diag_pos_;  // value positions in sm_ of J's entries and the diagonal
  std::vector<SparseMat::StorageIndex> jac_inner_;  // J's pattern when sm_ was built
  bool analyzed_ = false;                           // slu_ has sm_'s pattern
  SparseRefactorLu<Scalar> slu_;
};

class Radau5 final : public Integrator {
 public:
  // The tableau checked as above. MethodInfo: the tableau's name and order, 3 stages, a
  // description saying which tableau RADAU5 runs (a registered method's description, kind and
  // reference come from its method file).
  Radau5(ButcherTableau tableau, Radau5Options opt);
  // radau5_tableau().
  explicit Radau5(Radau5Options opt);

  bool supports_adaptive() const override { return true; }
  std::optional<double> absolute_tolerance() const override { return opt_.control.atol; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(tableau_);
  }
  const ButcherTableau* butcher_tableau() const override { return &tableau_; }

 private:
  void restart_state(double t0);  // what reset() and restart() clear
  // Newton for the stages of a step of size h from (t, y), from the starting values (or, warm,
  // from the stages in z_).
  NewtonAttempt solve_stages(const OdeSystem& sys, double t, CVecRef y, double h, bool adaptive,
                             bool warm_start, SolveStats& stats);
  void ensure_jacobian(const OdeSystem& sys, double t, CVecRef y, SolveStats& stats);
  bool ensure_factors(double h, SolveStats& stats);
  // Scaled error of the accepted-candidate in z_ (adaptive mode).
  double estimate_error(const OdeSystem& sys, double t, CVecRef y, double h, bool refine,
                        SolveStats& stats);
  void starting_values(double h);
  void accept_stages(double h);

  ButcherTableau tableau_;
  Radau5Constants k_;
  bool zero_node_ = false;  // c_1 = 0: starting values without q(0) = 0
  Radau5Options opt_;
  ImplicitCore core_;
  StepController ctrl_;
  ShiftedSolver<double> real_;
  ShiftedSolver<std::complex<double>> complex_;
  Index n_ = 0;
  Mat z_, w_, f_, z_prev_;
  Vec f0_, ynew_, scale_, tmp_, tmp2_, err_;
  Vec r1_, x1_;
  Eigen::VectorXcd r2_, x2_;
  double eta_old_ = 1.0;
  // Where the current J was evaluated: this step's (t_n, y_n), an earlier step's (newton=frozen),
  // or the end point of a failed attempt's iterate (fixed-step retry).
  enum class JacPoint { start, earlier_step, end };
  JacPoint jac_point_ = JacPoint::start;
  double fact_h_ = 0.0;
  bool fact_valid_ = false, jac_valid_ = false, f0_valid_ = false, have_prev_ = false;
  double h_prev_ = 0.0;
  // Adaptive state.
  double t_ = 0.0, h_ = 0.0;
  bool first_ = true, trial_pending_ = false;  // a trial not yet committed: it was rejected
  AdaptiveCounts counts_;
  // Fixed-step continuation: the step continues from where the last one ended.
  const double* cached_y_ = nullptr;
  double cached_t_ = 0.0;
};

}  // namespace stiffbench
