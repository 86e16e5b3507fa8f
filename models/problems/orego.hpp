// OREGO: the Oregonator, Field & Noyes' model of the Belousov–Zhabotinskii reaction (Field &
// Noyes 1974), as in Hairer & Wanner, Solving ODEs II, §IV.10 and the IVP test set of Mazzia &
// Magherini (problem "orego"):
//   y1' = s (y2 + y1 (1 - q y1 - y2))
//   y2' = (y3 - (1 + y1) y2) / s
//   y3' = w (y1 - y3)
// with the literature constants s = 77.27, w = 0.161, q = 8.375e-6 (parameters s > 0, w >= 0,
// q >= 0), y(0) = (1, 2, 3) and the literature time span [0, 360] (the registry's t_end). The
// solution is periodic with period about 303 and sharp spikes (y1 up to about 1.2e5 near
// t = 20.5 and 323.3; y2 between about 5e-3 and 1.8e3, y3 up to about 3e4): fixed-step runs
// need small steps through the spikes.
// Reference solution at t = 360 (Hairer–Wanner; IVP test set "orego"): y = (0.1000814870318523e+01,
// 0.1228178521549917e+04, 0.1320554942846706e+03); CVODE BDF (rtol 1e-13) on this class
// reproduces it to 4e-11 relative (5e-10 at rtol 1e-12: the spikes make the end state sensitive).
// No linear invariant.
// Jacobian (fixed pattern, 7 entries; ∂f1/∂y3 = ∂f3/∂y2 = 0 structurally):
//   [[s (1 - 2 q y1 - y2),  s (1 - y1),   0  ],
//    [-y2 / s,             -(1 + y1)/s,   1/s],
//    [ w,                   0,           -w  ]].
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius.
// Non-negative components: all three (scaled concentrations of HBrO2, Br⁻ and Ce(IV) in Field &
// Noyes' model). Where y >= 0 and y_i = 0, f_i is s y2, y3/s, w y1 >= 0, so y(t) >= 0 for every
// s > 0, w, q >= 0 (the positivity criterion of core/ode_system.hpp).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Orego final : public OdeSystem {
 public:
  Orego(double s, double w, double q);

  std::string name() const override { return "orego"; }
  std::optional<PublishedSolution> published_solution() const override;
  Index dimension() const override { return 3; }
  Vec initial_state() const override { return Vec{{1.0, 2.0, 3.0}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::optional<double> stiffness(double t, CVecRef y) const override;
  std::vector<Index> nonnegative_components() const override { return all_components(3); }

  // End of the literature time span (Hairer–Wanner §IV.10; IVP test set).
  double literature_end_time() const { return 360.0; }
  std::optional<double> end_time() const override { return literature_end_time(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  double s_, w_, q_;
};

}  // namespace stiffbench
