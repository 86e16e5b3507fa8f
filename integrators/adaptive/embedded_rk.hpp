// Explicit embedded Runge–Kutta pairs (tableaux with b_embedded: bs3, dopri5, cash_karp, rkf45,
// integrators/explicit/tableaux.hpp) in fixed-step and adaptive mode.
//
//   k_i = f(t + c_i h, y + h Σ_{j<i} a_ij k_j),  y⁺ = y + h Σ b_i k_i,
//   error estimate e = y⁺ - ŷ⁺ = h Σ (b_i - b̂_i) k_i, controlled by StepController
//   (integrators/adaptive/controller.hpp) with k = min(order, embedded order) + 1.
//
// f evaluations, counted as they happen at the system boundary:
//   - stage 1 is f(t, y); FSAL pairs (bs3, dopri5) take it from the previous step's last stage
//     (evaluated at y⁺ itself), so a step costs s - 1 evaluations after the first;
//   - a rejected trial keeps stage 1 (same t, y) and costs s - 1 evaluations;
//   - the adaptive start costs f(t0, y0) (it is stage 1 of the first step) plus the one extra
//     evaluation of the starting-step heuristic (none when h0 is given).
//   Adaptive run with A accepted and R rejected steps, heuristic start:
//     FSAL:      2 + (s - 1)(A + R)
//     non-FSAL:  2 + (s - 1)(A + R) + (A - 1)     (stage 1 at each new accepted point)
//   Fixed-step run of N steps: FSAL 1 + (s - 1) N, otherwise s N.
// In fixed-step mode the FSAL stage is reused only when step() continues from where the last one
// ended (same t and storage; on constrained systems, whose projection moves y, also the same
// values), as velocity Verlet does.
//
// No allocation per step: workspaces are sized in reset().
#pragma once

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"
#include "integrators/adaptive/controller.hpp"

namespace stiffbench {

class EmbeddedRungeKutta final : public Integrator {
 public:
  EmbeddedRungeKutta(ButcherTableau tableau, std::string description, ControllerOptions opt);

  const ButcherTableau& tableau() const { return tableau_; }
  const ButcherTableau* butcher_tableau() const override { return &tableau_; }
  bool supports_adaptive() const override { return true; }
  std::optional<double> absolute_tolerance() const override { return opt_.atol; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return tableau_stability(tableau_);
  }

 private:
  // Stages 2..s from k_.col(0) = f(t, y) and the new solution into ynew_; with the error
  // estimate into err_ when `estimate`.
  void stages(const OdeSystem& sys, double t, CVecRef y, double h, bool estimate);

  ButcherTableau tableau_;
  ControllerOptions opt_;
  StepController ctrl_;
  Vec d_;  // b - b̂
  Mat k_;
  Vec ytmp_, ynew_, err_, work_;
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

}  // namespace stiffbench
