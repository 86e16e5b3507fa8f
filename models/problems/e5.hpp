// E5: a chemical pyrolysis problem from the stiff test set of Enright, Hull & Lindberg (BIT 15,
// 1975), as in Hairer & Wanner, Solving ODEs II, §IV.10 (problem E5):
//   y1' = -A y1 - B y1 y3
//   y2' =  A y1 - M C y2 y3
//   y3' =  A y1 - B y1 y3 - M C y2 y3 + C y4
//   y4' =  B y1 y3 - C y4
// with the literature constants A = 7.89e-10, B = 1.1e7, C = 1.13e3, M = 1e6 (parameters a, b,
// c, m, each >= 0), y(0) = (1.76e-3, 0, 0, 0) and the literature time span [0, 1e13] (the
// registry's t_end). y2, y3, y4 never exceed about 1.5e-10 (y2 and y4 peak near t = 300) while y1
// starts at 1.76e-3 and decays by many orders of magnitude after t ≈ 1e5 (7.5e-6 at 1e5, 3e-14
// at 1e9), so error measures need per-component or tiny absolute tolerances (magnitudes from
// CVODE runs of this class). No reference solution at 1e13 is given here: CVODE BDF at rtol
// 1e-12 with atol from 1e-24 to 1e-36 gave inconsistent values there (y2 - y3 - y4 drifted to
// the size of the components, about 1e-21).
// Invariant "y2-y3-y4" (= 0): y2' - y3' - y4' = 0 identically. It is the only linear one:
// asking wᵀf ≡ 0 monomial by monomial, the y2y3 terms give w2 = -w3, the y4 terms w3 = w4,
// the y1y3 terms w4 = w1 + w3, so w1 = 0 and the y1 terms then hold.
// Jacobian (fixed pattern, 12 entries):
//   [[-A - B y3,   0,        -B y1,            0],
//    [ A,         -M C y3,   -M C y2,          0],
//    [ A - B y3,  -M C y3,   -B y1 - M C y2,   C],
//    [ B y3,       0,         B y1,           -C]].
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius.
// Non-negative components: all four (concentrations of the pyrolysis' species). Where y >= 0 and
// y_i = 0, f_i is 0, A y1, A y1 + C y4, B y1 y3 >= 0, so y(t) >= 0 for every A, B, C, M >= 0 (the
// positivity criterion of core/ode_system.hpp).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class E5 final : public OdeSystem {
 public:
  E5(double a, double b, double c, double m);

  std::string name() const override { return "e5"; }
  Index dimension() const override { return 4; }
  Vec initial_state() const override { return Vec{{1.76e-3, 0.0, 0.0, 0.0}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::vector<Invariant> invariants() const override;
  std::vector<Index> nonnegative_components() const override { return all_components(4); }
  std::optional<double> stiffness(double t, CVecRef y) const override;

  // End of the literature time span (Hairer–Wanner §IV.10).
  double literature_end_time() const { return 1e13; }
  std::optional<double> end_time() const override { return literature_end_time(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  double a_, b_, c_, m_;
};

}  // namespace stiffbench
