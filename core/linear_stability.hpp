// Linear stability theory of a time integrator: what one step does on the linear test
// equations, computed from the method's coefficients (never from a run).
//
//   Dahlquist test  y' = λy, z = hλ ∈ ℂ: the step map multiplies y by R(z) (one-step methods:
//     Runge–Kutta R(z) = 1 + z bᵀ(I − zA)⁻¹1, Rosenbrock the same with A = α + Γ); a k-step
//     linear multistep method Σ α_j y_{n+j} = h Σ β_j f_{n+j} has the characteristic polynomial
//     ρ(ζ) − zσ(ζ) and its amplification is the largest root modulus.
//   Mechanical test  x'' = a·x + b·x' (a 1-DOF oscillator; a = −ω², b = −2ζω): methods that need
//     a mechanical system (symplectic splittings, Verlet, Baraff–Witkin) have a 2×2 step map on
//     (x, h·v) that depends only on (h²a, h·b); its amplification is the spectral radius.
//     For an eigenvalue pair λ, λ̄ of a mechanical first-order system the matching oscillator is
//     a = −|λ|², b = 2 Re λ (exact for undamped and for proportionally damped systems).
//
// A step is stable on a mode when its amplification is <= 1 (+ stability_tolerance, so that
// |R| = 1 exactly on the imaginary axis — implicit midpoint, symplectic methods — counts as
// stable).
#pragma once

#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/tableau.hpp"
#include "core/types.hpp"

namespace stiffbench {

inline constexpr double stability_tolerance = 1e-9;

struct LinearStability {
  std::string kind;  // "Runge-Kutta", "Rosenbrock", "linear multistep", "splitting", ...
  // Spectral radius of the step map on y' = λy at z = hλ. Empty for methods defined only for
  // mechanical systems.
  std::function<double(std::complex<double>)> amplification;
  // Spectral radius of the step map on x'' = a x + b x' as a function of (h²a, h·b). Set for
  // every method: derived from `amplification` (the roots of λ² − bλ − a) when the method is
  // not mechanical-only.
  std::function<double(double h2a, double hb)> mechanical_amplification;
  // For multistep methods: the boundary locus z(θ) = ρ(e^{iθ})/σ(e^{iθ}), θ ∈ [0, 2π). Empty
  // for one-step methods (their boundary is traced as the contour |R(z)| = 1).
  std::function<std::complex<double>(double theta)> boundary_locus;
};

// Constructors from coefficients.
LinearStability tableau_stability(const ButcherTableau& t);
// Rosenbrock: stage coefficients α (strictly lower), Γ (lower, diagonal γ) and weights b.
LinearStability rosenbrock_stability(const Mat& alpha, const Mat& gamma, const Vec& b);
// Linear multistep: α_0..α_k and β_0..β_k (index j multiplies y_{n+j}).
LinearStability multistep_stability(const std::vector<double>& alpha,
                                    const std::vector<double>& beta);
// Kick/drift splitting (mechanical-only).
LinearStability kick_drift_stability(const KickDriftCoefficients& c);
// Fills mechanical_amplification of a method that has `amplification`.
LinearStability with_mechanical_from_scalar(LinearStability s);

// Stability limits along the rays of the test equations.
struct AxisLimit {
  // Largest r such that the method is stable on the whole segment from 0 to r along the ray
  // (its first crossing of the boundary), to relative accuracy ~1e-10; 0 when it is unstable
  // arbitrarily close to the origin (explicit Euler on the imaginary axis).
  double limit = 0.0;
  bool unbounded = false;  // stable along the whole ray up to the searched cap (A-stable on it)
};
AxisLimit real_axis_limit(const LinearStability& s, double cap = 1e6);       // z = −r
AxisLimit imaginary_axis_limit(const LinearStability& s, double cap = 1e6);  // z = i·r
// Undamped oscillator x'' = −ω²x: limit on hω (via mechanical_amplification(−(hω)², 0)).
AxisLimit oscillator_limit(const LinearStability& s, double cap = 1e6);

// The two functions below ignore eigenvalues of modulus below 1e-6 × the largest (numerical
// noise of the eigensolver on zero modes, e.g. pinned dofs' Jordan blocks) and eigenvalues with
// Re λ > kGrowingModeTolerance × the largest modulus: modes the system itself lets grow (a
// compressed spring's buckling, a negative concentration) are unstable for every method and
// say nothing about the step limit. Undamped modes (Re λ at round-off level) are kept.
inline constexpr double kGrowingModeTolerance = 1e-6;
// Largest amplification over a set of eigenvalues of a first-order system at step h.
// `mechanical`: the system is mechanical and only the mechanical test applies (pairs mapped to
// oscillators as above); otherwise `amplification(hλ)` is used.
double max_amplification(const LinearStability& s, double h,
                         const std::vector<std::complex<double>>& eigenvalues, bool mechanical);

// The largest step h stable on every eigenvalue, searched outward from h = 0 (first crossing,
// then bisection to relative tolerance `rel_tol`). unbounded when stable up to h_cap.
struct StepLimit {
  double h = 0.0;
  bool unbounded = false;
};
StepLimit predicted_step_limit(const LinearStability& s,
                               const std::vector<std::complex<double>>& eigenvalues,
                               bool mechanical, double h_cap, double rel_tol = 1e-10);

// The boundary |amplification(z)| = 1 inside a box of the complex plane, as polylines
// (marching squares on an n×n grid, refined by bisection on each crossed grid edge; for
// multistep methods the sampled boundary locus clipped to the box).
std::vector<std::vector<std::complex<double>>> region_boundary(const LinearStability& s,
                                                               double re_min, double re_max,
                                                               double im_min, double im_max,
                                                               int n = 400);

// True when amplification <= 1 + stability_tolerance on every sample of the left half-plane
// box [−r, 0] × [−r, r] (n×n grid plus the imaginary axis).
bool a_stable_on_samples(const LinearStability& s, double r = 1e3, int n = 201);

}  // namespace stiffbench
