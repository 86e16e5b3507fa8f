// SPH smoothing kernels and the hashed-grid neighbour search, checked against theory and
// independent computations (docs/reference-values.md, section SPH):
//  - every kernel integrates to 1 over its support (Gauss-Legendre radial quadrature, nodes
//    computed here from the Legendre recurrence),
//  - kernels and gradients vanish exactly at and beyond the support radius,
//  - dW/dr equals a finite difference of W; the compile-time entry points agree with the
//    run-time ones,
//  - the 3D viscosity Laplacian equals W'' + 2W'/r of the viscosity kernel by finite differences,
//    the 2D one is the documented convention,
//  - closed-form values at r = 0,
//  - kernel names round-trip,
//  - NeighbourGrid equals a brute-force O(n²) search (same neighbour set, bitwise equal r² and
//    d), visits each neighbour once, handles boundaries, duplicates, far and non-finite points,
//    reuse, and visits in a deterministic order.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "models/sph/kernels.hpp"
#include "models/sph/neighbour_grid.hpp"

namespace stiffbench::sph {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr std::array<KernelType, 5> kAllTypes = {KernelType::poly6, KernelType::spiky,
                                                 KernelType::viscosity, KernelType::cubic_spline,
                                                 KernelType::wendland_c2};
constexpr std::array<double, 3> kSupports = {0.3, 1.0, 2.5};
constexpr std::array<int, 2> kDims = {2, 3};

std::string label(KernelType t, int dim, double h) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s %dD h=%g", to_string(t).c_str(), dim, h);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// Kernels
// ---------------------------------------------------------------------------------------------

// n-point Gauss-Legendre rule on [-1, 1]: nodes by Newton's method on P_n (three-term
// recurrence), weights 2 / ((1 - x²) P_n'(x)²). Independent of the code under test.
struct GaussRule {
  std::vector<double> x, w;
};

GaussRule gauss_legendre(int n) {
  GaussRule g;
  for (int i = 0; i < n; ++i) {
    double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
    double dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double step = p1 / dp;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    g.x.push_back(x);
    g.w.push_back(2.0 / ((1.0 - x * x) * dp * dp));
  }
  return g;
}

// ∫_0^h W(r) S_d(r) dr with S_2 = 2πr, S_3 = 4πr², composite Gauss-Legendre on `panels` equal
// panels. Panel ends include h/2 (panels even), where the cubic spline changes piece. The
// viscosity kernel is ∝ 1/r at 0, but r·W (2D) and r²·W (3D) are polynomials in r, and the
// Gauss nodes never touch r = 0, so the rule integrates it like the others.
double radial_integral(const Kernel& k, const GaussRule& g, int panels) {
  const double h = k.support(), dr = h / panels;
  double sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double a = p * dr;
    for (std::size_t i = 0; i < g.x.size(); ++i) {
      const double r = a + 0.5 * dr * (g.x[i] + 1.0);
      const double shell = k.dim() == 2 ? 2.0 * kPi * r : 4.0 * kPi * r * r;
      sum += 0.5 * dr * g.w[i] * k.w(r) * shell;
    }
  }
  return sum;
}

TEST(SphKernel, GaussLegendreRuleIsExactForPolynomials) {
  // Sanity check of the quadrature itself: ∫_0^1 x^k dx = 1/(k+1) for k <= 2n-1.
  const GaussRule g = gauss_legendre(8);
  for (int kpow = 0; kpow <= 15; ++kpow) {
    double sum = 0.0;
    for (std::size_t i = 0; i < g.x.size(); ++i)
      sum += 0.5 * g.w[i] * std::pow(0.5 * (g.x[i] + 1.0), kpow);
    EXPECT_NEAR(sum, 1.0 / (kpow + 1), 1e-14) << "x^" << kpow;
  }
}

TEST(SphKernel, EveryKernelIntegratesToOne) {
  // Theory: ∫ W dV = 1 over the support (docs/reference-values.md, SPH).
  const GaussRule g = gauss_legendre(8);
  double worst = 0.0;
  std::string worst_label;
  for (KernelType t : kAllTypes)
    for (int dim : kDims)
      for (double h : kSupports) {
        const Kernel k(t, dim, h);
        const double integral = radial_integral(k, g, 64);
        const double err = std::abs(integral - 1.0);
        EXPECT_LE(err, 1e-3) << label(t, dim, h) << ": integral " << integral;
        if (err > worst) {
          worst = err;
          worst_label = label(t, dim, h);
        }
      }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3e", worst);
  RecordProperty("max_rel_error", std::string(buf) + " (" + worst_label + ")");
}

