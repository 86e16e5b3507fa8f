// XPBD (Macklin, Müller & Chentanez, "XPBD: position-based simulation of compliant constrained
// dynamics", MIG 2016) on mass-spring networks, with the substeps of Macklin et al., "Small steps
// in physics simulation" (SCA 2019). It needs the system's springs (core/springs.hpp) and refuses
// other systems (check_compatible names the model).
//
// One step of size h is `substeps` substeps of size h_s = h/substeps. Each substep:
//   1. prediction (free points): v ← (v + h_s g)/(1 + h_s γ/m), x^n = x, x ← x + h_s v
//      (gravity as the paper's external force; point damping -γv taken implicitly, so it never
//      amplifies);
//   2. Lagrange multipliers λ = 0 (reset every substep, as in the paper's Algorithm 1);
//   3. `iterations` sweeps over the springs, each spring (i, j, L, k, c) a compliant distance
//      constraint C = |x_j - x_i| - L with compliance α = 1/k, α̃ = α/h_s², ∇_j C = n = -∇_i C,
//      n = (x_j - x_i)/|x_j - x_i|, w = 1/m (0 for pinned points):
//        Δλ = (-C - α̃ λ - γ_c n·(Δx_j - Δx_i)) / ((1 + γ_c)(w_i + w_j) + α̃),
//        x_i -= w_i n Δλ,  x_j += w_j n Δλ,  λ += Δλ            (paper Eqs. 18 and 26),
//      Δx = x - x^n, with the paper's constraint damping γ_c = α̃ β̃ / h_s, β̃ = h_s² β and
//      β = c (the dashpot of force c (u·n) n), i.e. γ_c = c/(k h_s);
//   4. v = (x - x^n)/h_s.
// variant=gauss_seidel applies each spring's correction at once (in the spring list's order).
// variant=jacobi computes every Δλ from the same iterate and applies them together, each scaled
// by ω_c = ((1+γ_c)(w_i + w_j) + α̃) / ((1+γ_c)(n_i w_i + n_j w_j) + α̃), n_p = the springs at
// point p. Then the scaled iteration is a weighted Jacobi on the linearised system
// ((1+Γ) J W Jᵀ + α̃) Δλ = r whose iteration matrix Ω D⁻¹ A has real positive eigenvalues (it is
// similar to a symmetric positive definite matrix) bounded by its largest row sum, which is at
// most 1 by Gershgorin (row c's off-diagonal entries are (1+γ_c) w_p |n_c·n_c'| ≤ (1+γ_c) w_p at
// the shared point p): the sweeps converge where plain Jacobi over a cloth overshoots. ω_c → 1 as
// h_s → 0 (α̃ dominates), so one sweep per small substep applies the full spring impulse: with a
// fixed weight 1/max(n_i, n_j) instead (measured: 1 iteration, 64 substeps) the cloth's springs
// act with a fraction of their force and the error stops falling with the substeps. Scaling Δλ
// (not only the positions, as the constraint averaging of Macklin et al. 2014 does) keeps x - x̃
// and λ consistent, so both variants iterate towards the same equations C + α̃λ + damping = 0
// (where they converge to depends slightly on the path, through XPBD's frozen gradients).
//
// With enough iterations each substep solves the paper's implicit position update (backward
// Euler on the springs up to XPBD's frozen-gradient approximation), so the method is first
// order in h_s; with one iteration and small h_s it is close to symplectic Euler (Macklin et al.
// 2019). Springs of zero stiffness (infinite compliance) exert no force and are skipped (a
// dashpot on such a spring is not modelled); a spring of zero current length has no direction
// and is skipped in that sweep. Distance constraints of the model are enforced by the driver's
// projection, as for every integrator.
// Cost per step: substeps × iterations passes over the springs; no f evaluations (the springs
// are used directly, so f_evals stays 0: compare cost by wall time).
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/params.hpp"
#include "core/springs.hpp"

namespace stiffbench {

struct XpbdOptions {
  int substeps = 1;
  int iterations = 10;
  enum class Variant { gauss_seidel, jacobi } variant = Variant::gauss_seidel;
};

std::vector<ParamSpec> xpbd_param_specs();
XpbdOptions read_xpbd_options(const Params& p);

class Xpbd final : public Integrator {
 public:
  explicit Xpbd(XpbdOptions opt);
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;

 private:
  // A spring that can move (not both ends pinned, k > 0), with what every sweep reads.
  struct Constraint {
    Index i, j;
    double rest, compliance, damping;  // L, α = 1/k, c
    double wi, wj;                     // inverse masses of the ends
    double busy;                       // n_i w_i + n_j w_j (n_p: springs at p), Jacobi
  };
  template <int D>
  void substep(double* x, double* v, double hs);
  template <int D, bool Jacobi>
  void sweep(double* x, double hs);

  XpbdOptions opt_;
  const OdeSystem* sys_ = nullptr;
  const SpringNetworkView* net_ = nullptr;
  std::vector<Constraint> constraints_;
  std::vector<double> inv_mass_;  // per point
  Vec x_start_, lambda_, dx_;     // x^n, multipliers, Jacobi accumulator
};

}  // namespace stiffbench
