// Diagonally implicit Runge–Kutta methods as tableau data read by one generic stepper (BDF2,
// which starts with one of its steps, is in bdf2.hpp). Stage i solves
// z_i = y + h Σ_{j<i} a_ij k_j + h a_ii f(t + c_i h, z_i) by Newton (ImplicitCore) and sets
// k_i = (z_i - ψ_i)/(h a_ii) from the converged iterate; a_ii = 0 stages are explicit.
// y⁺ = y + h Σ b_i k_i.
//
// The tableaux are method files (methods/NAME.toml, kind = "dirk": coefficients as exact
// expressions, description, kind, reference, order; Hairer & Wanner, Solving ODEs II,
// §IV.3–IV.6), compiled into the library and parsed by built_in_methods()
// (integrators/method_file.hpp):
//   backward_euler     order 1, L-stable
//   implicit_midpoint  order 2, A-stable, symplectic
//   trapezoidal        order 2, A-stable (|R(∞)| = 1)
//   sdirk2             γ = 1 - 1/√2, order 2, L-stable
//   sdirk3             Alexander (1977), γ ≈ 0.4358665215, order 3, L-stable
// The L-stable ones are stiffly accurate (b = last row of A), so y⁺ = z_s exactly.
//
// ESDIRK pairs with an embedded estimate (esdirk_tableaux(); fixed step with --h, adaptive with
// rtol/atol). The first stage is explicit (a_11 = 0, k_1 = f(t, y)), every other diagonal entry
// is γ, and the last row of A is b (stiffly accurate, c_s = 1):
//   trbdf2    TR-BDF2 (Bank et al. 1985, in the form of Hosea & Shampine 1996): γ = 2 - √2,
//             order 2, embedded order 3, L-stable
//   esdirk43  ESDIRK4(3)6L[2]SA, the implicit tableau of the ARK4(3)6L[2]SA pair of Kennedy &
//             Carpenter (2003): γ = 1/4, order 4 (L-stable), embedded order 3 (A-stable)
// The order conditions of both rows and R(∞) = 0 are checked in
// tests/integrators/test_esdirk_gauss.cpp.
//
// f evaluations: stage 1 of a step is f(t, y). Because the method is stiffly accurate, k_s
// (recovered from the last stage equation, see above) is f(t + h, y⁺) up to the Newton
// residual, and the next step takes it as its k_1 (FSAL): a fixed-step run evaluates f(t0, y0)
// once, an adaptive run once at the start (plus one for the starting-step heuristic), and a
// rejected trial keeps k_1. Each implicit stage costs one evaluation per Newton iteration (the
// accepted iterate z_k + Δ_k is not evaluated again; ImplicitCore), plus finite-difference
// Jacobian columns. In fixed-step mode k_1 is reused only
// when step() continues where the last one ended (same t and storage; on constrained systems
// also the same values), as the explicit FSAL pairs do.
//
// Adaptive mode: the error estimate e = h Σ (b_i - b̂_i) k_i is O(h^(p̂+1)) with p̂ = min(order,
// embedded order); with error_filter=on (default) it is replaced by (I - hγJ)⁻¹ e with the
// iteration matrix already factored for the last stage (one more linear solve). The filter
// leaves e = O(h^(p̂+1)) for non-stiff components ((I - hγJ)⁻¹ = I + O(h)) and divides a stiff
// component's by 1 - hγλ (Shampine's filter, as in Hairer–Wanner IV.8 for radau5). The embedded
// rows are not L-stable: on y' = λy the raw estimate is (R(hλ) - R̂(hλ)) y, and TR-BDF2's R̂ grows
// like -(√2/3) hλ (the raw estimate of a stiff component ∝ |hλ|, the filtered one bounded),
// esdirk43's R̂(∞) = -0.15 (values from the tableaux, tests/integrators/test_esdirk_gauss.cpp).
// The shared controller (integrators/adaptive/controller.hpp) runs with k = p̂ + 1. A Newton or
// linear-solver failure rejects the trial and retries with h/2 (counted in error_test_failures;
// Newton failures also in newton_conv_failures). The Newton tolerance of a trial (in
// ImplicitCore's norm, relative to 1 + |z_i|) is max(0.01 min_i (atol + rtol |y_i|)/(1 + |y_i|),
// 1e-14), in place of newton_tol: the Newton error stays two orders below the error the
// controller allows in every component (else the estimate measures Newton noise and the steps
// collapse), and loose tolerances do not pay for Newton iterations to round-off. Fixed-step
// mode uses newton_tol (default 1e-15: to round-off) with ImplicitCore's contraction-aware test.
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"
#include "integrators/adaptive/controller.hpp"
#include "integrators/solvers/newton.hpp"

