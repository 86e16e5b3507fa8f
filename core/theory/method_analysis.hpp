// What a method's coefficients say about it, without running it (`stiffbench analyze`):
// order conditions by rooted trees, error coefficients, the stability function R = P/Q and
// what follows from it (A-/L-stability, exact axis limits, internal stability, dissipation and
// dispersion), the SSP coefficient of explicit methods, and the order of kick/drift splittings.
//
// Definitions (each with its source; the tests check every figure against an independent
// computation):
//   - Rooted trees t with |t| <= 8 vertices (1, 1, 2, 4, 9, 20, 48, 115 of each order), density
//     γ(t), symmetry σ(t) and elementary weights Φ(t) (Butcher, Numerical Methods for ODEs,
//     2016, §30–31; Hairer, Nørsett & Wanner I, §II.2). The condition of t for weights w:
//     residual(t) = wᵀΦ(t) − 1/γ(t).
//   - Error coefficients τ(t) = residual(t)/σ(t) (the coefficient of h^|t| F(t) in the local
//     error; Butcher §31). The principal error norms A^(p+1) = ‖τ^(p+1)‖₂ and max|τ^(p+1)|
//     over the trees of order p+1, and likewise for p+2 (Kennedy & Carpenter, Appl. Numer.
//     Math. 44 (2003) 139–181, §2.1).
//   - Rosenbrock methods in the form of Hairer & Wanner II, §IV.7 (α, Γ = γI + strictly lower
//     γ_ij): their own elementary weights (a vertex with one son takes β = α + Γ, others α).
//   - W-methods: the same scheme with an arbitrary matrix W in place of the Jacobian J
//     (Steihaug & Wolfbrandt, Math. Comp. 33 (1979) 521–534; Hairer & Wanner II, §IV.7,
//     "W-methods"). Its B-series runs over bi-coloured trees: f-vertices (any number of sons,
//     elementary weight factor α along their edges) and W-vertices (exactly one son, factor Γ
//     with its diagonal γ), the root either. Order p for every W when, for every such tree with
//     at most p vertices, wᵀΦ(t) = 1/γ(t) if it has no W-vertex and 0 otherwise (the exact
//     solution has no term with W). With W = J a W-vertex and an f-vertex with one son give the
//     same elementary differential, and the sum of the two conditions is the Rosenbrock one
//     (β = α + Γ): the W-order is at most the classical order.
//   - The embedded formula's stability function R̂ = P̂/Q̂ (the weights b̂ in place of b): |R̂(∞)|,
//     A- and L-stability, the exact axis limits, as for the main formula.
//   - A-stability: no pole of R in Re z < 0 and |Q(iy)|² − |P(iy)|² >= 0 for all real y,
//     checked on the coefficients of that even polynomial (exact, no sampling); L-stability:
//     A-stable and R(∞) = 0.
//   - Internal stability: the internal stability functions Q_j(z) = z bᵀ(I − zA)⁻¹ e_j of a
//     perturbation of stage j; the largest Σ_j |Q_j(z)| over the real and imaginary stability
//     intervals (Ketcheson, Lóczi & Parsani, SIAM J. Numer. Anal. 52 (2014) 2227–2249).
//   - SSP coefficient of an explicit method: the radius of absolute monotonicity of
//     K = [[A, 0], [bᵀ, 0]] — the largest r with (I + rK)⁻¹ defined, K(I + rK)⁻¹ >= 0 and
//     rK(I + rK)⁻¹1 <= 1 elementwise (Kraaijevanger, BIT 31 (1991) 482–528), by bisection on r.
//   - Dissipation and dispersion: |R(iν)| and arg R(iν) − ν; their orders are the lowest power
//     of ν in 1 − |R(iν)| and in arg R(iν) − ν, from the power series of log R(z) − z.
//   - Kick/drift splittings: log of the step map in the free Lie algebra of the kick and drift
//     vector fields (Baker–Campbell–Hausdorff, truncated tensor algebra to degree 8); order p
//     when log Φ_h = h(A + B) + O(h^(p+1)) (Hairer, Lubich & Wanner, Geometric Numerical
//     Integration, §III.5), and the oscillator stability interval.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/theory/linear_stability.hpp"
#include "core/theory/tableau.hpp"