TEST(SphKernel, ViscosityKernelIntegratesToOneWithRefinedComposite) {
  // The viscosity kernel is singular at 0: integrate with an independent rule as well —
  // composite Simpson in s with r = h s² (dr = 2hs ds), which removes the 1/r singularity, so
  // the integrand is smooth on [0, 1] (its value at s = 0 is the limit, computed by hand:
  // 2D: W·2πr·2hs -> n h/2 · 2π · 0 = 0, 3D: 0 as well since r²W -> 0).
  double worst = 0.0;
  for (int dim : kDims)
    for (double h : kSupports) {
      const Kernel k(KernelType::viscosity, dim, h);
      const int m = 2000;  // even
      const double ds = 1.0 / m;
      double sum = 0.0;
      for (int i = 0; i <= m; ++i) {
        const double s = i * ds, r = h * s * s;
        double f = 0.0;
        if (i > 0) {
          const double shell = dim == 2 ? 2.0 * kPi * r : 4.0 * kPi * r * r;
          f = k.w(r) * shell * 2.0 * h * s;
        }
        const double c = (i == 0 || i == m) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
        sum += c * f;
      }
      sum *= ds / 3.0;
      EXPECT_NEAR(sum, 1.0, 1e-3) << label(KernelType::viscosity, dim, h);
      worst = std::max(worst, std::abs(sum - 1.0));
    }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3e", worst);
  RecordProperty("max_rel_error", buf);
}

TEST(SphKernel, ZeroWithZeroGradientAtAndBeyondSupport) {
  // Theory: compact support, W = 0 and dW/dr = 0 for r >= h, exactly.
  for (KernelType t : kAllTypes)
    for (int dim : kDims)
      for (double h : kSupports) {
        const Kernel k(t, dim, h);
        for (double r : {h, 1.01 * h, 2.0 * h, 1e6 * h}) {
          EXPECT_EQ(k.w(r), 0.0) << label(t, dim, h) << " r=" << r;
          EXPECT_EQ(k.dw(r), 0.0) << label(t, dim, h) << " r=" << r;
          with_kernel(t, [&](auto tag) {
            constexpr KernelType T = decltype(tag)::value;
            EXPECT_EQ(k.w_as<T>(r), 0.0) << label(t, dim, h) << " r=" << r;
            EXPECT_EQ(k.dw_as<T>(r), 0.0) << label(t, dim, h) << " r=" << r;
            EXPECT_EQ(k.dw_over_r_as<T>(r), 0.0) << label(t, dim, h) << " r=" << r;
          });
          if (k.has_laplacian()) {
            EXPECT_EQ(k.laplacian(r), 0.0) << label(t, dim, h);
          }
        }
        // Just inside the support the kernel is positive (non-degenerate) and decreasing.
        EXPECT_GT(k.w(0.999 * h), 0.0) << label(t, dim, h);
        EXPECT_LT(k.dw(0.99 * h), 0.0) << label(t, dim, h);
      }
}

// Five-point central difference of f at r with step d: error O(d⁴).
template <class F>
double central_diff(const F& f, double r, double d) {
  return (f(r - 2 * d) - 8 * f(r - d) + 8 * f(r + d) - f(r + 2 * d)) / (12 * d);
}

// Five-point second difference.
template <class F>
double central_diff2(const F& f, double r, double d) {
  return (-f(r - 2 * d) + 16 * f(r - d) - 30 * f(r) + 16 * f(r + d) - f(r + 2 * d)) / (12 * d * d);
}