namespace stiffbench {

// The built-in DIRK tableaux (the method files of kind dirk, in the order of built_in_methods()):
// the fixed-step ones (and one by name: a logic_error for a name that is not one), the ESDIRK
// pairs with embedded weights (b_embedded: trbdf2, esdirk43).
const std::vector<ButcherTableau>& implicit_tableaux();
const ButcherTableau& implicit_tableau(const std::string& name);
const std::vector<ButcherTableau>& esdirk_tableaux();

// One DIRK step with a shared ImplicitCore (used by DirkIntegrator and by BDF2's start-up,
// bdf2.hpp).
class DirkStepper {
 public:
  explicit DirkStepper(ButcherTableau tableau) : tableau_(std::move(tableau)) {}
  void reset(Index n);
  // k1_given: an explicit first stage is already in first_stage() (= f(t, y)), not evaluated.
  Status step(ImplicitCore& core, const OdeSystem& sys, double t, VecRef y, double h,
              SolveStats& stats, bool k1_given = false);
  const ButcherTableau& tableau() const { return tableau_; }
  VecRef first_stage() { return k_.col(0); }
  // After a step: the stiffly accurate last stage k_s ≈ f(t + h, y⁺) becomes the next k_1.
  void last_stage_to_first() { k_.col(0) = k_.col(tableau_.stages() - 1); }
  // After a step of size h: e = h Σ (b_i - b̂_i) k_i.
  void embedded_difference(double h, VecRef e) const;

 private:
  ButcherTableau tableau_;
  Mat k_;
  Vec psi_, z_, fz_;
};

// Adaptive (advance_to) when the tableau has embedded weights and an explicit first stage.
class DirkIntegrator final : public Integrator {
 public:
  DirkIntegrator(ButcherTableau tableau, std::string description, ImplicitOptions opt,
                 ControllerOptions control = {}, bool error_filter = true);
  bool supports_adaptive() const override { return adaptive_; }
  std::optional<double> absolute_tolerance() const override { return control_.atol; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  void restart(const OdeSystem& sys, double t, CVecRef y) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(stepper_.tableau());
  }
  const ButcherTableau* butcher_tableau() const override { return &stepper_.tableau(); }
  const ImplicitCore& core() const { return core_; }

 private:
  void restart_state(const OdeSystem& sys, double t0);  // what reset() and restart() clear
  DirkStepper stepper_;
  ImplicitCore core_;
  bool adaptive_ = false, fsal_ = false, filter_ = true;
  double newton_tol_ = 1e-15;  // the user's (core_ gets a per-trial value in adaptive mode)
  ControllerOptions control_;
  StepController ctrl_;
  Vec ynew_, err_, work_, work2_;
  // Adaptive state.
  double t_ = 0.0, h_ = 0.0;
  bool k1_valid_ = false;
  AdaptiveCounts counts_;
  // Fixed-step FSAL cache.
  const double* cached_y_ = nullptr;
  double cached_t_ = 0.0;
  bool cache_valid_ = false, constrained_ = false;
  Vec cached_values_;
};

// The Newton tolerance of an adaptive trial from y (see the header comment): max(0.01 min_i
// (atol + rtol |y_i|)/(1 + |y_i|), 1e-14). Shared by the ESDIRK and IMEX pairs.
double adaptive_newton_tolerance(CVecRef y, const ControllerOptions& control);

// Parameters of the ESDIRK pairs: the implicit family's (with Newton), the controller's and
// error_filter, on by default for the ESDIRK pairs and off for the IMEX pairs (filter_by_default
// false: imex_ark.hpp says why); and the reader of the last.
std::vector<ParamSpec> esdirk_param_specs(bool filter_by_default = true);
bool read_error_filter(const Params& p);

}  // namespace stiffbench
