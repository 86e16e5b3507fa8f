// Linearly implicit methods: one Jacobian and linear solves per step, no Newton loop.
//
// semi_implicit_euler (linearly implicit Euler, Hairer–Wanner II §IV.9):
//   (I - hJ) Δy = h f(t, y) + h² f_t,  y⁺ = y + Δy,  J = ∂f/∂y(t, y): the method applied to
//   the autonomised system (the h² f_t term, by a forward difference in t, only for
//   non-autonomous models). Order 1, L-stable on linear problems; one f evaluation (two when
//   non-autonomous), one Jacobian, one factorisation and one solve per step. It is the
//   one-stage Rosenbrock method with γ = 1.
//
// Rosenbrock methods (Hairer–Wanner II §IV.7, eq. (7.4)), as tableau data (α, Γ, b, b̂):
//   (I - hγJ) k_i = h f(t + α_i h, y + Σ_{j<i} α_ij k_j) + γ_i h² f_t + hJ Σ_{j<i} γ_ij k_j,
//   y⁺ = y + Σ b_i k_i,  ŷ⁺ = y + Σ b̂_i k_i,   γ_i = Σ_{j<=i} γ_ij,  α_i = Σ_j α_ij.
// The integrator runs the equivalent form without Jacobian products (HW II §IV.7, section
// "Implementation of Rosenbrock-type methods"; the form of their codes ROS4 and RODAS): with u_i =
// Σ_{j<=i} γ_ij k_j,
//   (I - hγJ) u_i = hγ [ f(t + α_i h, y + Σ_{j<i} a_ij u_j) + Σ_{j<i} (c_ij/h) u_j + γ_i h f_t ],
//   y⁺ = y + Σ m_i u_i,   (a_ij) = αΓ⁻¹, (c_ij) = diag(1/γ) - Γ⁻¹, m = bᵀΓ⁻¹, m̂ = b̂ᵀΓ⁻¹,
// so every stage costs one f evaluation and one solve with the one factored matrix I - hγJ.
// A stage whose argument (α row and α_i) equals an earlier stage's reuses that f value (ROS3P's
// stages 2 and 3). J and f_t = ∂f/∂t are taken at (t, y) of the step; f_t (skipped when the model
// is autonomous) by the one-sided second-order difference (-3 f(t) + 4 f(t + δ) - f(t + 2δ))/(2δ),
// δ = max(ε^⅓, ε^⅔ |t|): two extra f evaluations per step, relative error ~1e-11 on an O(1) time
// scale. Its error enters y⁺ as h² times itself per step, so it sets an error floor ∝ h: with a
// forward difference (δ = √ε max(1, |t|)) rodas4 on Prothero–Robinson λ = -1 stalls at ~7e-12
// (observed order -0.5 from h = 0.0125 to 0.00625), with δ = ε^⅓ max(1, |t|) it shows 3.7 there
// (errors ~1e-12), and with this δ it keeps order 4 down to 4e-14
// (tests/integrators/test_rosenbrock.cpp). Order conditions (HW II §IV.7, Table 7.1 up to order 4):
// Σ_i w_i Φ_i(τ) = 1/γ(τ) over the rooted trees τ, where Φ multiplies, along each edge from a
// vertex to its son, by α_jk when the vertex has two or more sons and by β_jk = α_jk + γ_jk (the
// diagonal γ included) when it has exactly one.
//
// The Rosenbrock methods are method files (methods/NAME.toml, kind = "rosenbrock"), compiled
// into the library and parsed by built_in_methods() (integrators/method_file.hpp):
// rosenbrock2 = ROS2 of Verwer, Spee, Blom & Hundsdorfer (SIAM J. Sci. Comput. 20, 1999):
//   γ = 1 + 1/√2, order 2, L-stable (R(∞) = 0). Fixed step only.
// ros3p = ROS3P of Lang & Verwer (BIT 41, 2001): γ = ½ + √3/6, α21 = α31 = 1, γ21 = -1,
//   b = (⅔, 0, ⅓), embedded b̂ = (⅓, ⅓, ⅓) of order 2. Order 3, A-stable with R(∞) = 1 - √3;
//   stages 2 and 3 share their argument (2 f evaluations).
//   Its error estimate vanishes identically on linear autonomous problems with the exact
//   Jacobian: there β_21 = α21 + γ21 = 0 makes k_2 = k_1, and b - b̂ = (⅓, -⅓, 0), so the
//   embedded method has the same stability function as the main one. Adaptive ros3p then
//   controls only the nonlinear and time-dependent parts of the error (on a linear spring chain
//   the steps grow until the output times or h_max limit them): give h_max, or use rodas4.
// rodas4 = RODAS of Hairer & Wanner (Solving ODEs II, 2nd ed., Springer 1996; the coefficients
//   of their code RODAS, METH = 1): 6 stages, γ = ¼, order 4 with an embedded order-3 solution;
//   stiffly accurate (b_i = β_6i, b̂_i = β_5i, α_5 = α_6 = 1: y⁺ is the last stage's argument plus
//   u_6 and the error estimate is u_6), L-stable. Its coefficients are published, and its file
//   written, in the transformed form (a_ij, c_ij, γ, m, m̂); α, Γ, b, b̂ are derived from them
//   (rosenbrock_from_transformed).
//
// Adaptive mode (tableaux with b̂): the error estimate y⁺ - ŷ⁺ = Σ (m_i - m̂_i) u_i is O(h^(p̂+1))
// for an embedded order p̂, so the shared controller (integrators/adaptive/controller.hpp) uses
// k = p̂ + 1 and the starting-step heuristic p = p̂. J, f(t, y) and f_t are evaluated once per
// accepted point and kept across rejected trials (a new h costs a new factorisation only); a
// trial whose factorisation or solve fails, or whose values are not finite, is retried with h/2
// (counted as a rejected step).
// f evaluations: fixed step, (distinct stages) per step, + 2 when non-autonomous, + the
// finite-difference Jacobian's; adaptive, (distinct stages - 1) per trial + (1 + 2·[non-autonomous]
// + Jacobian's) per accepted point, + 1 for the starting-step heuristic.
// No allocation per step on the direct-solver paths: workspaces are sized in reset().
#pragma once

