// Störmer–Verlet in its two historical forms with history between steps. Both need a(t, x)
// independent of v (check_compatible refuses damped systems with a clear message) and both
// cost one acceleration evaluation per step after the first (two in the first).
//
// verlet — two-step position Verlet (the seed's form):  x_{n+1} = 2x_n - x_{n-1} + h² a(x_n).
//   Start-up: x_1 = x_0 + h v_0 + ½h² a(x_0) (Taylor; local error O(h³), keeps order 2).
//   Reported velocity: the central difference v_n = (x_{n+1} - x_{n-1})/(2h), computed at the
//   end of the step that produces x_n by looking one step ahead with the same recurrence:
//   x_{n+1} - x_{n-1} = 2(x_n - x_{n-1}) + h² a(x_n), so v_n = (x_n - x_{n-1})/h + ½h a(x_n).
//   The input velocity is read only at start-up.
//
// leapfrog — kick-drift with velocities at half steps:
//   v_{n+1/2} = v_{n-1/2} + h a(x_n),   x_{n+1} = x_n + h v_{n+1/2}.
//   Start-up half step: v_{1/2} = v_0 + ½h a(x_0). The staggered v_{n+1/2} is the integrator's
//   internal state; it reports the synchronised velocity v_{n+1} = v_{n+1/2} + ½h a(x_{n+1})
//   (second order at t_{n+1}, so the reported state is comparable with other methods).
//
// In exact arithmetic both produce the velocity Verlet trajectory; they differ in round-off
// and in what they store. Either restarts (start-up step again) when h changes or when the
// state passed in is not the one it returned: another storage (y.data()) or, on systems with
// constraints (whose projection by the driver moves x between steps), another position (a copy
// and a compare of x per step there only). Otherwise the Integrator contract (y is what the
// previous step left) holds and no whole vector is copied or compared. Each vector update is one
// fused pass, over OpenMP threads above 50,000 entries (the same arithmetic per entry, so the
// results do not depend on the thread count).
#pragma once

#include "core/integrator.hpp"

namespace stiffbench {

class PositionVerlet final : public Integrator {
 public:
  PositionVerlet();
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return kick_drift_stability({"velocity_verlet", {0.5, 0.5}, {1.0, 0.0}, 2});
  }

 private:
  const MechanicalSystem* mech_ = nullptr;
  Vec x_prev_, x_last_, acc_;  // x_last_: constrained systems only
  const double* y_last_ = nullptr;
  double h_last_ = 0.0;
  bool started_ = false;
};

class Leapfrog final : public Integrator {
 public:
  Leapfrog();
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return kick_drift_stability({"velocity_verlet", {0.5, 0.5}, {1.0, 0.0}, 2});
  }

 private:
  const MechanicalSystem* mech_ = nullptr;
  Vec v_half_, x_last_, acc_;  // x_last_: constrained systems only
  const double* y_last_ = nullptr;
  double h_last_ = 0.0;
  bool started_ = false;
};

}  // namespace stiffbench
