// Linear stability from coefficients (core/theory/linear_stability.hpp): axis limits against their
// closed forms, A-stability, region boundaries, and — as an independent check of every
// method's stability data — the spectral radius of the step map measured by stepping the
// registered integrator on a 1-DOF oscillator.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "core/run_control.hpp"
#include "core/theory/linear_stability.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

LinearStability stability_of(const std::string& name) {
  auto integ = make(name);
  auto s = integ->linear_stability();
  if (!s) throw std::logic_error(name + " has no linear stability data");
  return *s;
}

// Closed forms: rk4 |R(iy)|² = 1 − y⁶/72 + y⁸/576 → y = 2√2; kutta3 |R(iy)|² = 1 − y⁴/12 +
// y⁶/36 → y = √3; heun R(−x) = 1 − x + x²/2 = 1 → x = 2; euler R(−x) = −1 → x = 2. The real
// limits of rk4 and kutta3 are where |R(−x)| = 1 (rk4: R = +1, kutta3: R = −1), quoted in
// docs/reference-values.md as 2.7853 and 2.5127; refined here by bisection on the polynomial on [2,
// 3].
double real_limit_of_polynomial(const std::vector<double>& taylor) {
  auto g = [&](double x) {
    double r = 0.0;
    for (std::size_t k = 0; k < taylor.size(); ++k)
      r += taylor[k] * std::pow(-x, static_cast<double>(k));
    return std::abs(r) - 1.0;
  };
  double lo = 2.0, hi = 3.0;  // g(2) < 0 < g(3) for both polynomials
  for (int it = 0; it < 60; ++it) (g(0.5 * (lo + hi)) < 0 ? lo : hi) = 0.5 * (lo + hi);
  return lo;
}

