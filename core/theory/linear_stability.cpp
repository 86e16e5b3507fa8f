#include "core/theory/linear_stability.hpp"

#include "core/run_control.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <utility>

namespace stiffbench {

namespace {

using cd = std::complex<double>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// R(z) = 1 + z bᵀ(I − zA)⁻¹1 for a full (possibly implicit) stage matrix. Infinite where
// I − zA is singular (a pole of R).
cd rk_multiplier(const Mat& a, const Vec& b, cd z) {
  const Index s = b.size();
  const Eigen::MatrixXcd m = Eigen::MatrixXcd::Identity(s, s) - z * a.cast<cd>();
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(m);
  const Eigen::VectorXcd k = lu.solve(Eigen::VectorXcd::Ones(s));
  // bᵀk without conjugation (Eigen's dot() conjugates its first argument).
  const cd r = 1.0 + z * (b.cast<cd>().transpose() * k)(0, 0);
  return std::isfinite(r.real()) && std::isfinite(r.imag()) ? r : cd(kInf, 0.0);
}
double rk_amplification(const Mat& a, const Vec& b, cd z) {
  return std::abs(rk_multiplier(a, b, z));
}

// The root of largest modulus of Σ_j (α_j − zβ_j) ζ^j (companion matrix); ∞ for a root at
// infinity.
cd multistep_multiplier(const std::vector<double>& alpha, const std::vector<double>& beta, cd z) {
  const std::size_t k = alpha.size() - 1;
  std::vector<cd> c(k + 1);
  for (std::size_t j = 0; j <= k; ++j) c[j] = alpha[j] - z * beta[j];
  if (std::abs(c[k]) <= 1e-14 * std::abs(c[0]) + 1e-300) return {kInf, 0.0};
  if (k == 1) return -c[0] / c[1];
  Eigen::MatrixXcd comp = Eigen::MatrixXcd::Zero(static_cast<Index>(k), static_cast<Index>(k));
  for (std::size_t j = 0; j < k; ++j) {
    comp(0, static_cast<Index>(j)) = -c[k - 1 - j] / c[k];
    if (j + 1 < k) comp(static_cast<Index>(j + 1), static_cast<Index>(j)) = 1.0;
  }
  const Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(comp, false);
  Index best = 0;
  es.eigenvalues().cwiseAbs().maxCoeff(&best);
  return es.eigenvalues()(best);
}

}  // namespace

// The eigenvalue of largest modulus of a real 2×2 matrix [[p, q], [r, s]]; of a complex pair,
// the one with Im >= 0.
cd dominant_eigenvalue_2x2(double p, double q, double r, double s) {
  const double half_tr = 0.5 * (p + s);
  const double det = p * s - q * r;
  const double disc = half_tr * half_tr - det;
  if (disc >= 0.0) {
    const double root = std::sqrt(disc);
    return {half_tr >= 0.0 ? half_tr + root : half_tr - root, 0.0};
  }
  return {half_tr, std::sqrt(-disc)};
}

// Spectral radius of a real 2×2 matrix [[p, q], [r, s]].
double spectral_radius_2x2(double p, double q, double r, double s) {
  const double half_tr = 0.5 * (p + s);
  const double det = p * s - q * r;
  const double disc = half_tr * half_tr - det;
  if (disc >= 0.0) return std::abs(half_tr) + std::sqrt(disc);
  return std::sqrt(det);  // complex pair, |μ|² = det
}

namespace {

// The first crossing of g(r) > 1 + stability_tolerance for r in (0, cap], scanning outward with
// steps of 0.2% (never more than 1e-6 absolute near the origin), then bisecting to ~1e-12.
// An instability that starts within r < 0.05 and persists towards the origin (g > 1 strictly
// at a tenth of the crossing) is "unstable arbitrarily close to 0": limit 0.
template <class G>
AxisLimit first_crossing(const G& g, double cap) {
  auto unstable = [&](double r) {
    const double v = g(r);
    return !(v <= 1.0 + stability_tolerance);  // NaN counts as unstable
  };
  double lo = 0.0;
  double r = 1e-6;
  while (r <= cap && !unstable(r)) {
    lo = r;
    r += std::max(2e-3 * r, 1e-6);
  }
  if (r > cap) {
    if (!unstable(cap)) return {cap, true};
    r = cap;
  }
  double hi = r;
  while (hi - lo > 1e-12 * hi) {
    const double mid = 0.5 * (lo + hi);
    (unstable(mid) ? hi : lo) = mid;
  }
  if (hi < 0.05 && g(0.1 * hi) > 1.0) return {0.0, false};
  return {lo, false};
}

using ld = long double;
using cld = std::complex<long double>;

ld horner_ld(const std::vector<ld>& c, ld x) {
  ld v = 0.0L;
  for (std::size_t k = c.size(); k-- > 0;) v = v * x + c[k];
  return v;
}

// Drops trailing coefficients at round-off level of the largest (a degree the exact method
// does not have, e.g. an FSAL stage with b = 0).
Polynomial trimmed(std::vector<ld> c) {
  ld big = 0.0L;
  for (ld x : c) big = std::max(big, std::abs(x));
  while (c.size() > 1 && std::abs(c.back()) <= 1e-14L * big) c.pop_back();
  return Polynomial(c.begin(), c.end());
}

// det(I − zM) = Σ c_k z^k: c_k are the coefficients of the characteristic polynomial
// det(λI − M) = Σ c_k λ^{s−k}, from the Faddeev–LeVerrier recursion in long double.
std::vector<ld> det_i_minus_zm(const Mat& m) {
  const Index s = m.rows();
  using MatL = Eigen::Matrix<ld, Eigen::Dynamic, Eigen::Dynamic>;
  const MatL ml = m.cast<ld>();
  MatL mk = MatL::Zero(s, s);
  std::vector<ld> c = {1.0L};
  for (Index k = 1; k <= s; ++k) {
    mk = ml * mk + c.back() * MatL::Identity(s, s);
    c.push_back(-(ml * mk).trace() / static_cast<ld>(k));
  }
  return c;
}

// The sign-change search of F (coefficients in ascending powers of t, F(0) = 0) on t > 0,
// described in the header. Returns the first t where F turns positive, 0 when F > 0 right
// after 0, and nullopt when F <= 0 on the whole half-line.
std::optional<ld> first_positive_crossing(std::vector<ld> f, const std::vector<ld>& bound) {
  // Coefficients within round-off of the terms that formed them are zero: the tableau's
  // coefficients are doubles, so the order conditions hold to ~1e-16 only.
  for (std::size_t k = 0; k < f.size(); ++k)
    if (std::abs(f[k]) <= 1e-11L * bound[k]) f[k] = 0.0L;
  std::size_t k0 = 0;
  while (k0 < f.size() && f[k0] == 0.0L) ++k0;
  if (k0 == f.size()) return std::nullopt;  // |R| = 1 on the whole ray
  if (f[k0] > 0.0L) return ld{0.0L};        // growth of order t^k0 next to 0
  // G(t) = F(t)/t^k0, G(0) < 0.
  std::vector<ld> g(f.begin() + static_cast<std::ptrdiff_t>(k0), f.end());
  while (g.size() > 1 && g.back() == 0.0L) g.pop_back();
  std::vector<ld> roots;
  const Index n = static_cast<Index>(g.size()) - 1;
  if (n >= 1) {
    Mat comp = Mat::Zero(n, n);
    for (Index j = 0; j < n; ++j) {
      comp(0, j) = static_cast<double>(-g[static_cast<std::size_t>(n - 1 - j)] /
                                       g[static_cast<std::size_t>(n)]);
      if (j + 1 < n) comp(j + 1, j) = 1.0;
    }
    const Eigen::EigenSolver<Mat> es(comp, false);
    for (Index j = 0; j < n; ++j) {
      const cd r = es.eigenvalues()(j);
      // Generous: a spurious candidate only adds one sign test.
      if (r.real() > 0.0 && std::abs(r.imag()) <= 1e-3 * std::abs(r))
        roots.push_back(static_cast<ld>(r.real()));
    }
  }
  std::sort(roots.begin(), roots.end());
  // Sign of G between consecutive candidates (at their midpoints) and beyond the last one.
  ld prev_mid = 0.0L;  // a point with G <= 0 (G(0) < 0)
  for (std::size_t i = 0; i < roots.size(); ++i) {
    const ld mid = i + 1 < roots.size() ? 0.5L * (roots[i] + roots[i + 1]) : 2.0L * roots[i] + 1.0L;
    if (horner_ld(g, mid) > 0.0L) {
      ld lo = prev_mid, hi = mid;  // G(lo) <= 0 < G(hi)
      for (int it = 0; it < 200 && hi - lo > 4 * std::numeric_limits<ld>::epsilon() * hi; ++it) {
        const ld m = 0.5L * (lo + hi);
        (horner_ld(g, m) > 0.0L ? hi : lo) = m;
      }
      return 0.5L * (lo + hi);
    }
    prev_mid = mid;
  }
  return std::nullopt;
}

// F(t) = |P(tu)|² − |Q(tu)|² and the sums of the magnitudes of its terms, per power of t.
void ray_polynomial(const RationalForm& r, cd unit, std::vector<ld>& f, std::vector<ld>& bound) {
  const cld u(unit.real(), unit.imag());
  auto powers = [&](const Polynomial& c) {
    std::vector<cld> out;
    cld up = 1.0L;
    for (double x : c) {
      out.push_back(static_cast<ld>(x) * up);
      up *= u;
    }
    return out;
  };
  const std::vector<cld> cp = powers(r.p), cq = powers(r.q);
  const std::size_t deg = 2 * (std::max(cp.size(), cq.size()) - 1);
  f.assign(deg + 1, 0.0L);
  bound.assign(deg + 1, 0.0L);
  auto add = [&](const std::vector<cld>& c, ld sign) {
    for (std::size_t j = 0; j < c.size(); ++j)
      for (std::size_t k = 0; k < c.size(); ++k) {
        f[j + k] += sign * (c[j] * std::conj(c[k])).real();
        bound[j + k] += std::abs(c[j]) * std::abs(c[k]);
      }
  };
  add(cp, 1.0L);
  add(cq, -1.0L);
}

// The limit from a polynomial in t = r^power (power 1 or 2).
AxisLimit limit_from_crossing(const std::optional<ld>& t, int power, double cap) {
  if (!t) return {cap, true, true};
  const double r = static_cast<double>(power == 2 ? std::sqrt(*t) : *t);
  if (r > cap) return {cap, true, true};
  return {r, false, true};
}

// Exact limit on the undamped oscillator of a kick/drift splitting: T(−w)² − 1 in w = (hω)².
AxisLimit half_trace_limit(const Polynomial& t, double cap) {
  std::vector<ld> tw(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) tw[k] = (k % 2 ? -1.0L : 1.0L) * static_cast<ld>(t[k]);
  std::vector<ld> f(2 * t.size() - 1, 0.0L), bound(f.size(), 0.0L);
  for (std::size_t j = 0; j < tw.size(); ++j)
    for (std::size_t k = 0; k < tw.size(); ++k) {
      f[j + k] += tw[j] * tw[k];
      bound[j + k] += std::abs(tw[j] * tw[k]);
    }
  f[0] -= 1.0L;
  bound[0] += 1.0L;
  return limit_from_crossing(first_positive_crossing(f, bound), 2, cap);
}

// Exact limit on the undamped oscillator of a 2×2 step map with half-trace T and determinant D
// (polynomials in x = −(hω)²): the first w = (hω)² where one of the Schur–Cohn conditions
// |D| <= 1, |2T| <= 1 + D fails, i.e. one of D − 1, −D − 1, 2T − 1 − D, −2T − 1 − D turns
// positive.
AxisLimit schur_limit(const Polynomial& half_trace, const Polynomial& det, double cap) {
  const std::size_t n = std::max(half_trace.size(), det.size());
  std::vector<ld> tw(n, 0.0L), dw(n, 0.0L);  // 2T and D in w = −x
  for (std::size_t k = 0; k < n; ++k) {
    const ld sign = k % 2 ? -1.0L : 1.0L;
    if (k < half_trace.size()) tw[k] = 2.0L * sign * static_cast<ld>(half_trace[k]);
    if (k < det.size()) dw[k] = sign * static_cast<ld>(det[k]);
  }
  std::optional<ld> first;
  for (const auto& [ct, cd_] : {std::pair{0.0L, 1.0L}, std::pair{0.0L, -1.0L},
                                std::pair{1.0L, -1.0L}, std::pair{-1.0L, -1.0L}}) {
    std::vector<ld> f(n), bound(n);
    for (std::size_t k = 0; k < n; ++k) {
      f[k] = ct * tw[k] + cd_ * dw[k];
      bound[k] = std::abs(tw[k]) + std::abs(dw[k]);
    }
    f[0] -= 1.0L;
    bound[0] += 1.0L;
    const std::optional<ld> w = first_positive_crossing(f, bound);
    if (w && (!first || *w < *first)) first = w;
  }
  return limit_from_crossing(first, 2, cap);
}

// The oscillator limit from the polynomial data of a kick/drift splitting or a partitioned pair.
AxisLimit polynomial_oscillator_limit(const LinearStability& s, double cap) {
  if (s.oscillator_determinant.empty()) return half_trace_limit(s.oscillator_half_trace, cap);
  return schur_limit(s.oscillator_half_trace, s.oscillator_determinant, cap);
}

// Eigenvalues with Im >= 0 only (the methods have real coefficients, so the amplification is
// symmetric under conjugation), sorted by decreasing modulus, near-duplicates removed.
std::vector<cd> distinct_upper(const std::vector<cd>& eigenvalues) {
  // Eigenvalues below 1e-6 of the largest modulus are taken as 0 (stable for every method with
  // R(0) = 1): a Jordan block of a pinned dof, [[0, 1], [0, 0]], comes out of a numerical
  // eigensolver as ±O(√ε·‖J‖). Growing modes (Re λ > 0 beyond round-off) are left out: see
  // the header.
  double largest = 0.0;
  for (const cd& l : eigenvalues)
    if (std::isfinite(l.real()) && std::isfinite(l.imag()))
      largest = std::max(largest, std::abs(l));
  std::vector<cd> out;
  for (const cd& l : eigenvalues)
    if (std::isfinite(l.real()) && std::isfinite(l.imag()) && std::abs(l) > 1e-6 * largest &&
        l.real() <= kGrowingModeTolerance * largest)
      out.emplace_back(std::abs(l.real()) <= kGrowingModeTolerance * largest ? 0.0 : l.real(),
                       std::abs(l.imag()));
  std::sort(out.begin(), out.end(), [](const cd& a, const cd& b) {
    if (std::abs(a) != std::abs(b)) return std::abs(a) > std::abs(b);
    return a.real() < b.real();
  });
  std::vector<cd> unique;
  for (const cd& l : out)
    if (unique.empty() || std::abs(l - unique.back()) > 1e-12 * std::max(1.0, std::abs(l)))
      unique.push_back(l);
  return unique;
}

// Amplification on one eigenvalue λ at h = r/|λ|, for a first-order or a mechanical system.
double amplification_on_ray(const LinearStability& s, cd unit, double r, bool mechanical) {
  if (!mechanical && s.amplification) return s.amplification(r * unit);
  // Mechanical: λ pairs with λ̄ as the oscillator a = −|λ|², b = 2 Re λ; a real λ (an
  // overdamped or free mode) is taken as x'' = λ x' (eigenvalues 0 and λ).
  if (unit.imag() > 0.0) return s.mechanical_amplification(-r * r, 2.0 * r * unit.real());
  return s.mechanical_amplification(0.0, r * unit.real());
}

}  // namespace

LinearStability tableau_stability(const ButcherTableau& t) {
  LinearStability s;
  s.kind = t.is_explicit() ? "explicit Runge-Kutta" : "implicit Runge-Kutta";
  s.amplification = [a = t.a, b = t.b](cd z) { return rk_amplification(a, b, z); };
  s.multiplier = [a = t.a, b = t.b](cd z) { return rk_multiplier(a, b, z); };
  s.rational = runge_kutta_rational_form(t.a, t.b);
  return with_mechanical_from_scalar(std::move(s));
}

LinearStability rosenbrock_stability(const Mat& alpha, const Mat& gamma, const Vec& b) {
  // On y' = λy the stages (I − zγ)k_i = z(y + Σ α_ij k_j) + z Σ_{j<i} γ_ij k_j are those of a
  // Runge–Kutta method with A = α + Γ (Hairer–Wanner II, §IV.7).
  LinearStability s;
  s.kind = "Rosenbrock";
  s.amplification = [a = Mat(alpha + gamma), b](cd z) { return rk_amplification(a, b, z); };
  s.multiplier = [a = Mat(alpha + gamma), b](cd z) { return rk_multiplier(a, b, z); };
  s.rational = runge_kutta_rational_form(alpha + gamma, b);
  return with_mechanical_from_scalar(std::move(s));
}

LinearStability multistep_stability(const std::vector<double>& alpha,
                                    const std::vector<double>& beta) {
  require_input(alpha.size() == beta.size() && alpha.size() >= 2,
                "multistep_stability: alpha and beta need the same length k + 1 >= 2");
  LinearStability s;
  s.kind = "linear multistep";
  s.state_levels = static_cast<int>(alpha.size()) - 1;
  s.amplification = [alpha, beta](cd z) {
    const cd mu = multistep_multiplier(alpha, beta, z);
    return std::isfinite(mu.real()) ? std::abs(mu) : kInf;
  };
  s.multiplier = [alpha, beta](cd z) { return multistep_multiplier(alpha, beta, z); };
  s.boundary_locus = [alpha, beta](double theta) {
    const cd zeta = std::polar(1.0, theta);
    cd rho = 0.0, sigma = 0.0, p = 1.0;
    for (std::size_t j = 0; j < alpha.size(); ++j, p *= zeta) {
      rho += alpha[j] * p;
      sigma += beta[j] * p;
    }
    return rho / sigma;
  };
  return with_mechanical_from_scalar(std::move(s));
}

namespace {
// The step matrix [m00, m01, m10, m11] of a kick/drift splitting on x'' = a x + b x' in the
// variables (x, u = h v): a kick u ← u + k(h²a x + hb u) and a drift x ← x + d u are 2×2
// matrices depending only on (h²a, hb); the step is their product.
std::array<double, 4> kick_drift_matrix(const std::vector<double>& kick,
                                        const std::vector<double>& drift, double h2a, double hb) {
  double m00 = 1, m01 = 0, m10 = 0, m11 = 1;
  for (std::size_t j = 0; j < kick.size(); ++j) {
    // kick: [[1, 0], [k h²a, 1 + k hb]] · M
    const double k = kick[j];
    const double n10 = k * h2a * m00 + (1 + k * hb) * m10;
    const double n11 = k * h2a * m01 + (1 + k * hb) * m11;
    m10 = n10;
    m11 = n11;
    // drift: [[1, d], [0, 1]] · M
    m00 += drift[j] * m10;
    m01 += drift[j] * m11;
  }
  return {m00, m01, m10, m11};
}
}  // namespace

LinearStability kick_drift_stability(const KickDriftCoefficients& c) {
  LinearStability s;
  s.kind = "splitting";
  s.mechanical_amplification = [kick = c.kick, drift = c.drift](double h2a, double hb) {
    const auto m = kick_drift_matrix(kick, drift, h2a, hb);
    return spectral_radius_2x2(m[0], m[1], m[2], m[3]);
  };
  s.mechanical_multiplier = [kick = c.kick, drift = c.drift](double h2a, double hb) {
    const auto m = kick_drift_matrix(kick, drift, h2a, hb);
    return dominant_eigenvalue_2x2(m[0], m[1], m[2], m[3]);
  };
  // The same product with polynomial entries in x = h²a at hb = 0, for the half-trace.
  using P = std::vector<ld>;
  auto mul_add = [](const P& a, const P& b, ld scale, int shift) {  // a + scale·x^shift·b
    P out = a;
    if (out.size() < b.size() + static_cast<std::size_t>(shift))
      out.resize(b.size() + static_cast<std::size_t>(shift), 0.0L);
    for (std::size_t k = 0; k < b.size(); ++k)
      out[k + static_cast<std::size_t>(shift)] += scale * b[k];
    return out;
  };
  P p00 = {1.0L}, p01 = {0.0L}, p10 = {0.0L}, p11 = {1.0L};
  for (std::size_t j = 0; j < c.kick.size(); ++j) {
    p10 = mul_add(p10, p00, c.kick[j], 1);  // kick: row 1 += k x · row 0
    p11 = mul_add(p11, p01, c.kick[j], 1);
    p00 = mul_add(p00, p10, c.drift[j], 0);  // drift: row 0 += d · row 1
    p01 = mul_add(p01, p11, c.drift[j], 0);
  }
  std::vector<ld> half = mul_add(p00, p11, 1.0L, 0);
  for (ld& x : half) x *= 0.5L;
  s.oscillator_half_trace = trimmed(half);
  return s;
}

namespace {
// The step matrix [m00, m01, m10, m11] of an additive pair on x'' = a x + b x' with x' = v in
// f_I, in the variables (x, u = h v): the 2s stage equations (header) solved for the two unit
// starting states.
std::array<double, 4> partitioned_matrix(const AdditiveTableau& t, double h2a, double hb) {
  const Mat& ae = t.explicit_table.a;
  const Mat& ai = t.implicit_table.a;
  const Index s = ae.rows();
  Mat m = Mat::Identity(2 * s, 2 * s);  // unknowns [X; U]
  m.topRightCorner(s, s) = -ai;
  m.bottomLeftCorner(s, s) = -h2a * ae;
  m.bottomRightCorner(s, s) -= hb * ae;
  Mat rhs = Mat::Zero(2 * s, 2);
  rhs.col(0).head(s).setOnes();  // (x_n, u_n) = (1, 0)
  rhs.col(1).tail(s).setOnes();  // (0, 1)
  const Mat xu = m.partialPivLu().solve(rhs);
  std::array<double, 4> out{};
  for (int c = 0; c < 2; ++c) {
    const Vec x = xu.col(c).head(s), u = xu.col(c).tail(s);
    out[static_cast<std::size_t>(c)] = (c == 0 ? 1.0 : 0.0) + t.implicit_table.b.dot(u);
    out[static_cast<std::size_t>(2 + c)] =
        (c == 1 ? 1.0 : 0.0) + t.explicit_table.b.dot(h2a * x + hb * u);
  }
  return out;
}

// The entries of the map at hb = 0 as polynomials in x = h²a (and, with `abs`, the same sums
// over the coefficients' magnitudes: the round-off bound of each coefficient). U solves
// U = c + x N U with N = A_E A_I strictly lower triangular, so U = Σ_{k<s} x^k N^k c.
std::array<std::vector<ld>, 4> partitioned_polynomials(const AdditiveTableau& t, bool abs) {
  using MatL = Eigen::Matrix<ld, Eigen::Dynamic, Eigen::Dynamic>;
  using VecL = Eigen::Matrix<ld, Eigen::Dynamic, 1>;
  auto cast = [abs](const auto& m) {
    MatL out = m.template cast<ld>();
    return abs ? MatL(out.cwiseAbs()) : out;
  };
  const MatL ae = cast(t.explicit_table.a), ai = cast(t.implicit_table.a);
  const MatL be = cast(Mat(t.explicit_table.b.transpose())),
             bi = cast(Mat(t.implicit_table.b.transpose()));
  const Index s = ae.rows();
  const MatL n = ae * ai;
  const VecL e = VecL::Ones(s), ae1 = ae * e;
  std::vector<ld> m00(s + 1, 0.0L), m01(s, 0.0L), m10(s + 2, 0.0L), m11(s + 1, 0.0L);
  m00[0] = m11[0] = 1.0L;
  m10[1] = (be * e)(0);
  VecL nk_e = e, nk_ae = ae1;  // N^k 1 and N^k A_E 1
  for (Index k = 0; k < s; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    m01[kk] = (bi * nk_e)(0);
    m11[kk + 1] = (be * ai * nk_e)(0);
    m00[kk + 1] = (bi * nk_ae)(0);
    m10[kk + 2] = (be * ai * nk_ae)(0);
    nk_e = n * nk_e;
    nk_ae = n * nk_ae;
  }
  return {m00, m01, m10, m11};
}

std::vector<ld> poly_product(const std::vector<ld>& a, const std::vector<ld>& b) {
  std::vector<ld> out(a.size() + b.size() - 1, 0.0L);
  for (std::size_t j = 0; j < a.size(); ++j)
    for (std::size_t k = 0; k < b.size(); ++k) out[j + k] += a[j] * b[k];
  return out;
}

std::vector<ld> poly_sum(std::vector<ld> a, const std::vector<ld>& b, ld scale) {
  if (a.size() < b.size()) a.resize(b.size(), 0.0L);
  for (std::size_t k = 0; k < b.size(); ++k) a[k] += scale * b[k];
  return a;
}

// A polynomial's coefficients, those at round-off level of `bound` set to zero, trailing zeros
// dropped.
Polynomial cleaned(std::vector<ld> c, const std::vector<ld>& bound) {
  for (std::size_t k = 0; k < c.size(); ++k)
    if (std::abs(c[k]) <= 1e-13L * bound[k]) c[k] = 0.0L;
  while (c.size() > 1 && c.back() == 0.0L) c.pop_back();
  return Polynomial(c.begin(), c.end());
}
}  // namespace

LinearStability partitioned_imex_stability(const AdditiveTableau& t) {
  LinearStability s;
  s.kind = "partitioned IMEX (x implicit, v explicit)";
  s.mechanical_amplification = [t](double h2a, double hb) {
    const auto m = partitioned_matrix(t, h2a, hb);
    return spectral_radius_2x2(m[0], m[1], m[2], m[3]);
  };
  s.mechanical_multiplier = [t](double h2a, double hb) {
    const auto m = partitioned_matrix(t, h2a, hb);
    return dominant_eigenvalue_2x2(m[0], m[1], m[2], m[3]);
  };
  // Polynomial entries exist when N = A_E A_I is nilpotent (A_E strictly lower, A_I lower).
  const Mat n = t.explicit_table.a * t.implicit_table.a;
  if (n.isLowerTriangular(0.0) && n.diagonal().isZero(0.0)) {
    const auto m = partitioned_polynomials(t, false), b = partitioned_polynomials(t, true);
    std::vector<ld> half = poly_sum(m[0], m[3], 1.0L), half_b = poly_sum(b[0], b[3], 1.0L);
    for (ld& x : half) x *= 0.5L;
    const std::vector<ld> det = poly_sum(poly_product(m[0], m[3]), poly_product(m[1], m[2]), -1.0L);
    const std::vector<ld> det_b =
        poly_sum(poly_product(b[0], b[3]), poly_product(b[1], b[2]), 1.0L);
    s.oscillator_half_trace = cleaned(half, half_b);
    s.oscillator_determinant = cleaned(det, det_b);
  }
  return s;
}

LinearStability with_mechanical_from_scalar(LinearStability s) {
  if (!s.amplification) return s;
  s.mechanical_amplification = [amp = s.amplification](double h2a, double hb) {
    // hλ are the roots of μ² − hb μ − h²a = 0.
    const cd root = std::sqrt(cd(0.25 * hb * hb + h2a, 0.0));
    return std::max(amp(0.5 * hb + root), amp(0.5 * hb - root));
  };
  if (s.multiplier) {
    s.mechanical_multiplier = [mult = s.multiplier](double h2a, double hb) {
      // std::sqrt gives the root with Im >= 0 for a negative discriminant, so hλ₊ is the
      // eigenvalue with Im >= 0 and, for real coefficients, R(hλ₊) the one of the conjugate
      // pair R(hλ₊), R(hλ₋) = conj R(hλ₊) with Im >= 0 (for small ν).
      const cd root = std::sqrt(cd(0.25 * hb * hb + h2a, 0.0));
      const cd plus = mult(0.5 * hb + root), minus = mult(0.5 * hb - root);
      const cd best = std::abs(minus) > std::abs(plus) ? minus : plus;
      return best.imag() < 0.0 ? std::conj(best) : best;
    };
  }
  return s;
}

RationalForm runge_kutta_rational_form(const Mat& a, const Vec& b) {
  const Index s = b.size();
  require_input(a.rows() == s && a.cols() == s,
                "runge_kutta_rational_form: A must be s x s with s = size of b");
  bool explicit_method = true;
  for (Index i = 0; i < s; ++i)
    for (Index j = i; j < s; ++j) explicit_method = explicit_method && a(i, j) == 0.0;
  RationalForm r;
  if (explicit_method) {
    // R(z) = 1 + Σ_k z^k bᵀA^{k−1}1 (A nilpotent): exact products, no recursion.
    using VecL = Eigen::Matrix<ld, Eigen::Dynamic, 1>;
    const auto al = a.cast<ld>();
    const VecL bl = b.cast<ld>();
    VecL v = VecL::Ones(s);
    std::vector<ld> p = {1.0L};
    for (Index k = 1; k <= s; ++k) {
      p.push_back(bl.dot(v));
      v = al * v;
    }
    r.p = trimmed(p);
    r.q = {1.0};
    return r;
  }
  // R = det(I − zA + z1bᵀ)/det(I − zA) (Hairer–Wanner II, Prop. IV.3.2).
  const Mat m = a - Vec::Ones(s) * b.transpose();
  r.p = trimmed(det_i_minus_zm(m));
  r.q = trimmed(det_i_minus_zm(a));
  return r;
}

double rational_modulus(const RationalForm& r, std::complex<double> z) {
  auto horner = [z](const Polynomial& c) {
    cd v = 0.0;
    for (auto it = c.rbegin(); it != c.rend(); ++it) v = v * z + *it;
    return v;
  };
  const double m = std::abs(horner(r.p) / horner(r.q));
  return std::isfinite(m) ? m : kInf;
}

Polynomial imaginary_axis_polynomial(const RationalForm& r) {
  std::vector<ld> f, bound;
  ray_polynomial(r, cd(0.0, 1.0), f, bound);
  Polynomial w;  // odd powers of y vanish: keep the even ones as powers of w = y²
  for (std::size_t k = 0; k < f.size(); k += 2)
    w.push_back(std::abs(f[k]) <= 1e-11L * bound[k] ? 0.0 : static_cast<double>(f[k]));
  return w;
}

AxisLimit rational_ray_limit(const RationalForm& r, std::complex<double> unit, double cap) {
  std::vector<ld> f, bound;
  ray_polynomial(r, unit, f, bound);
  // On the imaginary axis F is even in r: solve in w = r² (half the degree).
  bool even = true;
  for (std::size_t k = 1; k < f.size(); k += 2) even = even && std::abs(f[k]) <= 1e-11L * bound[k];
  if (even) {
    std::vector<ld> fw, bw;
    for (std::size_t k = 0; k < f.size(); k += 2) {
      fw.push_back(f[k]);
      bw.push_back(bound[k]);
    }
    return limit_from_crossing(first_positive_crossing(fw, bw), 2, cap);
  }
  return limit_from_crossing(first_positive_crossing(f, bound), 1, cap);
}

AxisLimit real_axis_limit(const LinearStability& s, double cap) {
  if (s.rational) return rational_ray_limit(*s.rational, cd(-1.0, 0.0), cap);
  if (!s.amplification) return {};
  return first_crossing([&](double r) { return s.amplification(cd(-r, 0.0)); }, cap);
}

AxisLimit imaginary_axis_limit(const LinearStability& s, double cap) {
  if (s.rational) return rational_ray_limit(*s.rational, cd(0.0, 1.0), cap);
  if (!s.amplification) return {};
  return first_crossing([&](double r) { return s.amplification(cd(0.0, r)); }, cap);
}

AxisLimit oscillator_limit(const LinearStability& s, double cap) {
  // The oscillator's eigenvalues are ±iω: for a one-step method the imaginary-axis limit.
  if (s.rational) return rational_ray_limit(*s.rational, cd(0.0, 1.0), cap);
  if (!s.oscillator_half_trace.empty()) return polynomial_oscillator_limit(s, cap);
  if (!s.mechanical_amplification) return {};
  return first_crossing([&](double r) { return s.mechanical_amplification(-r * r, 0.0); }, cap);
}

double max_amplification(const LinearStability& s, double h,
                         const std::vector<std::complex<double>>& eigenvalues, bool mechanical) {
  double worst = 0.0;
  for (const cd& l : distinct_upper(eigenvalues)) {
    const double m = std::abs(l);
    const double a = m == 0.0 ? 1.0 : amplification_on_ray(s, l / m, h * m, mechanical);
    if (!(a <= worst)) worst = a;  // NaN propagates as "worst"
  }
  return worst;
}

StepLimit predicted_step_limit(const LinearStability& s,
                               const std::vector<std::complex<double>>& eigenvalues,
                               bool mechanical, double h_cap, double rel_tol) {
  // The first h at which the largest amplification exceeds 1 is the smallest of the first
  // crossings of the single eigenvalues; each ray is scanned only up to the best h so far
  // (largest moduli first, so later scans are short).
  StepLimit best{h_cap, true};
  for (const cd& l : distinct_upper(eigenvalues)) {
    const double m = std::abs(l);
    if (m == 0.0) continue;
    const cd unit = l / m;
    // Exact where the method has a polynomial form: R = P/Q on the ray of λ (a mechanical
    // pair λ, λ̄ is the oscillator whose roots are hλ, hλ̄: the same ray), the half-trace on an
    // undamped oscillator; otherwise the sampled search.
    AxisLimit lim;
    if (s.rational) {
      lim = rational_ray_limit(*s.rational, unit, best.h * m);
    } else if (mechanical && l.real() == 0.0 && !s.oscillator_half_trace.empty()) {
      lim = polynomial_oscillator_limit(s, best.h * m);
    } else {
      lim = first_crossing([&](double r) { return amplification_on_ray(s, unit, r, mechanical); },
                           best.h * m);
      best.exact = false;
    }
    if (!lim.unbounded) best = {lim.limit / m, false, best.exact};
    if (best.h == 0.0) break;
  }
  (void)rel_tol;  // first_crossing bisects to ~1e-12 relative, finer than any rel_tol asked
  return best;
}

std::vector<std::vector<std::complex<double>>> region_boundary(const LinearStability& s,
                                                               double re_min, double re_max,
                                                               double im_min, double im_max,
                                                               int n) {
  std::vector<std::vector<cd>> lines;
  auto inside_box = [&](cd z) {
    return z.real() >= re_min && z.real() <= re_max && z.imag() >= im_min && z.imag() <= im_max;
  };
  if (s.boundary_locus) {
    // Multistep: the sampled locus, cut where it leaves the box or jumps (through infinity).
    const int samples = std::max(8 * n, 2000);
    std::vector<cd> cur;
    cd prev{};
    const double jump = 0.05 * std::max(re_max - re_min, im_max - im_min);
    for (int i = 0; i <= samples; ++i) {
      const cd z = s.boundary_locus(2.0 * std::numbers::pi * i / samples);
      const bool ok = std::isfinite(z.real()) && std::isfinite(z.imag()) && inside_box(z);
      if (!ok || (!cur.empty() && std::abs(z - prev) > jump)) {
        if (cur.size() > 1) lines.push_back(std::move(cur));
        cur.clear();
      }
      if (ok) cur.push_back(z);
      prev = z;
    }
    if (cur.size() > 1) lines.push_back(std::move(cur));
    return lines;
  }
  if (!s.amplification || n < 2) return lines;

  // Marching squares on φ(z) = |R(z)| − 1 (poles and NaN count as +1: outside). One-step
  // methods evaluate their rational form R = P/Q (formed once: two Horner sums per point, where
  // the amplification solves an s×s system); the others their amplification.
  const double dx = (re_max - re_min) / n, dy = (im_max - im_min) / n;
  auto at = [&](int i, int j) { return cd(re_min + i * dx, im_min + j * dy); };
  const std::function<double(cd)> modulus =
      s.rational
          ? std::function<double(cd)>([r = *s.rational](cd z) { return rational_modulus(r, z); })
          : s.amplification;
  auto phi = [&](cd z) {
    const double v = modulus(z) - 1.0;
    return std::isfinite(v) ? std::min(v, 1.0) : 1.0;
  };
  std::vector<double> grid(static_cast<std::size_t>((n + 1) * (n + 1)));
  auto g = [&](int i, int j) -> double& { return grid[static_cast<std::size_t>(j * (n + 1) + i)]; };
  for (int j = 0; j <= n; ++j) {
    poll_run_control();  // a large tableau or grid stops at an interrupt or --max-wall
    for (int i = 0; i <= n; ++i) g(i, j) = phi(at(i, j));
  }

  // Crossing on the edge between two grid nodes, refined by bisection on φ.
  auto crossing = [&](cd za, double fa, cd zb) {
    for (int it = 0; it < 40; ++it) {
      const cd zm = 0.5 * (za + zb);
      const double fm = phi(zm);
      if ((fm > 0) == (fa > 0)) {
        za = zm;
        fa = fm;
      } else {
        zb = zm;
      }
    }
    return 0.5 * (za + zb);
  };
  // Segments, each between crossings on two edges of one cell; then chained into polylines.
  std::vector<std::pair<cd, cd>> segs;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::array<std::pair<int, int>, 4> corner = {
          {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}}};
      std::vector<cd> pts;
      for (int e = 0; e < 4; ++e) {
        const auto [ia, ja] = corner[static_cast<std::size_t>(e)];
        const auto [ib, jb] = corner[static_cast<std::size_t>((e + 1) % 4)];
        const double fa = g(ia, ja), fb = g(ib, jb);
        if ((fa > 0) != (fb > 0)) pts.push_back(crossing(at(ia, ja), fa, at(ib, jb)));
      }
      if (pts.size() == 2) {
        segs.emplace_back(pts[0], pts[1]);
      } else if (pts.size() == 4) {  // saddle: pair by the centre value
        const bool centre_in = phi(at(i, j) + cd(0.5 * dx, 0.5 * dy)) > 0;
        const bool first_in = g(i, j) > 0;
        if (centre_in == first_in) {
          segs.emplace_back(pts[0], pts[1]);
          segs.emplace_back(pts[2], pts[3]);
        } else {
          segs.emplace_back(pts[0], pts[3]);
          segs.emplace_back(pts[1], pts[2]);
        }
      }
    }
  }
  // Chain: endpoints of neighbouring segments coincide (same edge, same bisection).
  const double eps = 1e-9 * std::max(dx, dy);
  std::vector<bool> used(segs.size(), false);
  auto same = [&](cd a, cd b) { return std::abs(a - b) <= eps; };
  // Index endpoints by a coarse key for O(n) chaining.
  std::multimap<std::pair<long, long>, std::size_t> by_end;
  auto key = [&](cd z) {
    return std::make_pair(std::lround((z.real() - re_min) / (0.25 * dx)),
                          std::lround((z.imag() - im_min) / (0.25 * dy)));
  };
  for (std::size_t k = 0; k < segs.size(); ++k) {
    by_end.emplace(key(segs[k].first), k);
    by_end.emplace(key(segs[k].second), k);
  }
  auto take_next = [&](cd end) -> std::optional<cd> {
    const auto [lo, hi] = by_end.equal_range(key(end));
    for (auto it = lo; it != hi; ++it) {
      const std::size_t k = it->second;
      if (used[k]) continue;
      if (same(segs[k].first, end)) {
        used[k] = true;
        return segs[k].second;
      }
      if (same(segs[k].second, end)) {
        used[k] = true;
        return segs[k].first;
      }
    }
    return std::nullopt;
  };
  for (std::size_t k = 0; k < segs.size(); ++k) {
    if (used[k]) continue;
    used[k] = true;
    std::vector<cd> fwd = {segs[k].first, segs[k].second};
    while (auto nx = take_next(fwd.back())) fwd.push_back(*nx);
    std::vector<cd> back;
    while (auto nx = take_next(back.empty() ? fwd.front() : back.back())) back.push_back(*nx);
    std::vector<cd> line(back.rbegin(), back.rend());
    line.insert(line.end(), fwd.begin(), fwd.end());
    lines.push_back(std::move(line));
  }
  return lines;
}