TEST(SphKernel, GradientMatchesFiniteDifference) {
  // Independent computation: dW/dr = finite difference of W (a wrong analytic gradient is the
  // bug docs/reference-values.md warns about). Sample points avoid r = 0 and [h - 1e-3h, h); the
  // step is 1e-3·min(r, h - r) so the stencil stays inside one smooth piece except at the cubic
  // spline's q = 1/2, where it is C2 and the difference still converges.
  const int n = 400;
  double worst = 0.0;
  for (KernelType t : kAllTypes)
    for (int dim : kDims)
      for (double h : kSupports) {
        const Kernel k(t, dim, h);
        const auto w = [&](double r) { return k.w(r); };
        // Scale: the largest |dW/dr| on [h/4, h) (bounded for every kernel, including the
        // viscosity kernel whose gradient is unbounded near 0; there the local value is used).
        double scale = 0.0;
        for (int i = 0; i < n; ++i)
          scale = std::max(scale, std::abs(k.dw(h * (0.25 + 0.75 * i / n))));
        std::vector<double> rs;
        for (int i = 0; i < n; ++i) rs.push_back(h * (i + 0.5) / n);
        rs.push_back(0.5 * h);
        rs.push_back(h * (1.0 - 1.001e-3));
        for (double r : rs) {
          if (r > h * (1.0 - 1e-3)) continue;
          const double d = 1e-3 * std::min(r, h - r);
          const double fd = central_diff(w, r, d);
          const double an = k.dw(r);
          const double tol_scale = std::max(scale, std::abs(an));
          const double err = std::abs(fd - an) / tol_scale;
          worst = std::max(worst, err);
          EXPECT_LE(err, 1e-6) << label(t, dim, h) << " r=" << r << " dw=" << an << " fd=" << fd;

          // Compile-time entry points: the same function, so bitwise equal; dW/dr / r to
          // rounding (poly6 and Wendland avoid the division).
          with_kernel(t, [&](auto tag) {
            constexpr KernelType T = decltype(tag)::value;
            EXPECT_EQ(k.w_as<T>(r), k.w(r)) << label(t, dim, h) << " r=" << r;
            EXPECT_EQ(k.dw_as<T>(r), k.dw(r)) << label(t, dim, h) << " r=" << r;
            const double over_r = k.dw_over_r_as<T>(r), ref = k.dw(r) / r;
            EXPECT_LE(std::abs(over_r - ref), 1e-14 * std::abs(ref))
                << label(t, dim, h) << " r=" << r << " dw/r=" << ref << " got " << over_r;
          });
        }
      }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3e", worst);
  RecordProperty("max_rel_fd_error", buf);
}