namespace stiffbench {

// ---- Rooted trees ------------------------------------------------------------------------------
struct RootedTree {
  int order = 0;              // vertices
  std::vector<int> children;  // the root's subtrees: indices into rooted_trees(), non-decreasing
  double density = 0;         // γ(t)
  double symmetry = 0;        // σ(t)
  std::string name;           // bracket notation: "t", "[t]", "[t^2]", "[[t]]", "[t,[t]]", ...
};
// Every rooted tree with at most 8 vertices, order by order.
const std::vector<RootedTree>& rooted_trees();

// One order condition: its tree and its residual for the weights analysed.
struct OrderCondition {
  int order = 0;
  int tree = 0;              // index into rooted_trees() (splittings: -1)
  std::string name;          // the tree's name (splittings: the degree's Lie terms)
  double residual = 0;       // wᵀΦ(t) − 1/γ(t)
  double error_coefficient;  // residual/σ(t)
};

// All conditions of order <= max_order (<= 8) for weights w (b, or the embedded b̂).
std::vector<OrderCondition> rk_order_conditions(const ButcherTableau& t, const Vec& w,
                                                int max_order = 8);
// The first condition of order <= order with |residual| > tol (lowest order first), if any.
std::optional<OrderCondition> first_violated_condition(const std::vector<OrderCondition>& c,
                                                       int order, double tol = 1e-12);

// ---- W-methods ---------------------------------------------------------------------------------
// A bi-coloured tree of a W-method (see above): an f-vertex root with sons `children` (indices
// into w_trees(), non-decreasing), or a W-vertex root (w_root) with exactly one son.
struct WTree {
  int order = 0;
  bool w_root = false;
  std::vector<int> children;
  bool has_w = false;   // some vertex is a W-vertex (the condition's right-hand side is 0)
  double density = 0;   // γ(t) of the tree without colours (used when !has_w)
  double symmetry = 0;  // σ(t): the automorphisms that keep the colours
  std::string name;     // bracket notation, a W-vertex written W[...]: "W[t]", "[W[t]]"
};
inline constexpr int kMaxWOrder = 6;
// Every bi-coloured tree with at most kMaxWOrder vertices (1, 2, 5, 13, 37, 108 of each order),
// order by order.
const std::vector<WTree>& w_trees();
// The W-conditions of order <= max_order (<= kMaxWOrder) for weights w (tree = the index into
// w_trees(), name its bracket name, residual wᵀΦ(t) − (has_w ? 0 : 1/γ(t))).
std::vector<OrderCondition> rosenbrock_w_conditions(const RosenbrockTableau& t, const Vec& w,
                                                    int max_order = kMaxWOrder);
// Largest p <= kMaxWOrder with every W-condition of order <= p met to tol.
int rosenbrock_w_order(const RosenbrockTableau& t, const Vec& w, double tol = 1e-12);

// ---- The analysis of one method ----------------------------------------------------------------
// What an embedded formula's stability function gives (the same figures as the main one's).
struct EmbeddedStability {
  Polynomial p, q;        // R̂ = P̂/Q̂, ascending powers
  double r_infinity = 0;  // |R̂(∞)| (+inf when deg P̂ > deg Q̂)
  bool a_stable = false, l_stable = false;
  double real_axis_limit = 0, imag_axis_limit = 0;
  bool real_axis_unbounded = false, imag_axis_unbounded = false;
};

struct MethodAnalysis {
  std::string name;
  std::string kind;  // explicit_rk, dirk, irk, rosenbrock, splitting
  int stages = 0;
  int claimed_order = 0;   // the method's claim (0: none)
  int order = 0;           // achieved: every condition up to it holds to 1e-12 (8: at least 8)
  int stage_order = -1;    // largest q with C(q); -1 where not defined (Rosenbrock, splitting)
  int embedded_order = 0;  // achieved order of the embedded weights (0: none)
  // Rosenbrock: the W-order (every W-condition up to it holds to 1e-12; kMaxWOrder means at
  // least that) of b and of b̂ (0: no embedded weights); -1 for other kinds.
  int w_order = -1, embedded_w_order = -1;
  int claimed_w_order = 0;  // the method's claim (0: none)
  bool fsal = false, stiffly_accurate = false;
  std::vector<double> residual_by_order;        // [k-1]: max |residual| over the trees of order k
  double error_norm_2 = 0, error_norm_max = 0;  // of τ over the trees of order p+1
  double error_norm_2_next = 0, error_norm_max_next = 0;  // of order p+2
  double max_coefficient = 0;                             // largest |a_ij|, |b_i|, |c_i|
  // The stability function (one-step methods; empty P for splittings).
  Polynomial p, q;        // R = P/Q, ascending powers
  double r_infinity = 0;  // |R(∞)| (+inf when deg P > deg Q)
  bool a_stable = false, l_stable = false;
  double real_axis_limit = 0, imag_axis_limit = 0;  // exact (AxisLimit of linear_stability.hpp)
  bool real_axis_unbounded = false, imag_axis_unbounded = false;
  double internal_amplification_real = 0, internal_amplification_imag = 0;
  double ssp_coefficient = -1;                      // explicit RK only; -1 otherwise
  int dissipation_order = 0, dispersion_order = 0;  // 0: none (exact to the series' length)
  double oscillator_limit = 0;                      // splittings: stable for hω below it
  // The embedded weights give the same R(z) as b (P·Q̂ = P̂·Q to 1e-12): the error estimate
  // vanishes on linear constant-coefficient problems (ros3p). A note says so.
  bool embedded_same_stability = false;
  // The embedded formula's stability (embedded pairs with a stability function; empty otherwise).
  std::optional<EmbeddedStability> embedded_stability;
  std::vector<OrderCondition> conditions;    // every condition up to order 8
  std::vector<OrderCondition> w_conditions;  // Rosenbrock: every W-condition up to kMaxWOrder
  std::vector<std::string> notes;            // what was not analysed, and why
};

// Runge–Kutta (kind "explicit_rk", "dirk" or "irk"), Rosenbrock and kick/drift methods.
MethodAnalysis analyze_runge_kutta(const ButcherTableau& t, const std::string& kind);
MethodAnalysis analyze_rosenbrock(const RosenbrockTableau& t);
MethodAnalysis analyze_kick_drift(const KickDriftCoefficients& c);

// Additive (IMEX) Runge–Kutta pairs, kind "imex_ark": the pair's order and embedded order from
// the additive order conditions of core/theory/additive_conditions.hpp (both tables' own conditions
// and the coupling ones, to order kMaxAdditiveOrder), the largest residual per order, stiffly
// accurate (the implicit table's last row equals its b), the largest coefficient of either table.
// The conditions keep their names (tree = -1) and have no error coefficient (NaN): the coloured
// trees' symmetries are not formed, so no error norms either. The pair has no stability function of
// its own: each table alone is an analyze_runge_kutta of its own (what `stiffbench analyze` shows
// as NAME:explicit and NAME:implicit).
inline constexpr int kMaxAdditiveOrder = 6;
MethodAnalysis analyze_additive(const AdditiveTableau& t);

// |R(iν)| and arg R(iν) − ν (unwrapped) on ν = 10^(−2 + 3k/(n−1)), k = 0..n−1.
struct DispersionPoint {
  double nu, amplification, phase_error;
};
std::vector<DispersionPoint> dissipation_dispersion(const RationalForm& r, int n = 121);

// The SSP coefficient (radius of absolute monotonicity) of a Runge–Kutta tableau; 0 when none.
// Found by bisection and rounded to 12 significant digits: the true value lies within
// kSspRelativeTolerance (relative) of it.
inline constexpr double kSspRelativeTolerance = 1e-12;
double ssp_coefficient(const ButcherTableau& t);

}  // namespace stiffbench
