// One generic explicit Runge–Kutta stepper over any explicit Butcher tableau:
//   k_i = f(t + c_i h, y + h Σ_{j<i} a_ij k_j),   y⁺ = y + h Σ_i b_i k_i.
// Exactly `stages` f evaluations per step; the stage matrix is allocated in reset().
#pragma once

#include "core/integrator.hpp"
#include "core/tableau.hpp"

namespace stiffbench {

class ExplicitRungeKutta final : public Integrator {
 public:
  ExplicitRungeKutta(ButcherTableau tableau, std::string description);

  const ButcherTableau& tableau() const { return tableau_; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(tableau_);
  }

 private:
  ButcherTableau tableau_;
  Mat k_;     // n × s stage derivatives
  Vec ytmp_;  // stage argument
};

}  // namespace stiffbench
