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
// A step is stable on a mode when its amplification is <= 1.
//
// Exact limits. A one-step method's R is rational, R = P/Q (explicit Runge–Kutta: Q = 1,
// P_k = bᵀA^{k−1}1; implicit: P(z) = det(I − zA + z1bᵀ), Q(z) = det(I − zA), Hairer–Wanner II,
// Prop. IV.3.2). Along a ray z = r·u (|u| = 1) the step is stable while
// F(r) = |P(ru)|² − |Q(ru)|² <= 0, a real polynomial in r (in w = r² on the imaginary axis, u = i,
// degree <= s; on the real axis F = (P − Q)(P + Q), whose roots are those of R = ±1). The limit is
// the first r > 0 at which F changes sign to positive: its coefficients are formed in long
// double, the lowest-order non-zero one decides the behaviour next to 0 (positive: unstable
// arbitrarily close to 0, limit 0; every coefficient zero: |R| = 1 on the whole ray), the
// positive real roots come from the companion matrix and the crossing is then bisected on F in
// long double to the double's precision (better than 1e-12 relative). Kick/drift splittings on
// the undamped oscillator x'' = −ω²x have a step map of determinant 1 whose half-trace T is a
// polynomial in x = −(hω)²: stable while T² − 1 <= 0, the same computation.
// Methods without such a form (linear multistep: the largest root modulus of the characteristic
// polynomial; splittings on a damped oscillator) keep a sampled search (scan outward, then
// bisection) that accepts an amplification up to 1 + stability_tolerance, so that |R| = 1 on
// the imaginary axis from round-off does not count as growth; such limits are marked
// AxisLimit::exact = false.
#pragma once

#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/theory/tableau.hpp"
#include "core/types.hpp"

namespace stiffbench {

inline constexpr double stability_tolerance = 1e-9;

// A real polynomial by its coefficients in ascending powers.
using Polynomial = std::vector<double>;
// The product a·b (empty when either is).
Polynomial poly_multiply(const Polynomial& a, const Polynomial& b);
// R(z) = P(z)/Q(z), P(0) = Q(0) = 1.
struct RationalForm {
  Polynomial p, q;
};

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
  // One-step methods: R = P/Q (exact limits). Empty for multistep and mechanical-only methods.
  std::optional<RationalForm> rational;
  // Kick/drift splittings and partitioned IMEX pairs: half-trace T(x) of the step map on
  // x'' = −ω²x, x = −(hω)², as a polynomial in x. Empty otherwise.
  Polynomial oscillator_half_trace;
  // Its determinant D(x), a polynomial in x too; empty: D = 1 (a kick/drift splitting, whose
  // stages are shears). With both, the undamped oscillator's limit is exact (Schur–Cohn: both
  // eigenvalues of a real 2×2 map lie in the closed unit disk iff |D| <= 1 and |2T| <= 1 + D).
  Polynomial oscillator_determinant;
  // The step map's dominant eigenvalue itself (complex), for damping and phase: on y' = λy,
  // R(z) for one-step methods and the root of largest modulus of ρ(ζ) − zσ(ζ) for multistep
  // ones (empty for mechanical-only methods); on x'' = a x + b x', the eigenvalue of largest
  // modulus of the step map, the one with Im >= 0 of a complex pair (set for every method).
  std::function<std::complex<double>(std::complex<double>)> multiplier;
  std::function<std::complex<double>(double h2a, double hb)> mechanical_multiplier;
  // Levels of the state the step map acts on: 1 for one-step methods, k for a k-step method.
  int state_levels = 1;
};

