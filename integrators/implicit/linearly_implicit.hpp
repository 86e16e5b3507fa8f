// Linearly implicit methods: one Jacobian and linear solves per step, no Newton loop.
//
// semi_implicit_euler (linearly implicit Euler, Hairer–Wanner II §IV.9):
//   (I - hJ) Δy = h f(t, y) + h² f_t,  y⁺ = y + Δy,  J = ∂f/∂y(t, y): the method applied to
//   the autonomised system (the h² f_t term, by a forward difference in t, only for
//   non-autonomous models). Order 1, L-stable on linear problems; one f evaluation (two when
//   non-autonomous), one Jacobian, one factorisation and one solve per step. It is the
//   one-stage Rosenbrock method with γ = 1.
//
// Rosenbrock methods (Hairer–Wanner II §IV.7, eq. (7.4)), as tableau data:
//   (I - hγJ) k_i = h f(t + α_i h, y + Σ_{j<i} α_ij k_j) + γ_i h² f_t + hJ Σ_{j<i} γ_ij k_j,
//   y⁺ = y + Σ b_i k_i,   γ_i = Σ_{j<=i} γ_ij,  α_i = Σ_j α_ij.
//   f_t = ∂f/∂t by a forward difference in t (one extra f evaluation) unless the model is
//   autonomous.
// rosenbrock2 = ROS2 of Verwer, Spee, Blom & Hundsdorfer (SIAM J. Sci. Comput. 20, 1999):
//   γ = 1 + 1/√2, α21 = 1, γ21 = -2γ, b = (½, ½). Order 2, L-stable (R(∞) = 0).
#pragma once

#include "core/integrator.hpp"
#include "integrators/implicit/implicit_core.hpp"

namespace stiffbench {

class SemiImplicitEuler final : public Integrator {
 public:
  explicit SemiImplicitEuler(ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return rosenbrock_stability(Mat::Zero(1, 1), Mat::Ones(1, 1), Vec::Ones(1));
  }

 private:
  ImplicitCore core_;
  Vec f_, dy_, ft_, rhs_;
};

struct RosenbrockTableau {
  std::string name;
  int order = 0;
  double gamma = 0;  // γ_ii (the same for all stages)
  Mat alpha;         // strictly lower
  Mat gamma_lower;   // γ_ij, j < i (strictly lower)
  Vec b;
};

const RosenbrockTableau& rosenbrock2_tableau();

class Rosenbrock final : public Integrator {
 public:
  Rosenbrock(RosenbrockTableau tableau, std::string description, ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return rosenbrock_stability(
        tab_.alpha, tab_.gamma_lower + tab_.gamma * Mat::Identity(tab_.b.size(), tab_.b.size()),
        tab_.b);
  }

 private:
  RosenbrockTableau tab_;
  ImplicitCore core_;
  Mat k_;
  Vec u_, f_, ft_, rhs_, sum_, jv_;
};

}  // namespace stiffbench
