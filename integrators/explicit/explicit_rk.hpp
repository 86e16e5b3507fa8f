// One generic explicit Runge–Kutta stepper over any explicit Butcher tableau:
//   k_i = f(t + c_i h, y + h Σ_{j<i} a_ij k_j),   y⁺ = y + h Σ_i b_i k_i.
// Exactly `stages` f evaluations per step; the stage matrix is allocated in reset().
//
// Each stage argument and the final update are one fused pass over the entries (out_e = y_e +
// Σ_j (h a_ij) k_je, the terms added left to right, zero coefficients skipped: the same
// operations per entry as a sequence of axpy passes), over OpenMP threads when the system has at
// least kParallelEntries entries. The per-entry arithmetic does not depend on the thread count,
// so results are bitwise the same for any number of threads. A stage whose row of A is zero (the
// first) evaluates f at y itself, without a copy. The final update also takes ‖y⁺‖∞ (the
// driver's blow-up check: last_step_max_norm()).
//
// On a MechanicalSystem (y = [x; v], f = [v; a]) the method is written in its accelerations
// A_i = a(t + c_i h, X_i, V_i) alone: with V_j = v + h Σ_k a_jk A_k,
//   X_i = x + h (Σ_j a_ij) v + h² Σ_k (A²)_ik A_k,   V_i = v + h Σ_j a_ij A_j,
//   x⁺ = x + h (Σ_i b_i) v + h² Σ_k (bA)_k A_k,      v⁺ = v + h Σ_i b_i A_i,
// the same stage values as the first-order form in exact arithmetic (the rounding differs: the
// test compares within a bound). Each stage forms X_i and V_i in one pass over the entries, and
// V_i only when a depends on v (velocity_dependent()); the final update is one pass too. A
// stage position may be formed in place from the previous one (X_i = X_j + h (r_i - r_j) v +
// h² Σ_k ((A²)_ik - (A²)_jk) A_k) where that reads no more vectors: rk4's X_3 = X_2 + (h²/4) A_1.
// For rk4 without damping that is 18 vector streams a step instead of the first-order form's 30,
// and one write fewer to a buffer it has not read.
// Each of these passes runs inside the evaluation before it (MechanicalSystem::
// acceleration_in_ranges): on each range of dofs as soon as the system has finished it, while
// that range's accelerations and stage values are still in cache (MassSpringNetwork: each of its
// partitions of points). The per-entry arithmetic is the same wherever a pass runs, so the bits
// do not depend on the system's ranges (the test compares with passes after whole evaluations).
// A system that offers an AccelerationChain (core/fused_evaluation.hpp; MassSpringNetwork's
// partitions) gets the whole step as a wavefront over its blocks instead (explicit_rk.cpp,
// chained_stages), when every row after the first has terms and OpenMP has at most 2 threads: each
// block's stage values are formed right after its stage is evaluated, and only about s + 1 blocks'
// vectors are in use at a time, so they stay in cache. The same bits (the tests compare).
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"

namespace stiffbench {

class ExplicitRungeKutta final : public Integrator {
 public:
  // Vector updates of at least this many entries run over OpenMP threads.
  static constexpr Index kParallelEntries = 50000;
  // A chained step (header) runs its two sweeps on two threads from this many dofs: the
  // network's own parallel threshold (2048 points in 3D), so a cloth whose evaluation used two
  // threads before the chain still does (a gain below it is not measured).
  static constexpr Index kParallelChainDofs = 6144;

  ExplicitRungeKutta(ButcherTableau tableau, std::string description);

  const ButcherTableau& tableau() const { return tableau_; }
  const ButcherTableau* butcher_tableau() const override { return &tableau_; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(tableau_);
  }
  std::optional<double> last_step_max_norm() const override {
    return norm_valid_ ? std::optional<double>(last_norm_) : std::nullopt;
  }

 private:
  Status step_mechanical(const MechanicalSystem& mech, double t, VecRef y, double h);
  ButcherTableau tableau_;
  Mat k_;     // n × s stage derivatives
  Vec ytmp_;  // stage argument
  // Non-zero coefficients of each row of A (rows 0..s-1) and of b (row s): stage indices and
  // the coefficients' values, fixed at construction (no allocation per step).
  std::vector<std::vector<int>> terms_;
  std::vector<std::vector<double>> coefs_;
  std::vector<const double*> cols_;  // workspace: the stage columns of one combination
  std::vector<double> scaled_;       // workspace: h times the coefficients
  // The mechanical path's position rows 0..s (header): the coefficient on v (Σ_j a_ij, or Σ b),
  // and the stages k with their (A²)_ik (or (bA)_k), non-zero only; and their workspaces.
  std::vector<double> x_v_coef_;
  std::vector<std::vector<int>> x_terms_;
  std::vector<std::vector<double>> x_coefs_;
  // The mechanical path's workspaces of rows 0..s: the columns and h-scaled coefficients of the
  // position and the velocity combination, and the position's column count.
  std::vector<std::vector<const double*>> row_x_cols_, row_v_cols_;
  std::vector<std::vector<double>> row_x_scaled_, row_v_scaled_;
  std::vector<int> row_x_count_;
  // Rows whose position is formed from the previous stage position in place (constructor): for
  // them x_v_coef_, x_terms_ and x_coefs_ hold the differences to that row.
  std::vector<bool> x_from_prev_;
  double last_norm_ = 0.0;  // ‖y‖∞ after the last step (NaN when an entry is NaN)
  bool norm_valid_ = false;
};

}  // namespace stiffbench
