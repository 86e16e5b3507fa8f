// Diagonally implicit Runge–Kutta methods as tableau data read by one generic stepper, and
// BDF2. Stage i solves z_i = y + h Σ_{j<i} a_ij k_j + h a_ii f(t + c_i h, z_i) by Newton
// (ImplicitCore) and sets k_i = (z_i - ψ_i)/(h a_ii) from the converged iterate; a_ii = 0
// stages are explicit. y⁺ = y + h Σ b_i k_i.
//
// Tableaux (Hairer & Wanner, Solving ODEs II, §IV.3–IV.6):
//   backward_euler     A = [1], b = [1]                         order 1, L-stable
//   implicit_midpoint  A = [½], b = [1]                         order 2, A-stable, symplectic
//   trapezoidal        A = [[0,0],[½,½]], b = [½,½]             order 2, A-stable (|R(∞)| = 1)
//   sdirk2             γ = 1 - 1/√2: A = [[γ,0],[1-γ,γ]], b = [1-γ,γ]   order 2, L-stable
//   sdirk3             Alexander (1977): γ = 0.4358665215084590 (root of x³ - 3x² + 3x/2 - 1/6
//                      in (1/6, 1/2)), τ = (1+γ)/2, b1 = -(6γ² - 16γ + 1)/4,
//                      b2 = (6γ² - 20γ + 5)/4: A = [[γ,0,0],[τ-γ,γ,0],[b1,b2,γ]]
//                                                                order 3, L-stable
// The L-stable ones are stiffly accurate (b = last row of A), so y⁺ = z_s exactly.
//
// bdf2: y_{n+1} - 4/3 y_n + 1/3 y_{n-1} = 2/3 h f(t_{n+1}, y_{n+1}), order 2, L-stable
//   (A-stable with R(∞) = 0). Start-up: the first step (and any step after h changes or after
//   y was changed from outside, e.g. by a constraint projection) is one sdirk2 step, whose
//   O(h³) local error keeps global order 2. Predictor: linear extrapolation 2y_n - y_{n-1}.
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/tableau.hpp"
#include "integrators/implicit/implicit_core.hpp"

namespace stiffbench {

const std::vector<ButcherTableau>& implicit_tableaux();
const ButcherTableau& implicit_tableau(const std::string& name);

// One DIRK step with a shared ImplicitCore (used by DirkIntegrator and by BDF2's start-up).
class DirkStepper {
 public:
  explicit DirkStepper(ButcherTableau tableau) : tableau_(std::move(tableau)) {}
  void reset(Index n);
  Status step(ImplicitCore& core, const OdeSystem& sys, double t, VecRef y, double h,
              SolveStats& stats);
  const ButcherTableau& tableau() const { return tableau_; }

 private:
  ButcherTableau tableau_;
  Mat k_;
  Vec psi_, z_, fz_;
};

class DirkIntegrator final : public Integrator {
 public:
  DirkIntegrator(ButcherTableau tableau, std::string description, ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(stepper_.tableau());
  }
  const ImplicitCore& core() const { return core_; }

 private:
  DirkStepper stepper_;
  ImplicitCore core_;
};

class Bdf2Integrator final : public Integrator {
 public:
  explicit Bdf2Integrator(ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return multistep_stability({1.0 / 3.0, -4.0 / 3.0, 1.0}, {0.0, 0.0, 2.0 / 3.0});
  }

 private:
  ImplicitCore core_;
  DirkStepper startup_;
  Vec y_prev_, y_last_, psi_, z_, fz_;
  double h_last_ = 0.0;
  bool started_ = false;
};

}  // namespace stiffbench