std::optional<bool> a_stable_exact(const LinearStability& s) {
  if (!s.rational) return std::nullopt;
  if (!rational_ray_limit(*s.rational, cd(0.0, 1.0), kInf).unbounded) return false;
  const Polynomial& q = s.rational->q;
  const Index n = static_cast<Index>(q.size()) - 1;
  if (n < 1) return s.rational->p.size() <= 1;  // R a polynomial: A-stable only if constant
  Mat comp = Mat::Zero(n, n);
  for (Index j = 0; j < n; ++j) {
    comp(0, j) = -q[static_cast<std::size_t>(n - 1 - j)] / q[static_cast<std::size_t>(n)];
    if (j + 1 < n) comp(j + 1, j) = 1.0;
  }
  const Eigen::EigenSolver<Mat> es(comp, false);
  for (Index j = 0; j < n; ++j)
    if (!(es.eigenvalues()(j).real() > 0.0)) return false;
  return true;
}

bool a_stable_on_samples(const LinearStability& s, double r, int n) {
  if (!s.amplification) return false;
  auto ok = [&](cd z) { return s.amplification(z) <= 1.0 + stability_tolerance; };
  for (int j = 0; j < n; ++j) {
    poll_run_control();
    const double im = -r + 2.0 * r * j / (n - 1);
    if (!ok(cd(0.0, im))) return false;
    for (int i = 0; i < n; ++i)
      if (!ok(cd(-r * i / (n - 1), im))) return false;
  }
  // Near the origin on a log-polar grid (|z| from 1e-3 to r, arguments π/2..3π/2).
  for (int i = 0; i < n; ++i) {
    const double m = 1e-3 * std::pow(r / 1e-3, static_cast<double>(i) / (n - 1));
    for (int j = 0; j < n; ++j) {
      const double arg = std::numbers::pi * (0.5 + static_cast<double>(j) / (n - 1));
      if (!ok(std::polar(m, arg))) return false;
    }
  }
  return true;
}