// What one step does to the undamped oscillator x'' = −ω²x at ν = hω, from the step map's
// dominant eigenvalue μ = A e^{iθ} (θ = arg μ ∈ [0, π]; the exact flow has μ = e^{iν}). The
// definitions are those of Hilber, Hughes & Taylor (1977), "Improved numerical dissipation for
// time integration algorithms in structural dynamics", Earthquake Eng. Struct. Dyn. 5:
//   amplification    A = |μ| per step (1: no numerical damping);
//   damping_ratio    ξ̄ = −ln A / θ, the damping ratio of the linear oscillator whose exact
//                    solution the numerical one is (amplitude ×e^{−2πξ̄} per numerical period);
//   period_error     T̄/T − 1 = ν/θ − 1 (relative period elongation; > 0: too slow);
//   frequency_error  θ/ν − 1.
// θ = 0 (a real eigenvalue: the numerical mode does not oscillate) gives NaN for ξ̄ and ∞ for
// the period error.
struct OscillatorResponse {
  double nu = 0.0;
  double amplification = 0.0;
  double phase = 0.0;  // θ
  double damping_ratio = 0.0;
  double period_error = 0.0;
  double frequency_error = 0.0;
};
OscillatorResponse oscillator_response(std::complex<double> multiplier, double nu);
// From the method's coefficients (mechanical_multiplier at h²a = −ν², hb = 0); nullopt when
// the method has no stability data.
std::optional<OscillatorResponse> oscillator_response(const LinearStability& s, double nu);

// The eigenvalue of largest modulus of a real 2×2 matrix [[p, q], [r, s]] (of a complex pair,
// the one with Im >= 0), and its spectral radius.
std::complex<double> dominant_eigenvalue_2x2(double p, double q, double r, double s);
double spectral_radius_2x2(double p, double q, double r, double s);

// R = P/Q of a Runge–Kutta stage matrix and weights (Rosenbrock: A = α + Γ).
RationalForm runge_kutta_rational_form(const Mat& a, const Vec& b);
// |P(z)/Q(z)| by Horner sums (+∞ at a pole or on overflow).
double rational_modulus(const RationalForm& r, std::complex<double> z);

// Constructors from coefficients.
LinearStability tableau_stability(const ButcherTableau& t);
// Rosenbrock: stage coefficients α (strictly lower), Γ (lower, diagonal γ) and weights b.
LinearStability rosenbrock_stability(const Mat& alpha, const Mat& gamma, const Vec& b);
// Linear multistep: α_0..α_k and β_0..β_k (index j multiplies y_{n+j}).
LinearStability multistep_stability(const std::vector<double>& alpha,
                                    const std::vector<double>& beta);
// Kick/drift splitting (mechanical-only).
LinearStability kick_drift_stability(const KickDriftCoefficients& c);
// An additive (IMEX) Runge–Kutta pair on a mechanical split that puts x' = v in f_I and the
// acceleration in f_E (every built-in mechanical split): on x'' = a x + b x' the pair is a
// partitioned Runge–Kutta method, x advanced with the implicit table and v with the explicit
// one. Stages X = x_n 1 + A_I U, U = u_n 1 + A_E(h²a X + hb U) (u = h v), x_{n+1} = x_n + b_Iᵀ U,
// u_{n+1} = u_n + b_Eᵀ(h²a X + hb U): a 2×2 step map in (h²a, hb). Mechanical-only
// (`amplification` empty). At hb = 0 and a DIRK implicit table, A_E A_I is nilpotent, so the
// map's entries are polynomials in x = h²a: oscillator_half_trace and oscillator_determinant
// are set and the oscillator limit is exact. Its limit is not the explicit table's on ±iω
// (ARS(2,3,2): hω = 2.843 against 1.414; ARK3(2)4L[2]SA: unstable for every hω > 0).
LinearStability partitioned_imex_stability(const AdditiveTableau& t);
// Fills mechanical_amplification of a method that has `amplification`.
LinearStability with_mechanical_from_scalar(LinearStability s);
// k steps of size h/k as one step of size h: R_k(z) = R(z/k)^k (its limits along every ray are k
// times R's). From `amplification` and, when present, the rational form (P(z/k)^k / Q(z/k)^k);
// a multistep or mechanical-only method is returned unchanged when k = 1 and refused otherwise
// (logic_error).
LinearStability substepped(const LinearStability& s, int k);

