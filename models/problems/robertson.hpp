// Robertson's chemical kinetics problem ROBER (Robertson 1966; Hairer & Wanner, Solving ODEs II,
// §IV.10; IVP test set of Mazzia & Magherini, problem "rober"):
//   y1' = -k1 y1 + k3 y2 y3
//   y2' =  k1 y1 - k3 y2 y3 - k2 y2²
//   y3' =  k2 y2²
// with the literature rate constants k1 = 0.04, k2 = 3e7, k3 = 1e4 (parameters k1, k2, k3, each
// >= 0), y(0) = (1, 0, 0) and the literature time span [0, 1e11] (the registry's t_end: the
// CLI runs to it when --t-end is omitted). y2 peaks at about 3.65e-5 near t = 4.5e-3; late in the
// run J has an eigenvalue near -k3 = -1e4 (trace -k1 - k3 y3 - 2 k2 y2 with y3 → 1).
// Reference solution at t = 1e11 (IVP test set "rober"): y = (0.2083340149701255e-07,
// 0.8333360770334713e-13, 0.9999999791665050e+00). CVODE BDF (rtol 1e-13, atol 1e-20) on this
// class reproduces it to 3e-11 relative; tests/models/test_stiff_problems reaches it to 1e-8 with
// sdirk3 and checks the late-time asymptotics y2/y1 → k1/k3, y1 t → (1 + k1/k3) k3²/(k1² k2).
// Invariant "mass" = y1 + y2 + y3 (= 1): the three right-hand sides sum to zero, so every
// Runge–Kutta and linear multistep method keeps it to round-off.
// Jacobian (fixed pattern, 7 entries; (3,1) and (3,3) are structurally zero):
//   [[-k1,  k3 y3,               k3 y2],
//    [ k1, -k3 y3 - 2 k2 y2,    -k3 y2],
//    [  0,  2 k2 y2,                 0]].
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius of J (exact, 0.04,
// at y(0)).
// Non-negative components: all three (the concentrations of the three species). Where y >= 0
// and y_i = 0, f_i is k3 y2 y3, k1 y1, k2 y2² >= 0, so y(t) >= 0 for every k1, k2, k3 >= 0 (the
// positivity criterion of core/ode_system.hpp).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Robertson final : public OdeSystem {
 public:
  Robertson(double k1, double k2, double k3);

  // End of the literature time span (Hairer–Wanner §IV.10; IVP test set).
  double literature_end_time() const { return 1e11; }
  std::optional<double> end_time() const override { return literature_end_time(); }

  std::string name() const override { return "robertson"; }
  // Only for the standard rate constants (0.04, 3e7, 1e4).
  std::optional<PublishedSolution> published_solution() const override;
  Index dimension() const override { return 3; }
  Vec initial_state() const override { return Vec{{1.0, 0.0, 0.0}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::vector<Invariant> invariants() const override;
  std::vector<Index> nonnegative_components() const override { return all_components(3); }
  std::optional<double> stiffness(double t, CVecRef y) const override;

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  double k1_, k2_, k3_;
};

}  // namespace stiffbench