Polynomial poly_multiply(const Polynomial& a, const Polynomial& b) {
  if (a.empty() || b.empty()) return {};
  Polynomial c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}

namespace {
// P(z/k)^k (coefficients in ascending powers of z).
Polynomial scaled_power(Polynomial p, int k) {
  double f = 1.0;
  for (double& c : p) {
    c *= f;
    f /= k;
  }
  Polynomial r{1.0};
  for (int i = 0; i < k; ++i) r = poly_multiply(r, p);
  return r;
}
}  // namespace

LinearStability substepped(const LinearStability& s, int k) {
  if (k == 1) return s;
  if (!s.amplification || s.boundary_locus || !s.oscillator_half_trace.empty())
    throw std::logic_error("substepped: only one-step methods with R(z) have R(z/k)^k");
  LinearStability out;
  out.kind = s.kind + ", " + std::to_string(k) + " substeps of h/" + std::to_string(k);
  const auto amp = s.amplification;
  out.amplification = [amp, k](std::complex<double> z) {
    return std::pow(amp(z / static_cast<double>(k)), k);
  };
  if (s.multiplier)
    out.multiplier = [mult = s.multiplier, k](std::complex<double> z) {
      return std::pow(mult(z / static_cast<double>(k)), k);
    };
  if (s.rational)
    out.rational = RationalForm{scaled_power(s.rational->p, k), scaled_power(s.rational->q, k)};
  return with_mechanical_from_scalar(std::move(out));
}

OscillatorResponse oscillator_response(std::complex<double> multiplier, double nu) {
  OscillatorResponse r;
  r.nu = nu;
  r.amplification = std::abs(multiplier);
  r.phase = std::abs(std::arg(multiplier));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.damping_ratio = r.phase > 0.0 ? -std::log(r.amplification) / r.phase + 0.0 : nan;  // no -0
  r.period_error = r.phase > 0.0 ? nu / r.phase - 1.0 : kInf;
  r.frequency_error = r.phase / nu - 1.0;
  return r;
}

std::optional<OscillatorResponse> oscillator_response(const LinearStability& s, double nu) {
  if (!s.mechanical_multiplier) return std::nullopt;
  return oscillator_response(s.mechanical_multiplier(-nu * nu, 0.0), nu);
}

}  // namespace stiffbench