TEST(SphKernel, ViscosityLaplacian3DIsLaplacianOfTheKernel) {
  // Independent computation: ∇²W = W'' + 2W'/r in 3D, W'' and W' by five-point differences of
  // w(r); Müller's closed form is 45/(π h⁶)(h - r). Near r = 0 both terms grow like 1/r³ and
  // cancel, so the difference loses digits there: sample r in [0.05h, 0.99h] and compare on
  // the scale of the Laplacian's maximum 45/(π h⁵). As a second, well-conditioned check,
  // ∇²W = (rW)''/r in 3D, where rW is a polynomial.
  double worst = 0.0, worst_rw = 0.0;
  for (double h : kSupports) {
    const Kernel k(KernelType::viscosity, 3, h);
    ASSERT_TRUE(k.has_laplacian());
    const auto w = [&](double r) { return k.w(r); };
    const auto rw = [&](double r) { return r * k.w(r); };
    const double scale = 45.0 / (kPi * std::pow(h, 5));
    for (int i = 0; i <= 200; ++i) {
      const double r = h * (0.05 + 0.94 * i / 200.0);
      // Steps: small against r for the singular W; the polynomial rW takes a fixed step.
      // Both stencils stay inside (0, h).
      const double d = 1e-3 * std::min(r, 0.5 * h), d_rw = 2e-3 * h;
      const double fd = central_diff2(w, r, d) + 2.0 * central_diff(w, r, d) / r;
      const double fd_rw = central_diff2(rw, r, d_rw) / r;
      const double closed = 45.0 / (kPi * std::pow(h, 6)) * (h - r);
      worst = std::max(worst, std::abs(k.laplacian(r) - fd) / scale);
      worst_rw = std::max(worst_rw, std::abs(k.laplacian(r) - fd_rw) / scale);
      EXPECT_NEAR(k.laplacian(r), fd, 1e-5 * scale) << "h=" << h << " r=" << r;
      EXPECT_NEAR(k.laplacian(r), fd_rw, 1e-6 * scale) << "h=" << h << " r=" << r;
      EXPECT_NEAR(k.laplacian(r), closed, 1e-13 * scale) << "h=" << h << " r=" << r;
    }
    EXPECT_EQ(k.laplacian(h), 0.0);
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3e", worst);
  RecordProperty("max_error_over_scale", buf);
  std::snprintf(buf, sizeof buf, "%.3e", worst_rw);
  RecordProperty("max_error_over_scale_rw", buf);
}

TEST(SphKernel, ViscosityLaplacian2DIsTheConvention) {
  // docs/reference-values.md: in 2D, 40/(π h⁵)(h - r) is a convention, not the Laplacian of the 2D
  // kernel (that one, W'' + W'/r, is singular at 0). Assert what the convention guarantees:
  // positive on (0, h) (dissipative), zero at and beyond h, and the documented formula.
  for (double h : kSupports) {
    const Kernel k(KernelType::viscosity, 2, h);
    ASSERT_TRUE(k.has_laplacian());
    const double scale = 40.0 / (kPi * std::pow(h, 5));
    for (int i = 1; i < 200; ++i) {
      const double r = h * i / 200.0;
      EXPECT_GT(k.laplacian(r), 0.0) << "h=" << h << " r=" << r;
      EXPECT_NEAR(k.laplacian(r), scale * (h - r), 1e-13 * scale * h) << "h=" << h << " r=" << r;
    }
    EXPECT_GT(k.laplacian(0.0), 0.0);
    EXPECT_EQ(k.laplacian(h), 0.0);
    EXPECT_EQ(k.laplacian(2.0 * h), 0.0);
    // Documentation, not a requirement: the true 2D Laplacian of the kernel differs.
    const auto w = [&](double r) { return k.w(r); };
    const double r = 0.5 * h, d = 1e-3 * r;
    const double true_lap = central_diff2(w, r, d) + central_diff(w, r, d) / r;
    EXPECT_GT(std::abs(true_lap - k.laplacian(r)), 1e-3 * scale * h);
  }
  for (KernelType t : kAllTypes)
    EXPECT_EQ(Kernel(t, 3, 1.0).has_laplacian(), t == KernelType::viscosity) << to_string(t);
}

TEST(SphKernel, ClosedFormsAtTheOrigin) {
  // Theory: the closed forms of docs/reference-values.md, SPH.
  for (double h : kSupports) {
    const double h2 = h * h, h3 = h2 * h;
    const auto near = [](double got, double want) {
      return std::abs(got - want) <= 1e-14 * std::abs(want);
    };
    EXPECT_TRUE(near(Kernel(KernelType::poly6, 3, h).w(0.0), 315.0 / (64.0 * kPi * h3)));
    EXPECT_TRUE(near(Kernel(KernelType::poly6, 2, h).w(0.0), 4.0 / (kPi * h2)));
    EXPECT_TRUE(near(Kernel(KernelType::spiky, 3, h).w(0.0), 15.0 / (kPi * h3)));
    EXPECT_TRUE(near(Kernel(KernelType::spiky, 2, h).w(0.0), 10.0 / (kPi * h2)));
    EXPECT_TRUE(near(Kernel(KernelType::cubic_spline, 3, h).w(0.0), 8.0 / (kPi * h3)));
    EXPECT_TRUE(near(Kernel(KernelType::cubic_spline, 2, h).w(0.0), 40.0 / (7.0 * kPi * h2)));
    EXPECT_TRUE(near(Kernel(KernelType::wendland_c2, 3, h).w(0.0), 21.0 / (2.0 * kPi * h3)));
    EXPECT_TRUE(near(Kernel(KernelType::wendland_c2, 2, h).w(0.0), 7.0 / (kPi * h2)));

    // Spiky gradient: ∇W = -45/(π h⁶)(h - r)² r̂ (3D), -30/(π h⁵)(h - r)² r̂ (2D); finite as
    // r -> 0, where it tends to -45/(π h⁴) and -30/(π h³).
    for (int dim : kDims) {
      const Kernel k(KernelType::spiky, dim, h);
      const double c = dim == 3 ? 45.0 / (kPi * std::pow(h, 6)) : 30.0 / (kPi * std::pow(h, 5));
      for (double r : {0.0, 1e-12 * h, 0.1 * h, 0.5 * h, 0.9 * h}) {
        const double want = -c * (h - r) * (h - r);
        EXPECT_TRUE(std::isfinite(k.dw(r))) << dim << "D r=" << r;
        EXPECT_TRUE(near(k.dw(r), want)) << dim << "D r=" << r << ": " << k.dw(r) << " vs " << want;
      }
      // Poly6 at mid-support against the closed form.
      const Kernel p(KernelType::poly6, dim, h);
      const double r = 0.4 * h, d = h2 - r * r;
      const double pn =
          dim == 3 ? 315.0 / (64.0 * kPi * std::pow(h, 9)) : 4.0 / (kPi * std::pow(h, 8));
      EXPECT_TRUE(near(p.w(r), pn * d * d * d)) << dim << "D";
    }

    // Smooth-at-the-origin kernels have dW/dr(0) = 0.
    for (int dim : kDims)
      for (KernelType t : {KernelType::poly6, KernelType::cubic_spline, KernelType::wendland_c2}) {
        const Kernel k(t, dim, h);
        EXPECT_EQ(k.dw(0.0), 0.0) << label(t, dim, h);
        EXPECT_TRUE(std::isfinite(k.w(0.0))) << label(t, dim, h);
      }
    // The viscosity kernel is documented to be +inf at 0.
    EXPECT_EQ(Kernel(KernelType::viscosity, 3, h).w(0.0), std::numeric_limits<double>::infinity());
  }
}

TEST(SphKernel, NamesRoundTrip) {
  ASSERT_EQ(kernel_names().size(), kAllTypes.size());
  for (const std::string& name : kernel_names())
    EXPECT_EQ(to_string(kernel_from_string(name)), name);
  for (KernelType t : kAllTypes) EXPECT_EQ(kernel_from_string(to_string(t)), t);
  EXPECT_EQ(kernel_from_string("wendland_c2"), KernelType::wendland_c2);
  EXPECT_THROW(kernel_from_string("bogus"), std::invalid_argument);
  EXPECT_THROW(kernel_from_string(""), std::invalid_argument);
}

TEST(SphKernel, ConstructorRejectsBadArguments) {
  EXPECT_THROW(Kernel(KernelType::poly6, 1, 1.0), std::invalid_argument);
  EXPECT_THROW(Kernel(KernelType::poly6, 4, 1.0), std::invalid_argument);
  EXPECT_THROW(Kernel(KernelType::poly6, 3, 0.0), std::invalid_argument);
  EXPECT_THROW(Kernel(KernelType::poly6, 3, -1.0), std::invalid_argument);
  EXPECT_THROW(Kernel(KernelType::poly6, 3, std::nan("")), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Neighbour grid
// ---------------------------------------------------------------------------------------------

template <int D>
struct Hit {
  Index j;
  double r2;
  std::array<double, D> dx;
  bool operator==(const Hit&) const = default;
};

// Brute force, with the same arithmetic as the documented contract: d = q - x_j, r² summed in
// coordinate order, kept when r² < radius².
template <int D>
std::vector<Hit<D>> brute_force(const std::vector<double>& x, const double* q, double radius) {
  std::vector<Hit<D>> hits;
  const Index n = static_cast<Index>(x.size()) / D;
  for (Index j = 0; j < n; ++j) {
    Hit<D> hit{j, 0.0, {}};
    for (int d = 0; d < D; ++d) {
      hit.dx[d] = q[d] - x[static_cast<std::size_t>(D * j + d)];
      hit.r2 += hit.dx[d] * hit.dx[d];
    }
    if (hit.r2 < radius * radius) hits.push_back(hit);
  }
  return hits;
}

// The grid's hits in visiting order.
template <int D>
std::vector<Hit<D>> grid_hits(const NeighbourGrid<D>& g, const double* q, double radius) {
  std::vector<Hit<D>> hits;
  g.for_each_neighbour(q, radius, [&](Index j, double r2, const std::array<double, D>& dx) {
    hits.push_back(Hit<D>{j, r2, dx});
  });
  return hits;
}

template <int D>
std::string point_str(const double* q) {
  std::string s = "(";
  char buf[40];
  for (int d = 0; d < D; ++d) {
    std::snprintf(buf, sizeof buf, "%.17g", q[d]);
    s += (d ? ", " : "") + std::string(buf);
  }
  return s + ")";
}

// Grid == brute force for every query: same set of indices, each visited once, bitwise equal r²
// and d. Returns the first mismatch.
template <int D>
::testing::AssertionResult matches_brute_force(const NeighbourGrid<D>& g,
                                               const std::vector<double>& x,
                                               const std::vector<double>& queries, double radius) {
  const std::size_t nq = queries.size() / D;
  for (std::size_t i = 0; i < nq; ++i) {
    const double* q = queries.data() + D * i;
    auto got = grid_hits(g, q, radius);
    const auto want = brute_force<D>(x, q, radius);
    std::sort(got.begin(), got.end(), [](const Hit<D>& a, const Hit<D>& b) { return a.j < b.j; });
    for (std::size_t k = 1; k < got.size(); ++k)
      if (got[k].j == got[k - 1].j)
        return ::testing::AssertionFailure()
               << "query " << i << " " << point_str<D>(q) << ": neighbour " << got[k].j
               << " visited more than once";
    if (got != want) {
      // First index in one list and not the other.
      std::size_t k = 0;
      while (k < got.size() && k < want.size() && got[k] == want[k]) ++k;
      auto f = ::testing::AssertionFailure();
      f << "query " << i << " " << point_str<D>(q) << " radius " << radius << ": grid "
        << got.size() << " neighbours, brute force " << want.size();
      if (k < want.size())
        f << "; brute force has j=" << want[k].j << " " << point_str<D>(x.data() + D * want[k].j)
          << " r2=" << want[k].r2;
      if (k < got.size())
        f << "; grid has j=" << got[k].j << " " << point_str<D>(x.data() + D * got[k].j)
          << " r2=" << got[k].r2;
      return f;
    }
  }
  return ::testing::AssertionSuccess();
}

template <int D>
NeighbourGrid<D> built(const std::vector<double>& x, double cell) {
  NeighbourGrid<D> g;
  g.build(x.data(), static_cast<Index>(x.size()) / D, cell);
  return g;
}

template <int D>
std::vector<double> uniform_points(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> x(static_cast<std::size_t>(n) * D);
  for (double& v : x) v = u(rng);
  return x;
}

// Coordinates that are integer multiples of the cell (cell boundaries), negative ones too.
template <int D>
std::vector<double> lattice_points(std::mt19937& rng, int n, double cell, int kmax) {
  std::uniform_int_distribution<int> k(-kmax, kmax);
  std::vector<double> x(static_cast<std::size_t>(n) * D);
  for (double& v : x) v = k(rng) * cell;
  return x;
}

void append(std::vector<double>& to, const std::vector<double>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// Mixed set: uniform points, points on cell boundaries, and duplicates of some of them.
template <int D>
std::vector<double> mixed_points(unsigned seed, double cell) {
  std::mt19937 rng(seed);
  std::vector<double> x = uniform_points<D>(rng, 250, -6 * cell, 6 * cell);
  append(x, lattice_points<D>(rng, 150, cell, 5));
  const std::vector<double> dup(x.begin() + 10 * D, x.begin() + 60 * D);
  append(x, dup);  // 50 coincident pairs, including lattice points
  append(x, std::vector<double>(x.begin() + 300 * D, x.begin() + 310 * D));
  return x;
}

template <int D>
std::vector<double> queries_for(const std::vector<double>& x, unsigned seed, double cell) {
  std::mt19937 rng(seed);
  std::vector<double> q = x;                                    // every point of the set
  append(q, uniform_points<D>(rng, 100, -7 * cell, 7 * cell));  // not in the set
  append(q, lattice_points<D>(rng, 50, cell, 6));               // boundaries, maybe not in set
  return q;
}

template <int D>
void check_random_sets() {
  for (unsigned seed : {1u, 2u, 3u})
    for (double cell : {0.25, 0.1, 0.037}) {
      const std::vector<double> x = mixed_points<D>(seed, cell);
      const std::vector<double> q = queries_for<D>(x, seed + 100, cell);
      const NeighbourGrid<D> g = built<D>(x, cell);
      EXPECT_EQ(g.size(), static_cast<Index>(x.size() / D));
      // 13^D cells around 460 points: the dense bounding-box mode is the one tested here (the
      // far sets below test the hashed mode).
      EXPECT_TRUE(g.dense());
      for (double radius : {cell, 0.7 * cell, 0.3 * cell})
        EXPECT_TRUE(matches_brute_force(g, x, q, radius))
            << D << "D seed " << seed << " cell " << cell << " radius " << radius;
    }
}

TEST(SphNeighbourGrid, MatchesBruteForce2D) { check_random_sets<2>(); }
TEST(SphNeighbourGrid, MatchesBruteForce3D) { check_random_sets<3>(); }

// Clusters around far points: ±1e6 and ±1e12 (cell indices clamp at ±kCellLimit for cell
// 0.01), around the clamp limit itself, per-coordinate mixtures, and a cluster at the origin.
template <int D>
std::vector<double> far_points(unsigned seed, double cell) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> off(-2.5 * cell, 2.5 * cell);
  const double lim = static_cast<double>(NeighbourGrid<D>::kCellLimit) * cell;
  const std::vector<std::array<double, 3>> centres = {
      {1e6, 0.0, 0.0},    {-1e6, -1e6, 0.0}, {1e12, 1e12, 1e12}, {-1e12, 0.5, -1e12},
      {1e12, -1e12, 0.0}, {lim, 0.0, lim},   {-lim, -lim, 3.0},  {lim - 2 * cell, 0.0, 0.0},
      {0.0, 0.0, 0.0},    {0.0, 1e12, 0.0}};
  std::vector<double> x;
  for (const auto& c : centres)
    for (int i = 0; i < 40; ++i)
      for (int d = 0; d < D; ++d) x.push_back(c[static_cast<std::size_t>(d)] + off(rng));
  // Coincident points at the far centres, and the exact centres (on cell boundaries).
  for (const auto& c : centres)
    for (int rep = 0; rep < 3; ++rep)
      for (int d = 0; d < D; ++d) x.push_back(c[static_cast<std::size_t>(d)]);
  return x;
}

template <int D>
void check_far_sets() {
  const double cell = 0.01;
  for (unsigned seed : {7u, 8u}) {
    const std::vector<double> x = far_points<D>(seed, cell);
    std::vector<double> q = x;
    std::mt19937 rng(seed + 50);
    std::uniform_real_distribution<double> jitter(-cell, cell);
    for (std::size_t i = 0; i < x.size(); i += 3 * D)  // off-set queries near the points
      for (int d = 0; d < D; ++d) q.push_back(x[i + static_cast<std::size_t>(d)] + jitter(rng));
    const NeighbourGrid<D> g = built<D>(x, cell);
    EXPECT_FALSE(g.dense());  // points 1e12 apart: the hashed mode
    for (double radius : {cell, 0.6 * cell})
      EXPECT_TRUE(matches_brute_force(g, x, q, radius)) << D << "D seed " << seed;
  }
}

TEST(SphNeighbourGrid, FarPointsAndClampedCells2D) { check_far_sets<2>(); }
TEST(SphNeighbourGrid, FarPointsAndClampedCells3D) { check_far_sets<3>(); }

TEST(SphNeighbourGrid, NonFiniteCoordinatesAreNeverNeighboursOfFinitePoints) {
  constexpr int D = 3;
  const double cell = 0.01, inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937 rng(11);
  std::vector<double> x = far_points<D>(11, cell);
  const std::vector<std::array<double, 3>> bad = {
      {nan, 0.0, 0.0},     {0.0, nan, 0.0},    {nan, nan, nan},    {inf, 0.0, 0.0},
      {-inf, 0.0, 0.0},    {inf, inf, inf},    {-inf, -inf, -inf}, {1e12, inf, 1e12},
      {-1e12, nan, -1e12}, {-inf, 0.5, -1e12}, {0.0, 0.0, -inf},   {nan, 1e12, 1e12}};
  for (int rep = 0; rep < 2; ++rep)
    for (const auto& b : bad) x.insert(x.end(), b.begin(), b.end());
  // Interleave more finite points after the non-finite ones.
  append(x, uniform_points<D>(rng, 100, -0.05, 0.05));
  const NeighbourGrid<D> g = built<D>(x, cell);

  std::vector<double> q;
  for (std::size_t i = 0; i < x.size() / D; ++i) {
    const double* p = x.data() + D * i;
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
      q.insert(q.end(), p, p + D);
  }
  // Finite queries in the cells where the non-finite points land (±kCellLimit).
  const std::vector<std::array<double, 3>> limit_cells = {
      {-1e12, -1e12, -1e12}, {1e12, 1e12, 1e12}, {-1e12, 0.0, 0.0},     {1e12, 0.0, 0.0},
      {0.0, 0.0, -1e12},     {0.0, -1e12, 0.0},  {1e300, 1e300, 1e300}, {-1e300, 0.0, 0.0}};
  for (const auto& c : limit_cells) q.insert(q.end(), c.begin(), c.end());
  EXPECT_TRUE(matches_brute_force(g, x, q, cell));
  for (std::size_t i = 0; i < q.size() / D; ++i)
    g.for_each_neighbour(q.data() + D * i, cell, [&](Index j, double r2, const auto&) {
      const double* p = x.data() + D * j;
      EXPECT_TRUE(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
          << "non-finite point " << j << " reported with r2=" << r2;
      EXPECT_LT(static_cast<std::size_t>(j), x.size() / D);
    });
}

TEST(SphNeighbourGrid, RebuildReusesTheGrid) {
  // One grid object, rebuilt with different positions, sizes and cells: each build must match
  // brute force on its own points, with nothing left over from the previous build.
  NeighbourGrid<3> g;
  const double cells[] = {0.1, 0.1, 0.25, 0.01};
  const unsigned seeds[] = {21u, 22u, 23u, 24u};
  for (int b = 0; b < 4; ++b) {
    std::vector<double> x =
        b == 3 ? far_points<3>(seeds[b], cells[b]) : mixed_points<3>(seeds[b], cells[b]);
    if (b == 1) x.resize(x.size() / 3 / 3 * 3);  // fewer points than the previous build
    g.build(x.data(), static_cast<Index>(x.size() / 3), cells[b]);
    const Index n = static_cast<Index>(x.size() / 3);
    ASSERT_EQ(g.size(), n);
    // order() is a permutation of 0..n-1.
    std::vector<Index> ord = g.order();
    ASSERT_EQ(static_cast<Index>(ord.size()), n);
    std::sort(ord.begin(), ord.end());
    for (Index i = 0; i < n; ++i) ASSERT_EQ(ord[static_cast<std::size_t>(i)], i);
    EXPECT_TRUE(matches_brute_force(g, x, queries_for<3>(x, seeds[b] + 5, cells[b]), cells[b]))
        << "build " << b;
  }
  // An empty build finds nothing.
  g.build(nullptr, 0, 0.1);
  const double q[3] = {0.0, 0.0, 0.0};
  int count = 0;
  g.for_each_neighbour(q, 0.1, [&](Index, double, const auto&) { ++count; });
  EXPECT_EQ(count, 0);
}

TEST(SphNeighbourGrid, EachNeighbourVisitedOnceNearTheClampLimit) {
  // Points at 1e12 with cell 0.01 all map to the clamped cell kCellLimit; the 27 offsets around
  // it name only 8 distinct cells. Each neighbour must still be visited exactly once.
  for (double base : {1e12, -1e12}) {
    std::vector<double> x;
    for (int i = 0; i < 30; ++i) {
      const double o = (i % 10) * 1e-3 * (base > 0 ? 1 : -1);  // ~8 ulps of 1e12 apart
      x.insert(x.end(), {base + o, base, base - o});
    }
    const NeighbourGrid<3> g = built<3>(x, 0.01);
    for (std::size_t i = 0; i < x.size() / 3; ++i) {
      std::vector<int> visits(x.size() / 3, 0);
      g.for_each_neighbour(x.data() + 3 * i, 0.01, [&](Index j, double, const auto&) {
        ++visits[static_cast<std::size_t>(j)];
      });
      int total = 0;
      for (std::size_t j = 0; j < visits.size(); ++j) {
        EXPECT_LE(visits[j], 1) << "base " << base << " query " << i << " neighbour " << j;
        total += visits[j];
      }
      EXPECT_EQ(total, static_cast<int>(brute_force<3>(x, x.data() + 3 * i, 0.01).size()));
    }
  }
  // The same in 2D with one coordinate clamped and the other ordinary, and at ±(limit - 1).
  const double cell = 0.01;
  const double lim = static_cast<double>(NeighbourGrid<2>::kCellLimit) * cell;
  std::vector<double> x;
  for (double cx : {1e12, -1e12, lim, -lim, lim - cell, -lim + cell, lim + cell})
    for (int i = -3; i <= 3; ++i) x.insert(x.end(), {cx + i * 0.004, i * 0.004});
  const NeighbourGrid<2> g = built<2>(x, cell);
  EXPECT_TRUE(matches_brute_force(g, x, x, cell));
}

TEST(SphNeighbourGrid, VisitingOrderIsDeterministic) {
  // Two grids built from the same points (one of them reused after another build) visit the
  // neighbours of each query in the same order with the same r² and d.
  for (unsigned seed : {31u, 32u}) {
    const std::vector<double> x = mixed_points<3>(seed, 0.1);
    const NeighbourGrid<3> a = built<3>(x, 0.1);
    NeighbourGrid<3> b;
    const std::vector<double> other = mixed_points<3>(seed + 1, 0.05);
    b.build(other.data(), static_cast<Index>(other.size() / 3), 0.05);
    b.build(x.data(), static_cast<Index>(x.size() / 3), 0.1);
    EXPECT_EQ(a.order(), b.order());
    const std::vector<double> q = queries_for<3>(x, seed, 0.1);
    for (std::size_t i = 0; i < q.size() / 3; ++i) {
      const auto ha = grid_hits(a, q.data() + 3 * i, 0.1);
      const auto hb = grid_hits(b, q.data() + 3 * i, 0.1);
      ASSERT_TRUE(ha == hb) << "query " << i;
    }
  }
}

TEST(SphNeighbourGrid, FindsNeighbourAcrossARoundedCellBoundary) {
  // Regression for floor(x * (1/cell)) rounding: with cell = 0.1, the points
  //   b = 0x1.9999999999999p+3 (12.799999999999999, b*10 rounds to 127.99999999999999 -> cell 127)
  //   a = 0x1.9ccccccccccccp+3 (12.899999999999999, a*10 rounds up to 129.0          -> cell 129)
  // are 0.099999999999999645 < cell apart, so each is a true neighbour of the other for
  // radius = cell, but their cells are two apart and the 3^D-cell search cannot see them.
  const double b = 0x1.9999999999999p+3, a = 0x1.9ccccccccccccp+3;
  ASSERT_LT((a - b) * (a - b), 0.1 * 0.1);
  for (int dim : kDims) {
    std::vector<double> x(static_cast<std::size_t>(2 * dim), 0.5);
    x[0] = b;
    x[static_cast<std::size_t>(dim)] = a;
    if (dim == 2) {
      const NeighbourGrid<2> g = built<2>(x, 0.1);
      EXPECT_TRUE(matches_brute_force(g, x, x, 0.1)) << "2D";
    } else {
      const NeighbourGrid<3> g = built<3>(x, 0.1);
      EXPECT_TRUE(matches_brute_force(g, x, x, 0.1)) << "3D";
    }
  }
}

}  // namespace
}  // namespace stiffbench::sph