// Stability limits along the rays of the test equations.
struct AxisLimit {
  // Largest r such that the method is stable on the whole segment from 0 to r along the ray
  // (its first crossing of the boundary), to relative accuracy ~1e-10; 0 when it is unstable
  // arbitrarily close to the origin (explicit Euler on the imaginary axis).
  double limit = 0.0;
  bool unbounded = false;  // stable along the whole ray up to the searched cap (A-stable on it)
  bool exact = false;      // from the polynomial roots (true) or the sampled search (false)
};
// |P(iy)|² − |Q(iy)|² as a polynomial in w = y² (coefficients in ascending powers, those at
// round-off level of their terms set to 0); F(0) = 0. Its lowest-order non-zero coefficient is
// positive exactly when the method is unstable arbitrarily close to 0 on the imaginary axis.
Polynomial imaginary_axis_polynomial(const RationalForm& r);
// The exact limit along the ray z = r·unit (|unit| = 1) from R = P/Q, as described above.
AxisLimit rational_ray_limit(const RationalForm& r, std::complex<double> unit, double cap = 1e6);
AxisLimit real_axis_limit(const LinearStability& s, double cap = 1e6);       // z = −r
AxisLimit imaginary_axis_limit(const LinearStability& s, double cap = 1e6);  // z = i·r
// Undamped oscillator x'' = −ω²x: limit on hω (exact from R = P/Q on the imaginary axis or from
// the splitting's half-trace; else sampled on mechanical_amplification(−(hω)², 0)).
AxisLimit oscillator_limit(const LinearStability& s, double cap = 1e6);

// The two functions below ignore eigenvalues of modulus below 1e-6 × the largest (numerical
// noise of the eigensolver on zero modes, e.g. pinned dofs' Jordan blocks) and eigenvalues with
// Re λ > kGrowingModeTolerance × the largest modulus: modes the system itself lets grow (a
// compressed spring's buckling, a negative concentration) are unstable for every method and
// say nothing about the step limit. Undamped modes (|Re λ| <= kGrowingModeTolerance × the
// largest modulus, i.e. the eigensolver's round-off on an undamped spectrum) are kept and put on
// the imaginary axis (Re λ = 0), so that a method with imaginary-axis limit 0 is predicted
// unstable for every h on them rather than given a limit set by round-off damping.
inline constexpr double kGrowingModeTolerance = 1e-6;
// Largest amplification over a set of eigenvalues of a first-order system at step h.
// `mechanical`: the system is mechanical and only the mechanical test applies (pairs mapped to
// oscillators as above); otherwise `amplification(hλ)` is used.
double max_amplification(const LinearStability& s, double h,
                         const std::vector<std::complex<double>>& eigenvalues, bool mechanical);

// The largest step h stable on every eigenvalue, searched outward from h = 0 (first crossing,
// then bisection to relative tolerance `rel_tol`). unbounded when stable up to h_cap.
struct StepLimit {
  double h = 0.0;  // 0: unstable for every h > 0 (an undamped mode and imaginary-axis limit 0)
  bool unbounded = false;
  bool exact = true;  // every eigenvalue's limit came from polynomial roots (see above)
};
StepLimit predicted_step_limit(const LinearStability& s,
                               const std::vector<std::complex<double>>& eigenvalues,
                               bool mechanical, double h_cap, double rel_tol = 1e-10);

// The boundary |amplification(z)| = 1 inside a box of the complex plane, as polylines
// (marching squares on an n×n grid, refined by bisection on each crossed grid edge; for
// multistep methods the sampled boundary locus clipped to the box). Polls run control once per
// grid row (throws Interrupted or WallLimitExceeded, core/run_control.hpp).
std::vector<std::vector<std::complex<double>>> region_boundary(const LinearStability& s,
                                                               double re_min, double re_max,
                                                               double im_min, double im_max,
                                                               int n = 400);

// True when amplification <= 1 + stability_tolerance on every sample of the left half-plane
// box [−r, 0] × [−r, r] (n×n grid plus the imaginary axis).
bool a_stable_on_samples(const LinearStability& s, double r = 1e3, int n = 201);
// Exact A-stability of R = P/Q (Hairer–Wanner II, IV.3): |R(iy)| <= 1 for every real y
// (|P(iy)|² − |Q(iy)|² never turns positive) and every pole (root of Q) in Re z > 0, so that by
// the maximum principle |R| <= 1 on the closed left half-plane. Empty without a rational form.
std::optional<bool> a_stable_exact(const LinearStability& s);

}  // namespace stiffbench
