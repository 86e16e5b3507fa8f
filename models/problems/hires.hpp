// HIRES: "High Irradiance RESponse" of photomorphogenesis (Schäfer 1975), as in Hairer & Wanner,
// Solving ODEs II, §IV.10 and the IVP test set of Mazzia & Magherini (problem "hires"):
//   y1' = -1.71 y1 + 0.43 y2 + 8.32 y3 + 0.0007
//   y2' =  1.71 y1 - 8.75 y2
//   y3' = -10.03 y3 + 0.43 y4 + 0.035 y5
//   y4' =  8.32 y2 + 1.71 y3 - 1.12 y4
//   y5' = -1.745 y5 + 0.43 y6 + 0.43 y7
//   y6' = -280 y6 y8 + 0.69 y4 + 1.71 y5 - 0.43 y6 + 0.69 y7
//   y7' =  280 y6 y8 - 1.81 y7
//   y8' = -280 y6 y8 + 1.81 y7
// y(0) = (1, 0, 0, 0, 0, 0, 0, 0.0057); literature time span [0, 321.8122] (the registry's
// t_end, used when --t-end is omitted). No parameters: the literature fixes all 20 constants.
// Reference solution at t = 321.8122 (IVP test set "hires"): y = (0.7371312573325668e-3,
// 0.1442485726316185e-3, 0.5888729740967575e-4, 0.1175651343283149e-2, 0.2386356198831331e-2,
// 0.6238968252742796e-2, 0.2849998395185769e-2, 0.2850001604814231e-2); CVODE BDF (rtol 1e-13)
// on this class reproduces it to 3e-11 relative, tests/models/test_stiff_problems.cpp with
// sdirk3 to 3e-8.
// Invariant "y7+y8" (= 0.0057): y7' + y8' = 0 identically. It is the only linear one: asking
// wᵀf ≡ 0 monomial by monomial, the constant 0.0007 gives w1 = 0, then the y1, y2, y3, y4 and y5
// terms give w2 = w4 = w3 = w6 = w5 = 0, and the y7 terms give w7 = w8.
// Jacobian: 25 fixed entries (the linear coefficients plus ±280 y8, ±280 y6 in rows 6–8).
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius.
// Non-negative components: all eight (the concentrations of the eight reactants, IVP test set).
// Where y >= 0 and y_i = 0 every f_i above is a sum of non-negative terms (y6' = 0.69 y4 +
// 1.71 y5 + 0.69 y7, y7' = 280 y6 y8, y8' = 1.81 y7, ...), and y(0) >= 0, so y(t) >= 0 (the
// positivity criterion of core/ode_system.hpp).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Hires final : public OdeSystem {
 public:
  // End of the literature time span (Hairer–Wanner §IV.10; IVP test set).
  double literature_end_time() const { return 321.8122; }
  std::optional<double> end_time() const override { return literature_end_time(); }

  std::string name() const override { return "hires"; }
  std::optional<PublishedSolution> published_solution() const override;
  Index dimension() const override { return 8; }
  Vec initial_state() const override;
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::vector<Invariant> invariants() const override;
  std::vector<Index> nonnegative_components() const override { return all_components(8); }
  std::optional<double> stiffness(double t, CVecRef y) const override;

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
};

}  // namespace stiffbench