TEST(LinearStability, ExplicitAxisLimitsMatchClosedForms) {
  const double rk4_real = real_limit_of_polynomial({1, 1, 0.5, 1.0 / 6, 1.0 / 24});
  const double kutta3_real = real_limit_of_polynomial({1, 1, 0.5, 1.0 / 6});
  EXPECT_NEAR(rk4_real, 2.7853, 1e-4);  // the published figure
  EXPECT_NEAR(kutta3_real, 2.5127, 1e-4);

  const auto rk4 = stability_of("rk4");
  EXPECT_NEAR(imaginary_axis_limit(rk4).limit, 2.0 * std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(real_axis_limit(rk4).limit, rk4_real, 1e-6);
  const auto kutta3 = stability_of("kutta3");
  EXPECT_NEAR(imaginary_axis_limit(kutta3).limit, std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(real_axis_limit(kutta3).limit, kutta3_real, 1e-6);
  const auto heun = stability_of("heun");
  EXPECT_NEAR(real_axis_limit(heun).limit, 2.0, 1e-6);
  // Heun and Euler are unstable arbitrarily close to 0 on the imaginary axis
  // (|R(iy)|² = 1 + y⁴/4 and 1 + y²).
  EXPECT_EQ(imaginary_axis_limit(heun).limit, 0.0);
  const auto euler = stability_of("euler");
  EXPECT_NEAR(real_axis_limit(euler).limit, 2.0, 1e-6);
  EXPECT_EQ(imaginary_axis_limit(euler).limit, 0.0);
  EXPECT_EQ(oscillator_limit(euler).limit, 0.0);
  EXPECT_FALSE(real_axis_limit(euler).unbounded);
}

TEST(LinearStability, SymplecticOscillatorIntervals) {
  // Symplectic Euler and Störmer–Verlet on x'' = −ω²x: trace of the step map 2 − (hω)², stable
  // for hω <= 2 (Hairer–Lubich–Wanner I.5); rk4 on the oscillator is its imaginary-axis limit.
  for (const char* name :
       {"symplectic_euler", "symplectic_euler_x", "velocity_verlet", "verlet", "leapfrog"}) {
    SCOPED_TRACE(name);
    const AxisLimit lim = oscillator_limit(stability_of(name));
    EXPECT_NEAR(lim.limit, 2.0, 1e-6);
    EXPECT_FALSE(lim.unbounded);
  }
  EXPECT_NEAR(oscillator_limit(stability_of("rk4")).limit, 2.0 * std::sqrt(2.0), 1e-6);
  EXPECT_TRUE(oscillator_limit(stability_of("implicit_midpoint")).unbounded);
}

TEST(LinearStability, ImplicitMethodsAreAStableExplicitAreNot) {
  for (const char* name :
       {"backward_euler", "sdirk2", "sdirk3", "bdf2", "trapezoidal", "implicit_midpoint",
        "semi_implicit_euler", "rosenbrock2", "baraff_witkin"}) {
    SCOPED_TRACE(name);
    const auto s = stability_of(name);
    EXPECT_TRUE(a_stable_on_samples(s));
    EXPECT_TRUE(real_axis_limit(s).unbounded);
  }
  for (const char* name : {"euler", "heun", "rk4", "kutta3"}) {
    SCOPED_TRACE(name);
    EXPECT_FALSE(a_stable_on_samples(stability_of(name)));
  }
}

TEST(LinearStability, Bdf2BoundaryLocus) {
  // ρ(ζ) = ζ² − 4/3 ζ + 1/3, σ(ζ) = 2/3 ζ²: z(π) = ρ(−1)/σ(−1) = (8/3)/(2/3) = 4, z(0) = 0; the
  // largest root modulus at z = 4 is exactly 1, at z = 2 (inside the unstable bubble) above 1.
  const auto s = stability_of("bdf2");
  ASSERT_TRUE(s.boundary_locus);
  EXPECT_NEAR(std::abs(s.boundary_locus(std::numbers::pi) - 4.0), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(s.boundary_locus(0.0)), 0.0, 1e-12);
  EXPECT_NEAR(s.amplification(4.0), 1.0, 1e-9);
  EXPECT_GT(s.amplification(2.0), 1.0);
  EXPECT_LT(s.amplification(-2.0), 1.0);
}

TEST(LinearStability, RegionBoundaryLiesOnUnitModulus) {
  const auto rk4 = stability_of("rk4");
  const auto lines = region_boundary(rk4, -4, 1, -4, 4, 120);
  ASSERT_FALSE(lines.empty());
  std::size_t points = 0;
  double best_real = 1e9, best_imag = 1e9;
  for (const auto& line : lines) {
    for (const auto& z : line) {
      ++points;
      EXPECT_NEAR(rk4.amplification(z), 1.0, 1e-8);
      if (std::abs(z.imag()) < 0.05) best_real = std::min(best_real, z.real());
      if (std::abs(z.real()) < 0.05)
        best_imag = std::min(best_imag, std::abs(std::abs(z.imag()) - 2.0 * std::sqrt(2.0)));
    }
  }
  EXPECT_GT(points, 200u);
  // The closed curve crosses the negative real axis at −2.7853 and the imaginary axis near ±2√2.
  EXPECT_NEAR(best_real, -2.7853, 0.01);
  EXPECT_LT(best_imag, 0.05);
  // The rk4 region is one closed curve (chained by the marching squares into few polylines).
  EXPECT_LE(lines.size(), 4u);
}

// The grid evaluates R = P/Q (Horner) where a rational form exists. Independent check: the same
// boundary traced on the amplification alone (an s×s complex solve per point, the rational form
// removed) lies on the same curve, for implicit methods with poles in the box too. (Not for
// Gauss methods: their boundary is the imaginary axis, where |R| − 1 is round-off of either
// sign, so the traced segments there are noise in both evaluations.) Each crossing is bisected
// 40 times on a cell of 0.1, to about 1e-13; 1e-9 leaves room for the two evaluations' round-off.
TEST(LinearStability, RegionFromTheRationalFormMatchesTheStageSolve) {
  for (const std::string name : {"radau5", "esdirk43", "sdirk2", "rk4", "dopri5"}) {
    const auto with = stability_of(name);
    ASSERT_TRUE(with.rational.has_value()) << name;
    auto without = with;
    without.rational.reset();
    const auto a = region_boundary(with, -8, 8, -8, 8, 160);
    const auto b = region_boundary(without, -8, 8, -8, 8, 160);
    ASSERT_EQ(a.size(), b.size()) << name;
    for (std::size_t k = 0; k < a.size(); ++k) {
      ASSERT_EQ(a[k].size(), b[k].size()) << name;
      for (std::size_t i = 0; i < a[k].size(); ++i)
        EXPECT_LT(std::abs(a[k][i] - b[k][i]), 1e-9) << name;
    }
    // and each point is on |R| = 1 by the stage solve
    for (const auto& line : a)
      for (const auto& z : line) EXPECT_NEAR(with.amplification(z), 1.0, 1e-8) << name;
  }
}

// A row past its wall-clock limit stops the grid at its next row (core/run_control.hpp): the
// clock is started with a limit already passed, so nothing here depends on speed.
TEST(LinearStability, RegionBoundaryStopsWhenTheRowClockExpired) {
  const auto radau = stability_of("radau5");
  const RowClock clock(1e-9);
  while (!RowClock::expired()) {
  }
  EXPECT_THROW(region_boundary(radau, -8, 8, -8, 8, 100), WallLimitExceeded);
  EXPECT_THROW(a_stable_on_samples(radau), WallLimitExceeded);
}

// Step map of a registered integrator on m x'' + γ x' + k x = 0, measured by stepping from the
// unit states; its spectral radius must match mechanical_amplification(−h²k/m, −hγ/m).
double measured_radius(const std::string& name, double k, double gamma, double h) {
  const std::vector<std::string> p = {"k=" + std::to_string(k), "gamma=" + std::to_string(gamma)};
  auto sys = model("harmonic_oscillator", p);
  double s[2][2];
  for (int col = 0; col < 2; ++col) {
    auto integ = make(name);
    Vec y = Vec::Zero(2);
    y(col) = 1.0;
    integ->reset(*sys, 0.0, y);
    SolveStats stats;
    EXPECT_EQ(integ->step(*sys, 0.0, y, h, stats), Status::ok);
    s[0][col] = y(0);
    s[1][col] = y(1);
  }
  const double tr = s[0][0] + s[1][1], det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
  const double disc = tr * tr / 4 - det;
  return disc >= 0 ? std::abs(tr) / 2 + std::sqrt(disc) : std::sqrt(det);
}

TEST(LinearStability, StepMapOfEveryOneStepMethodMatchesItsStabilityData) {
  int checked = 0;
  for (const auto& e : integrator_registry().entries()) {
    const std::string& name = e.info.name;
    auto integ = make(name);
    const auto s = integ->linear_stability();
    if (!s || name == "bdf2") continue;  // bdf2: a two-step map, checked by its locus above
    for (const double gamma : {0.0, 0.7}) {
      for (const double h : {0.1, 0.6, 0.75}) {  // ω = 3: hω = 0.3, 1.8, 2.25
        const double k = 9.0;
        double measured = 0.0;
        try {
          measured = measured_radius(name, k, gamma, h);
        } catch (const BadInput&) {
          continue;  // the method refuses damped systems (Verlet forms)
        }
        SCOPED_TRACE(name + " gamma=" + std::to_string(gamma) + " h=" + std::to_string(h));
        EXPECT_NEAR(s->mechanical_amplification(-h * h * k, -h * gamma), measured, 1e-8);
        ++checked;
      }
    }
  }
  // 8 explicit tableaux, 5 DIRK, semi-implicit Euler, rosenbrock2, Baraff-Witkin: 6 cases
  // each; 3 symplectic splittings + verlet + leapfrog: at least the 3 undamped cases.
  EXPECT_GE(checked, 16 * 6 + 5 * 3);
}

TEST(LinearStability, MultiplierIsTheEigenvalueWhoseModulusIsTheAmplification) {
  // The complex multiplier and the modulus are computed separately (R(z) and |R(z)|, the
  // companion matrix's root and its modulus, the 2×2 kick/drift matrix's eigenvalue and its
  // spectral radius): they must agree for every method, damped oscillators included.
  int checked = 0;
  for (const auto& e : integrator_registry().entries()) {
    auto integ = make(e.info.name);
    const auto s = integ->linear_stability();
    if (!s) continue;
    ASSERT_TRUE(s->mechanical_multiplier) << e.info.name;
    for (const double h2a : {-0.01, -1.0, -3.5})
      for (const double hb : {0.0, -0.3}) {
        const std::complex<double> mu = s->mechanical_multiplier(h2a, hb);
        EXPECT_NEAR(std::abs(mu), s->mechanical_amplification(h2a, hb), 1e-12)
            << e.info.name << " h2a " << h2a << " hb " << hb;
        EXPECT_GE(mu.imag(), 0.0) << e.info.name;
        ++checked;
      }
    if (s->multiplier) {
      for (const std::complex<double> z :
           {std::complex<double>(-0.5, 0.3), {0.0, 1.2}, {-3.0, 0.0}})
        EXPECT_NEAR(std::abs(s->multiplier(z)), s->amplification(z), 1e-12) << e.info.name;
    }
  }
  EXPECT_GE(checked, 20 * 6);
}

TEST(LinearStability, OscillatorResponseDefinitions) {
  // μ = e^{iν}: the exact flow (no damping, no period error). μ = e^{(−ξ + i)θ}: damping ratio ξ
  // by the definition −ln|μ|/arg μ, period error ν/θ − 1.
  const OscillatorResponse exact = oscillator_response(std::polar(1.0, 0.7), 0.7);
  EXPECT_NEAR(exact.amplification, 1.0, 1e-15);
  EXPECT_NEAR(exact.damping_ratio, 0.0, 1e-15);
  EXPECT_NEAR(exact.period_error, 0.0, 1e-15);
  const double xi = 0.05, theta = 0.4, nu = 0.5;
  const OscillatorResponse r =
      oscillator_response(std::exp(std::complex<double>(-xi, 1.0) * theta), nu);
  EXPECT_NEAR(r.damping_ratio, xi, 1e-14);
  EXPECT_NEAR(r.period_error, nu / theta - 1.0, 1e-14);
  EXPECT_NEAR(r.frequency_error, theta / nu - 1.0, 1e-14);
  // Backward Euler from its coefficients: μ = 1/(1 − iν).
  const auto be = oscillator_response(stability_of("backward_euler"), 2.0);
  ASSERT_TRUE(be);
  EXPECT_NEAR(be->amplification, 1.0 / std::sqrt(5.0), 1e-14);
  EXPECT_NEAR(be->phase, std::atan(2.0), 1e-14);
  // k substeps: R(z/k)^k.
  const LinearStability sub = substepped(stability_of("backward_euler"), 4);
  const std::complex<double> z(0.0, 2.0);
  EXPECT_NEAR(std::abs(sub.multiplier(z) - std::pow(1.0 / (1.0 - z / 4.0), 4)), 0.0, 1e-14);
}

TEST(LinearStability, PredictedStepOnTheFixedChainSpectrum) {
  // Fixed–fixed chain, k = m = 1, N = 10: ω_j = 2 sin(jπ/22), eigenvalues ±iω_j
  // (docs/reference-values.md, ω_max = 1.979643). Verlet-type methods: h = 2/ω_max; rk4: 2√2/ω_max.
  std::vector<std::complex<double>> eig;
  for (int j = 1; j <= 10; ++j) {
    const double w = 2.0 * std::sin(j * std::numbers::pi / 22.0);
    eig.emplace_back(0.0, w);
    eig.emplace_back(0.0, -w);
  }
  const double wmax = 2.0 * std::sin(10 * std::numbers::pi / 22.0);
  EXPECT_NEAR(wmax, 1.979643, 1e-6);
  auto pred = [&](const char* name) {
    return predicted_step_limit(stability_of(name), eig, true, 100.0);
  };
  EXPECT_NEAR(pred("velocity_verlet").h, 2.0 / wmax, 1e-8);
  EXPECT_NEAR(pred("symplectic_euler").h, 2.0 / wmax, 1e-8);
  EXPECT_NEAR(pred("rk4").h, 2.0 * std::sqrt(2.0) / wmax, 1e-8);
  EXPECT_EQ(pred("euler").h, 0.0);
  EXPECT_FALSE(pred("euler").unbounded);
  EXPECT_TRUE(pred("backward_euler").unbounded);
  // A growing mode of the model itself (Re λ > 0, e.g. a buckling pair ±0.3) is unstable for
  // every method and is left out: the limit is still set by the oscillating modes.
  auto with_growing = eig;
  with_growing.emplace_back(0.3, 0.0);
  with_growing.emplace_back(-0.3, 0.0);
  EXPECT_NEAR(predicted_step_limit(stability_of("velocity_verlet"), with_growing, true, 100.0).h,
              2.0 / wmax, 1e-8);
  EXPECT_TRUE(
      predicted_step_limit(stability_of("backward_euler"), with_growing, true, 100.0).unbounded);
  // Same answer from the first-order view (amplification on hλ) for the one-step methods.
  EXPECT_NEAR(predicted_step_limit(stability_of("rk4"), eig, false, 100.0).h,
              2.0 * std::sqrt(2.0) / wmax, 1e-8);
}

// Exact limits from R = P/Q (polynomial roots, not sampling). Independent values:
//   rk4: |R(iy)|² − 1 = −y⁶/72 + y⁸/576 → y = 2√2; R(−x) = 1 ⇔ x³ − 4x² + 12x − 24 = 0, whose
//     real root 2.785293563405281623... was bisected in exact rational arithmetic (Python
//     fractions, 120 halvings of [2, 3]);
//   kutta3: y = √3; heun: |R(iy)|² = 1 + y⁴/4, euler: 1 + y² → 0; euler R(−2) = −1 → 2.
//   dopri5, cash_karp, rkf45: P from bᵀA^{k−1}1 in exact rationals (Python fractions, the
//     tableaux as published by Dormand & Prince 1980, Cash & Karp 1990, Fehlberg 1969):
//     dopri5 P = Σ_{k<=5} z^k/k! + z⁶/600, |P(iy)|² − 1 = −w³/1800 + w⁴/1600 − w⁵/14400 +
//     w⁶/360000 (w = y²), first positive root bisected in rationals: y = 0.997189008632529915...
//     (the figure 0.9972 of Hairer, Nørsett & Wanner I, Sect. II.4, rounds it); cash_karp
//     P = ... + z⁶/800, |P|² − 1 = +w³/3600 + ...; rkf45 (fourth-order solution) P = ... +
//     z⁵/104, |P|² − 1 = +5w³/936 + ...: a positive lowest-order coefficient, |R(iy)| > 1 for
//     every small y > 0, limit 0.
TEST(LinearStability, ExactAxisLimitsFromPolynomialRoots) {
  const double rk4_real = 2.785293563405281623;
  const auto rk4 = stability_of("rk4");
  ASSERT_TRUE(rk4.rational);
  EXPECT_TRUE(imaginary_axis_limit(rk4).exact);
  EXPECT_NEAR(imaginary_axis_limit(rk4).limit, 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(real_axis_limit(rk4).limit, rk4_real, 1e-12);
  EXPECT_NEAR(imaginary_axis_limit(stability_of("kutta3")).limit, std::sqrt(3.0), 1e-12);
  EXPECT_EQ(imaginary_axis_limit(stability_of("heun")).limit, 0.0);
  const auto euler = stability_of("euler");
  EXPECT_EQ(imaginary_axis_limit(euler).limit, 0.0);
  EXPECT_NEAR(real_axis_limit(euler).limit, 2.0, 1e-13);  // the sampled search gave 2 + 1e-9

  const AxisLimit dopri5 = imaginary_axis_limit(stability_of("dopri5"));
  EXPECT_TRUE(dopri5.exact);
  EXPECT_FALSE(dopri5.unbounded);
  EXPECT_NEAR(dopri5.limit, 0.997189008632529915, 1e-12);
  for (const char* name : {"cash_karp", "rkf45"}) {
    SCOPED_TRACE(name);
    const auto s = stability_of(name);
    EXPECT_EQ(imaginary_axis_limit(s).limit, 0.0);
    EXPECT_FALSE(imaginary_axis_limit(s).unbounded);
    EXPECT_EQ(oscillator_limit(s).limit, 0.0);
  }
  // The sign of the lowest-order coefficient of |P(iy)|² − 1 in w = y² decides it.
  const Polynomial ck = imaginary_axis_polynomial(*stability_of("cash_karp").rational);
  const Polynomial fehlberg = imaginary_axis_polynomial(*stability_of("rkf45").rational);
  const Polynomial dp = imaginary_axis_polynomial(*stability_of("dopri5").rational);
  ASSERT_GE(ck.size(), 4u);
  ASSERT_GE(fehlberg.size(), 4u);
  ASSERT_GE(dp.size(), 4u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(ck[k], 0.0);
    EXPECT_EQ(fehlberg[k], 0.0);
    EXPECT_EQ(dp[k], 0.0);
  }
  EXPECT_NEAR(ck[3], 1.0 / 3600.0, 1e-15);
  EXPECT_NEAR(fehlberg[3], 5.0 / 936.0, 1e-15);
  EXPECT_NEAR(dp[3], -1.0 / 1800.0, 1e-15);
}

TEST(LinearStability, ExactLimitsOfRationalImplicitMethods) {
  // θ-method as a two-stage tableau A = [[0, 0], [1 − θ, θ]], b = (1 − θ, θ):
  // R = (1 + (1 − θ)z)/(1 − θz). R(−x) = −1 ⇔ x = 2/(1 − 2θ) for θ < 1/2; on the imaginary
  // axis |P|² − |Q|² = ((1 − θ)² − θ²) y² > 0, so the limit is 0 (Hairer–Wanner II, IV.3).
  for (const double theta : {0.0, 0.25, 0.4}) {
    SCOPED_TRACE(theta);
    ButcherTableau t;
    t.name = "theta";
    t.a = Mat{{0.0, 0.0}, {1.0 - theta, theta}};
    t.b = Vec{{1.0 - theta, theta}};
    t.c = Vec{{0.0, 1.0}};
    t.order = 1;
    const auto s = tableau_stability(t);
    ASSERT_TRUE(s.rational);
    EXPECT_NEAR(real_axis_limit(s).limit, 2.0 / (1.0 - 2.0 * theta), 1e-12);
    EXPECT_EQ(a_stable_exact(s), std::optional<bool>(false));
    EXPECT_EQ(imaginary_axis_limit(s).limit, 0.0);
    // R = P/Q itself: P = 1 + (1 − θ)z, Q = 1 − θz.
    EXPECT_NEAR(s.rational->p.at(1), 1.0 - theta, 1e-15);
    if (theta > 0) {
      EXPECT_NEAR(s.rational->q.at(1), -theta, 1e-15);
    }
  }
  // θ >= 1/2: A-stable (pole 1/θ > 0, |R(iy)|² − 1 = (1 − 2θ)y²/|Q|² <= 0).
  for (const double theta : {0.5, 0.75, 1.0}) {
    ButcherTableau t;
    t.a = Mat{{0.0, 0.0}, {1.0 - theta, theta}};
    t.b = Vec{{1.0 - theta, theta}};
    t.c = Vec{{0.0, 1.0}};
    EXPECT_EQ(a_stable_exact(tableau_stability(t)), std::optional<bool>(true)) << theta;
  }
  // A-stable methods: no finite limit on either axis (|R(iy)| < 1, or = 1 for the symmetric
  // Gauss methods and the trapezoidal rule, where every coefficient of |P|² − |Q|² vanishes).
  for (const char* name : {"backward_euler", "trapezoidal", "implicit_midpoint", "sdirk2", "sdirk3",
                           "radau5", "gauss4", "gauss6", "esdirk43", "rosenbrock2"}) {
    SCOPED_TRACE(name);
    const auto s = stability_of(name);
    ASSERT_TRUE(s.rational);
    EXPECT_TRUE(real_axis_limit(s).unbounded);
    EXPECT_TRUE(imaginary_axis_limit(s).unbounded);
    EXPECT_TRUE(imaginary_axis_limit(s).exact);
    EXPECT_EQ(a_stable_exact(s), std::optional<bool>(true));
  }
  // The exact test agrees with the sampled one on every registered method with R = P/Q.
  for (const auto& e : integrator_registry().entries()) {
    const auto s = make(e.info.name)->linear_stability();
    if (!s || !s->rational) continue;
    EXPECT_EQ(a_stable_exact(*s), std::optional<bool>(a_stable_on_samples(*s))) << e.info.name;
  }
  // Radau IIA (3 stages): R = P/Q with deg P = 2, deg Q = 3 (L-stable).
  const auto radau = stability_of("radau5");
  EXPECT_EQ(radau.rational->p.size(), 3u);
  EXPECT_EQ(radau.rational->q.size(), 4u);
  // P/Q agrees with the amplification from (I − zA)⁻¹ anywhere off the poles.
  for (const std::complex<double> z :
       {std::complex<double>(-3.0, 2.0), {0.5, -4.0}, {-20.0, 0.1}}) {
    std::complex<double> p = 0.0, q = 0.0, zk = 1.0;
    for (std::size_t k = 0; k < std::max(radau.rational->p.size(), radau.rational->q.size());
         ++k, zk *= z) {
      if (k < radau.rational->p.size()) p += radau.rational->p[k] * zk;
      if (k < radau.rational->q.size()) q += radau.rational->q[k] * zk;
    }
    EXPECT_NEAR(std::abs(p / q), radau.amplification(z), 1e-12);
  }
  // Multistep methods keep the sampled search, marked as such.
  EXPECT_FALSE(stability_of("bdf2").rational);
  EXPECT_FALSE(real_axis_limit(stability_of("bdf2")).exact);
}

TEST(LinearStability, SplittingOscillatorLimitFromHalfTrace) {
  // Störmer–Verlet: half-trace T = 1 − (hω)²/2, |T| <= 1 ⇔ hω <= 2 (Hairer–Lubich–Wanner I.5).
  for (const char* name : {"velocity_verlet", "symplectic_euler", "leapfrog"}) {
    SCOPED_TRACE(name);
    const AxisLimit lim = oscillator_limit(stability_of(name));
    EXPECT_TRUE(lim.exact);
    EXPECT_NEAR(lim.limit, 2.0, 1e-13);
  }
}

TEST(LinearStability, UndampedSpectrumWithRoundOffDampingIsOnTheImaginaryAxis) {
  // An eigensolver returns an undamped spectrum with Re λ ~ 1e-15·|λ|; methods with
  // imaginary-axis limit 0 are unstable for every h on it (prediction 0), not given a limit set
  // by the round-off damping; rk4 keeps 2√2/ω.
  std::vector<std::complex<double>> eig;
  for (int j = 1; j <= 6; ++j) {
    const double w = 2.0 * std::sin(j * std::numbers::pi / 14.0);
    eig.emplace_back(-3e-15 * j, w);
    eig.emplace_back(-3e-15 * j, -w);
  }
  const double wmax = 2.0 * std::sin(6 * std::numbers::pi / 14.0);
  for (const bool mechanical : {true, false}) {
    SCOPED_TRACE(mechanical);
    for (const char* name : {"cash_karp", "rkf45", "euler", "heun"}) {
      const StepLimit lim = predicted_step_limit(stability_of(name), eig, mechanical, 100.0);
      EXPECT_EQ(lim.h, 0.0) << name;
      EXPECT_FALSE(lim.unbounded) << name;
      EXPECT_TRUE(lim.exact) << name;
    }
    EXPECT_NEAR(predicted_step_limit(stability_of("rk4"), eig, mechanical, 100.0).h,
                2.0 * std::sqrt(2.0) / wmax, 1e-12);
    EXPECT_NEAR(predicted_step_limit(stability_of("dopri5"), eig, mechanical, 100.0).h,
                0.997189008632529915 / wmax, 1e-12);
    EXPECT_TRUE(
        predicted_step_limit(stability_of("trapezoidal"), eig, mechanical, 100.0).unbounded);
  }
}

}  // namespace
}  // namespace stiffbench
