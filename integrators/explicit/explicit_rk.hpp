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
// driver's blow-up check: last_step_max_norm()). On a MechanicalSystem the stages call
// acceleration() and keep their velocities as the x-part of k (no copy of v per stage; bitwise
// the same results, see step()).
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/tableau.hpp"

namespace stiffbench {

class ExplicitRungeKutta final : public Integrator {
 public:
  // Vector updates of at least this many entries run over OpenMP threads.
  static constexpr Index kParallelEntries = 50000;

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
  ButcherTableau tableau_;
  Mat k_;     // n × s stage derivatives
  Vec ytmp_;  // stage argument
  // Non-zero coefficients of each row of A (rows 0..s-1) and of b (row s): stage indices and
  // the coefficients' values, fixed at construction (no allocation per step).
  std::vector<std::vector<int>> terms_;
  std::vector<std::vector<double>> coefs_;
  std::vector<const double*> cols_;  // workspace: the stage columns of one combination
  std::vector<double> scaled_;       // workspace: h times the coefficients
  double last_norm_ = 0.0;           // ‖y‖∞ after the last step (NaN when an entry is NaN)
  bool norm_valid_ = false;
};

}  // namespace stiffbench
