// Methods as data: Butcher tableaux for Runge–Kutta methods and kick/drift coefficients for
// symplectic splitting methods of mechanical systems. A tableau checks itself: row sums,
// order conditions (rooted trees up to order 8, core/theory/method_analysis.hpp) and its stability
// function R(z).
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

struct ButcherTableau {
  std::string name;
  Mat a;  // s×s stage matrix
  Vec b;  // weights
  Vec c;  // nodes, c = A·1
  int order = 0;
  Vec b_embedded = Vec();  // optional embedded weights (size 0: none)
  int embedded_order = 0;
  // First same as last: the last stage is evaluated at the new solution (c_s = 1 and the last
  // row of A equals b), so an explicit method reuses it as the next step's first stage.
  bool fsal = false;
  // Claimed stage order q (C(q): Σ_j a_ij c_j^(k-1) = c_i^k / k for k <= q); 0: not claimed.
  int stage_order = 0;

  int stages() const { return static_cast<int>(b.size()); }
  bool is_explicit() const;  // strictly lower triangular A

  // max_i |c_i - Σ_j a_ij|.
  double row_sum_defect() const;

  // R(z) = 1 + z bᵀ (I - zA)⁻¹ 1: one step of the method on y' = λy multiplies y by R(hλ).
  std::complex<double> stability(std::complex<double> z) const;

  // Largest |bᵀΦ(τ) - 1/γ(τ)| over the rooted trees τ with exactly p vertices (Butcher's
  // order conditions; Hairer–Nørsett–Wanner I, §II.2). Defined for 1 <= p <= 8.
  double order_defect(int p) const { return order_defect(b, p); }
  double order_defect(const Vec& weights, int p) const;

  // Largest p <= max_order with every condition of order <= p met to tol.
  int satisfied_order(double tol = 1e-12, int max_order = 6) const;
  int satisfied_order(const Vec& weights, double tol = 1e-12, int max_order = 6) const;

  // Largest q <= stages() with the simplifying condition C(q) met to tol (0 when the nodes are
  // not the row sums).
  int satisfied_stage_order(double tol = 1e-12) const;

  // Whether the coefficients are first same as last: the last row of A equals b to 1e-12 (and
  // so c_s = 1 when the row sums are 1); for an explicit tableau this includes b_s = 0, so the
  // last stage is f at the new solution.
  bool coefficients_fsal() const;

  // What a tableau must satisfy, checked when a stepper is built from it.
  enum class Shape { any, explicit_rk, diagonally_implicit };

  // Checks the tableau against what it claims and completes it; BadInput naming the tableau and
  // the first defect found:
  //   sizes: b has s >= 1 entries, A is s×s, c has s entries, b_embedded 0 or s; all finite;
  //   c: when empty it is completed from the row sums (c = A·1), otherwise it must equal them
  //     to 1e-12;
  //   shape: explicit_rk needs A strictly lower triangular, diagonally_implicit lower
  //     triangular;
  //   order >= 1 is claimed and every order condition up to min(order, 8) holds to 1e-12 (the
  //     rooted trees of core/theory/method_analysis.hpp; a claim above 8 is checked up to 8), else
  //     the first violated condition is named: "order 3 claimed but the condition of tree
  //     [[t]] (order 3) has residual -0.167"; likewise the embedded weights up to
  //     min(embedded_order, 8), and embedded_order >= 1 with them;
  //   stage_order (when claimed) holds (C(q) to 1e-12);
  //   fsal (when claimed): coefficients_fsal().
  void validate(Shape shape = Shape::any);
  // The same checks without completing c (which must then be given): the first defect as a
  // sentence, empty when there is none.
  std::string defect(Shape shape = Shape::any) const;
};

// An additive (IMEX) Runge–Kutta method for y' = f_E(t, y) + f_I(t, y) (Ascher, Ruuth & Spiteri
// 1997; Kennedy & Carpenter 2003): an explicit tableau (strictly lower triangular A_E) for f_E
// and a diagonally implicit one (lower triangular A_I) for f_I with the same nodes c. Stage i:
//   z_i = y + h Σ_{j<i} (aE_ij kE_j + aI_ij kI_j) + h aI_ii f_I(t + c_i h, z_i),
//   kE_i = f_E(t + c_i h, z_i), kI_i = f_I(t + c_i h, z_i),
//   y⁺ = y + h Σ_i (bE_i kE_i + bI_i kI_i)   (and the embedded ŷ with b̂E, b̂I when given).
// The two tables' b (and b_embedded) may differ (ARS methods have bE ≠ bI); `order` is the
// order of the pair, coupling conditions included (core/theory/method_analysis.hpp checks them).
struct AdditiveTableau {
  std::string name;
  ButcherTableau explicit_table;  // name, order: the pair's; orders of each table alone in them
  ButcherTableau implicit_table;
  int order = 0;
  int embedded_order = 0;  // 0: no embedded pair
  int stages() const { return explicit_table.stages(); }
  bool has_embedded() const {
    return explicit_table.b_embedded.size() > 0 && implicit_table.b_embedded.size() > 0;
  }
};

// Kick/drift splitting for x' = v, v' = a(t, x, v). One step of size h is, for j = 1..s:
//   v ← v + h·kick[j]·a(t_j, x, v);   x ← x + h·drift[j]·v;   t_j = t + h·Σ_{i<j} drift[i].
// Zero kicks cost no evaluation. Each stage is a shear, so the map is symplectic whenever a does
// not depend on v.
struct KickDriftCoefficients {
  std::string name;
  std::vector<double> kick;
  std::vector<double> drift;
  int order = 0;

  int evaluations_per_step() const;  // non-zero kicks
  // Conditions up to order 2: Σ kick = Σ drift = 1 and Σ_j kick_j Σ_{i<j} drift_i = 1/2.
  double order_defect(int p) const;
};

// Rosenbrock method in the form of Hairer & Wanner II, §IV.7, (7.4): stage coefficients α
// (strictly lower), Γ = γI + γ_ij (strictly lower), weights b and optional embedded weights b̂
// (integrators/implicit/rosenbrock.hpp runs it; order_defect is implemented there).
struct RosenbrockTableau {
  std::string name;
  int order = 0;
  double gamma = 0;  // γ_ii (the same for all stages)
  Mat alpha;         // strictly lower
  Mat gamma_lower;   // γ_ij, j < i (strictly lower)
  Vec b;
  Vec b_embedded = Vec();  // optional embedded weights (size 0: none)
  int embedded_order = 0;
  // Claimed W-order: the order kept when an arbitrary matrix W replaces the Jacobian (0: not
  // claimed; core/theory/method_analysis.hpp checks it).
  int w_order = 0;

  Index stages() const { return b.size(); }
  Mat gamma_full() const;  // Γ = gamma_lower + γ I
  // Largest |Σ w_i Φ_i(τ) - 1/γ(τ)| over the rooted trees τ with exactly p vertices (the
  // conditions of HW II §IV.7, see integrators/implicit/rosenbrock.hpp). Defined for 1 <= p <= 6.
  double order_defect(const Vec& weights, int p) const;
};

}  // namespace stiffbench
