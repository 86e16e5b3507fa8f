// POLLU: the air-pollution model of the Dutch National Institute of Public Health and the
// Environment (RIVM), Verwer, "Gauss–Seidel iteration for stiff ODEs from chemical kinetics",
// SIAM J. Sci. Comput. 15 (1994), as in the IVP test set of Mazzia & Magherini (problem
// "pollu"). 20 species, 25 reactions with mass-action rates r_j:
//   r1  = k1  y1         NO2 → NO + O3P            r14 = k14 y1 y6      NO2 + OH → HNO3
//   r2  = k2  y2 y4      NO + O3 → NO2             r15 = k15 y3         O3P → O3
//   r3  = k3  y5 y2      HO2 + NO → NO2 + OH       r16 = k16 y4         O3 → O1D
//   r4  = k4  y7         HCHO → 2 HO2 + CO         r17 = k17 y4         O3 → O3P
//   r5  = k5  y7         HCHO → CO                 r18 = k18 y16        O1D → 2 OH
//   r6  = k6  y7 y6      HCHO + OH → HO2 + CO      r19 = k19 y16        O1D → O3P
//   r7  = k7  y9         ALD → MEO2 + HO2 + CO     r20 = k20 y17 y6     SO2 + OH → SO4 + HO2
//   r8  = k8  y9 y6      ALD + OH → C2O3           r21 = k21 y19        NO3 → NO
//   r9  = k9  y11 y2     C2O3 + NO → NO2 + MEO2 + CO2   r22 = k22 y19   NO3 → NO2 + O3P
//   r10 = k10 y11 y1     C2O3 + NO2 → PAN          r23 = k23 y1 y4      NO2 + O3 → NO3
//   r11 = k11 y13        PAN → C2O3 + NO2          r24 = k24 y19 y1     NO3 + NO2 → N2O5
//   r12 = k12 y10 y2     MEO2 + NO → CH3O + NO2    r25 = k25 y20        N2O5 → NO3 + NO2
//   r13 = k13 y14        CH3O → HCHO + HO2
// Species y1..y20: NO2, NO, O3P, O3, HO2, OH, HCHO, CO, ALD, MEO2, C2O3, CO2, PAN, CH3O, HNO3,
// O1D, SO2, SO4, NO3, N2O5. y_i' = Σ_j ν_ij r_j with the net stoichiometry of the reactions
// above (e.g. y1' = -r1 - r10 - r14 - r23 - r24 + r2 + r3 + r9 + r11 + r12 + r22 + r25).
// Rate constants k1..k25 = 0.35, 26.6, 1.23e4, 8.6e-4, 8.2e-4, 1.5e4, 1.3e-4, 2.4e4, 1.65e4,
// 9e3, 0.022, 1.2e4, 1.88, 1.63e4, 4.8e6, 3.5e-4, 0.0175, 1e8, 4.44e11, 1240, 2.1, 5.78,
// 0.0474, 1780, 3.12 (fixed, as in the literature; no parameters).
// y(0): y2 = 0.2, y4 = 0.04, y7 = 0.1, y8 = 0.3, y9 = 0.01, y17 = 0.007, all others 0.
// Literature time span [0, 60] (the registry's t_end).
// Reference solution at t = 60 (IVP test set "pollu"; 16 digits there, listed in
// tests/models/test_stiff_problems.cpp), y1 = 0.5646255480022769e-01, y16 = 0.4352846369330103e-17;
// CVODE BDF (rtol 1e-13) on this class reproduces all 20 components to 1.1e-12 relative, the test
// with sdirk3 to 3e-8.
// Invariants (atom balances of the lumped mechanism; the left null space of the rate-weighted
// stoichiometry is exactly these three, computed in exact arithmetic):
//   "nitrogen" = y1 + y2 + y13 + y15 + y19 + 2 y20                     (= 0.2)
//   "carbon"   = y7 + y8 + 2 y9 + y10 + 2 y11 + y12 + 2 y13 + y14      (= 0.42)
//   "sulfur"   = y17 + y18                                              (= 0.007)
// Jacobian: Σ_j ν_j ∂r_j/∂y with a fixed pattern (every species a reaction changes × every
// reactant of that reaction; entries where contributions cancel stay in the pattern).
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius (dominated by
// k18 + k19 ≈ 4.44e11 from O1D).
// Non-negative components: all twenty (species concentrations). Mass action: every reaction that
// consumes a species has it in its rate, so f_i >= 0 where y >= 0 and y_i = 0, and y(0) >= 0:
// y(t) >= 0 (the positivity criterion of core/ode_system.hpp).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class Pollution final : public OdeSystem {
 public:
  std::string name() const override { return "pollution"; }
  Index dimension() const override { return 20; }
  Vec initial_state() const override;
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::vector<Invariant> invariants() const override;
  std::vector<Index> nonnegative_components() const override { return all_components(20); }
  std::string component_name(Index i) const override;  // the species above: "NO2", ...
  std::optional<double> stiffness(double t, CVecRef y) const override;

  // End of the literature time span (IVP test set).
  double literature_end_time() const { return 60.0; }
  std::optional<double> end_time() const override { return literature_end_time(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
};

}  // namespace stiffbench