#include "core/integrator.hpp"
#include "integrators/adaptive/controller.hpp"
#include "integrators/solvers/newton.hpp"

namespace stiffbench {

class SemiImplicitEuler final : public Integrator {
 public:
  explicit SemiImplicitEuler(ImplicitOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return rosenbrock_stability(Mat::Zero(1, 1), Mat::Ones(1, 1), Vec::Ones(1));
  }

 private:
  ImplicitCore core_;
  Vec f_, dy_, ft_, rhs_;
};

// struct RosenbrockTableau (α, Γ, b, b̂ as above) is declared in core/theory/tableau.hpp.

// The coefficients the integrator runs on (see above): a = αΓ⁻¹, c = diag(1/γ) - Γ⁻¹ (strictly
// lower), m = bᵀΓ⁻¹, m̂ = b̂ᵀΓ⁻¹, α_i and γ_i.
struct RosenbrockTransformed {
  Mat a, c;
  Vec m, m_embedded, alpha_sum, gamma_sum;
};
RosenbrockTransformed transform(const RosenbrockTableau& t);
// The inverse map, for methods published in the transformed form: Γ = (diag(1/γ) - c)⁻¹, α = aΓ,
// b = Γᵀm, b̂ = Γᵀm̂.
RosenbrockTableau rosenbrock_from_transformed(std::string name, int order, int embedded_order,
                                              double gamma, const Mat& a, const Mat& c,
                                              const Vec& m, const Vec& m_embedded);

// The built-in Rosenbrock tableaux by name (their method files, built_in_method()).
const RosenbrockTableau& rosenbrock2_tableau();
const RosenbrockTableau& ros3p_tableau();
const RosenbrockTableau& rodas4_tableau();

class Rosenbrock final : public Integrator {
 public:
  Rosenbrock(RosenbrockTableau tableau, std::string description, ImplicitOptions opt,
             ControllerOptions control = {});
  const RosenbrockTableau& tableau() const { return tab_; }
  const RosenbrockTableau* rosenbrock_tableau() const override { return &tab_; }
  bool supports_adaptive() const override { return tab_.b_embedded.size() > 0; }
  std::optional<double> absolute_tolerance() const override { return control_.atol; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return rosenbrock_stability(tab_.alpha, tab_.gamma_full(), tab_.b);
  }

 private:
  void restart_state(double t0);  // what reset() and restart() clear
  // f(t, y) into fs_.col(0), J and (non-autonomous) f_t at (t, y).
  void linearise(const OdeSystem& sys, double t, CVecRef y, SolveStats& stats);
  // The stages of a step of size h from the linearisation at (t, y), with I - hγJ factored:
  // ynew_, and the error estimate err_ when `estimate`. False when a linear solve fails.
  bool stages(const OdeSystem& sys, double t, CVecRef y, double h, bool estimate,
              SolveStats& stats);

  RosenbrockTableau tab_;
  RosenbrockTransformed tr_;
  std::vector<Index> same_as_;  // stage i takes f of stage same_as_[i] (i itself: evaluated)
  Vec m_diff_;                  // m - m̂
  ImplicitCore core_;
  ControllerOptions control_;
  StepController ctrl_;
  bool need_ft_ = false;
  Mat u_, fs_;
  Vec ft_, arg_, rhs_, ynew_, err_;
  // Adaptive state.
  double t_ = 0.0, h_ = 0.0;
  bool lin_valid_ = false;  // J, f(t_, y) and f_t are those of the current point
  AdaptiveCounts counts_;
};

}  // namespace stiffbench
