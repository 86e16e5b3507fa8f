// BDF2, the two-step backward differentiation formula:
//   y_{n+1} - 4/3 y_n + 1/3 y_{n-1} = 2/3 h f(t_{n+1}, y_{n+1}), order 2, L-stable
//   (A-stable with R(∞) = 0). Start-up: the first step (and any step after h changes or after
//   y was changed from outside, e.g. by a constraint projection) is one sdirk2 step
//   (DirkStepper, dirk.hpp), whose O(h³) local error keeps global order 2. Predictor: linear
//   extrapolation 2y_n - y_{n-1}. Each step solves one stage equation by Newton (ImplicitCore).
#pragma once

#include "core/integrator.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/solvers/newton.hpp"

namespace stiffbench {

class Bdf2Integrator final : public Integrator {
 public:
  explicit Bdf2Integrator(ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
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
