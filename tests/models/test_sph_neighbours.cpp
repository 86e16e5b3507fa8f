// SphFluid's Verlet neighbour list (sph_fluid.hpp, "Neighbour search"): the right-hand side over
// the list against a brute-force O(N²) evaluation of the header's equations written out here
// (every fluid and boundary particle tried for every fluid particle, Wendland C2 in closed form),
// at the initial state, after moves inside the half skin (the list is reused) and after moves
// beyond it (the list is rebuilt: a stale list misses pairs that came within h); and the build
// counter, which counts a build exactly when some particle has moved more than half the skin
// since the last one.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "models/sph/block_queue.hpp"
#include "models/sph/sph_fluid.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::model;

constexpr double kPi = 3.14159265358979323846;

const SphFluid& fluid(const OdeSystem& sys) {
  const auto* f = dynamic_cast<const SphFluid*>(&sys);
  if (!f) throw std::logic_error(sys.name() + " is not an SphFluid");
  return *f;
}

// Wendland C2 with support h in D dimensions: σ (1-q)⁴ (4q+1), σ = 7/(π h²) (2D) or
// 21/(2π h³) (3D); dW/dr = -20 σ q (1-q)³ / h (Wendland 1995; docs/reference-values.md).
double wendland(double r, double h, int dim) {
  const double q = r / h;
  if (q >= 1.0) return 0.0;
  const double sigma = dim == 2 ? 7.0 / (kPi * h * h) : 21.0 / (2.0 * kPi * h * h * h);
  return sigma * std::pow(1.0 - q, 4) * (4.0 * q + 1.0);
}
double wendland_dr(double r, double h, int dim) {
  const double q = r / h;
  if (q >= 1.0) return 0.0;
  const double sigma = dim == 2 ? 7.0 / (kPi * h * h) : 21.0 / (2.0 * kPi * h * h * h);
  return -20.0 * sigma * q * std::pow(1.0 - q, 3) / h;
}

// The accelerations of the header's equations for the options these scenes use (linear clamped
// EOS, variational pressure, Akinci's boundary pressure with f = 1, Monaghan's artificial
// viscosity on fluid and boundary pairs, gravity), every pair tried.
Vec brute_force(const SphFluid& f, CVecRef y) {
  const SphOptions& o = f.options();
  EXPECT_EQ(o.eos, SphEos::linear);
  EXPECT_TRUE(o.clamp);
  EXPECT_EQ(o.form, SphPressureForm::variational);
  EXPECT_EQ(o.viscosity, SphViscosity::artificial);
  EXPECT_EQ(o.boundary, SphBoundary::particles);
  EXPECT_FALSE(o.mirror_boundary_pressure);
  const int dim = f.dim();
  const Index n = f.fluid_particles(), nb = f.boundary_particles();
  const double h = o.support, rho0 = o.rho0, c = f.sound_speed(), k = c * c, hs = 0.5 * h;
  const auto& m = f.particle_masses();
  const auto& vb = f.boundary_volumes();
  const auto& bx = f.scene().boundary_x;
  const double* x = y.data();
  const double* v = y.data() + f.dofs();
  auto dist = [&](const double* p, const double* q) {
    double r2 = 0.0;
    for (int d = 0; d < dim; ++d) r2 += (p[d] - q[d]) * (p[d] - q[d]);
    return std::sqrt(r2);
  };
  std::vector<double> rho(static_cast<std::size_t>(n)), pr2(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    double s = 0.0;
    for (Index j = 0; j < n; ++j)
      s += m[static_cast<std::size_t>(j)] * wendland(dist(x + dim * i, x + dim * j), h, dim);
    for (Index b = 0; b < nb; ++b)
      s += rho0 * vb[static_cast<std::size_t>(b)] *
           wendland(dist(x + dim * i, bx[static_cast<std::size_t>(b)].data()), h, dim);
    rho[static_cast<std::size_t>(i)] = s;
    pr2[static_cast<std::size_t>(i)] = std::max(0.0, k * (s - rho0)) / (s * s);
  }
  Vec a(f.dofs());
  for (Index i = 0; i < n; ++i) {
    const std::size_t iu = static_cast<std::size_t>(i);
    std::array<double, 3> acc{};
    for (int d = 0; d < dim; ++d)
      acc[static_cast<std::size_t>(d)] = o.gravity[static_cast<std::size_t>(d)];
    // Fluid pairs (j ≠ i), then boundary particles (at rest, ρ_b = ρ0, m_b = ρ0 V_b).
    for (Index j = 0; j < n + nb; ++j) {
      if (j == i) continue;
      const bool wall = j >= n;
      const std::size_t ju = static_cast<std::size_t>(wall ? j - n : j);
      const double* xj = wall ? bx[ju].data() : x + dim * j;
      const double r = dist(x + dim * i, xj);
      if (r >= h || r == 0.0) continue;
      const double mj = wall ? rho0 * vb[ju] : m[ju];
      const double rhoj = wall ? rho0 : rho[ju];
      double vr = 0.0;
      for (int d = 0; d < dim; ++d)
        vr += (v[dim * i + d] - (wall ? 0.0 : v[dim * j + d])) * (x[dim * i + d] - xj[d]);
      double coef = mj * (pr2[iu] + (wall ? 0.0 : pr2[ju]));
      if (vr < 0.0)
        coef -= mj * o.alpha * c * hs * vr / (0.5 * (rho[iu] + rhoj) * (r * r + 0.01 * hs * hs));
      const double g = wendland_dr(r, h, dim) / r;
      for (int d = 0; d < dim; ++d)
        acc[static_cast<std::size_t>(d)] -= coef * g * (x[dim * i + d] - xj[d]);
    }
    for (int d = 0; d < dim; ++d) a[dim * i + d] = acc[static_cast<std::size_t>(d)];
  }
  return a;
}

Vec acceleration(const SphFluid& f, CVecRef y) {
  Vec a(f.dofs());
  f.acceleration(0.0, y.head(f.dofs()), y.tail(f.dofs()), a);
  return a;
}

// Every coordinate moved by up to `by` (uniform), velocities random up to 0.3 m/s.
Vec moved(const SphFluid& f, const Vec& y, double by, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec z = y;
  for (Index i = 0; i < f.dofs(); ++i) {
    z[i] += by * u(rng);
    z[f.dofs() + i] = 0.3 * u(rng);
  }
  return z;
}

// The two sums differ in order only: agreement to round-off. Measured: 2.5e-16 to 1.0e-13 of
// the largest acceleration over the 15 states below; bound 1e-10 (a pair missed by a stale
// list changes an acceleration by far more).
void expect_matches_brute_force(const SphFluid& f, const Vec& y) {
  const Vec a = acceleration(f, y), ref = brute_force(f, y);
  const double scale = ref.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  EXPECT_LE((a - ref).cwiseAbs().maxCoeff(), 1e-10 * scale);
}

TEST(SphNeighbours, ListRhsMatchesBruteForceAlsoAfterMoves) {
  struct Case {
    const char* name;
    std::vector<std::string> params;
  };
  const std::vector<Case> cases = {{"sph_tank_2d", {"n=8", "width=0.1", "alpha=0.5"}},
                                   {"sph_dam_break_2d", {"n=8", "alpha=0.5"}},
                                   {"sph_dam_break_3d", {"n=6", "alpha=0.5"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    auto sys = model(c.name, c.params);
    const SphFluid& f = fluid(*sys);
    const double s = f.neighbour_skin();
    ASSERT_GT(s, 0.0);
    Vec y = moved(f, f.initial_state(), 0.0, 1);
    expect_matches_brute_force(f, y);
    const long first = f.neighbour_list_builds();
    // Inside the half skin (each coordinate by < s/(2√D)): the list is reused and still exact.
    const double inside = 0.49 * s / std::sqrt(static_cast<double>(f.dim()));
    expect_matches_brute_force(f, moved(f, y, inside, 2));
    EXPECT_EQ(f.neighbour_list_builds(), first);
    // Far beyond it (up to 0.4 spacings per coordinate, several skins between some pairs):
    // pairs that were more than h + s apart at the last build come within h, which the old list
    // would miss; the list is rebuilt. Then again from there.
    for (unsigned seed = 3; seed < 6; ++seed) {
      y = moved(f, y, 0.4 * f.options().spacing, seed);
      expect_matches_brute_force(f, y);
    }
    EXPECT_EQ(f.neighbour_list_builds(), first + 3);
  }
}

// The pair passes (sph/pair_lanes.inc) run over the reused neighbour list on cell-sorted copies of
// the particle fields, four neighbours per SIMD vector. Their result is the one-pair-at-a-time
// loop written out here, bit for bit: the neighbours within h in the list's order (fluid ones by
// ascending particle index, as the list sorts them), the q-th of them adding to lane q mod 4 and
// a particle's sum (L0 + L1) + (L2 + L3) (the order pair_lanes.inc documents), each term with the
// model's operations in the model's order (the header's
// equations for the Wendland C2 kernels, the linear EOS through pressure(), Monaghan's and
// Müller's viscosities, penalty walls). Scenes without boundary particles, whose order is the
// boundary grid's.
Vec one_pair_at_a_time(const SphFluid& f, CVecRef y, Vec& rho) {
  using sph::Kernel;
  using sph::KernelType;
  const SphOptions& o = f.options();
  EXPECT_EQ(f.boundary_particles(), 0);
  EXPECT_EQ(o.density_kernel, KernelType::wendland_c2);
  EXPECT_EQ(o.gradient_kernel, KernelType::wendland_c2);
  const int dim = f.dim();
  const Index n = f.fluid_particles();
  const double h = o.support, h2 = h * h, hs = 0.5 * h;
  const Kernel wd(o.density_kernel, dim, h), wg(o.gradient_kernel, dim, h),
      wv(KernelType::viscosity, dim, h);
  const bool artificial = o.viscosity == SphViscosity::artificial && o.alpha > 0;
  const bool muller = o.viscosity == SphViscosity::muller && o.mu > 0;
  const double av = o.alpha * f.sound_speed() * hs, eps2 = 0.01 * hs * hs;
  const double d0 = f.wall_range(), k_wall = f.wall_strength();
  const auto& m = f.particle_masses();
  const double* x = y.data();
  const double* v = y.data() + f.dofs();
  auto r2_of = [&](Index i, Index j) {
    double r2 = 0.0;
    for (int d = 0; d < dim; ++d)
      r2 += (x[dim * i + d] - x[dim * j + d]) * (x[dim * i + d] - x[dim * j + d]);
    return r2;
  };
  rho.resize(n);
  Vec p(n), pr2(n), inv_rho(n);
  for (Index i = 0; i < n; ++i) {
    std::array<double, 4> lane{};  // kept neighbour q adds to lane q mod 4
    std::size_t q = 0;
    for (Index j = 0; j < n; ++j) {
      const double r2 = r2_of(i, j);
      if (r2 < h2)
        lane[q++ % 4] +=
            m[static_cast<std::size_t>(j)] * wd.w_inside_as<KernelType::wendland_c2>(std::sqrt(r2));
    }
    const double sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
    rho[i] = sum;
    p[i] = f.pressure(sum);
    pr2[i] = p[i] / (sum * sum);
    inv_rho[i] = 1.0 / sum;
  }
  Vec a(f.dofs());
  for (Index i = 0; i < n; ++i) {
    std::array<std::array<double, 3>, 4> lane{};  // kept neighbour q: lane q mod 4
    std::size_t q = 0;
    for (Index j = 0; j < n; ++j) {
      const double r2 = r2_of(i, j), r = std::sqrt(r2);
      if (!(r2 < h2)) continue;
      std::array<double, 3>& acc = lane[q++ % 4];
      if (r == 0.0) continue;  // itself: counted, adds nothing
      const double mj = m[static_cast<std::size_t>(j)];
      std::array<double, 3> dx{};
      for (int d = 0; d < dim; ++d)
        dx[static_cast<std::size_t>(d)] = x[dim * i + d] - x[dim * j + d];
      const double dwr = wg.dw_over_r_as<KernelType::wendland_c2>(r);
      double coef = o.form == SphPressureForm::variational
                        ? mj * (pr2[i] + pr2[j])
                        : 0.5 * mj * (p[i] + p[j]) * inv_rho[i] * inv_rho[j];
      if (artificial) {
        double vr = 0.0;
        for (int d = 0; d < dim; ++d)
          vr += (v[dim * i + d] - v[dim * j + d]) * dx[static_cast<std::size_t>(d)];
        if (vr < 0.0) coef -= mj * av * vr / (0.5 * (rho[i] + rho[j]) * (r * r + eps2));
      }
      for (int d = 0; d < dim; ++d)
        acc[static_cast<std::size_t>(d)] -= coef * dwr * dx[static_cast<std::size_t>(d)];
      if (muller) {
        const double cv = o.mu * inv_rho[i] * mj * inv_rho[j] * wv.laplacian(r);
        for (int d = 0; d < dim; ++d)
          acc[static_cast<std::size_t>(d)] += cv * (v[dim * j + d] - v[dim * i + d]);
      }
    }
    std::array<double, 3> acc{};
    for (std::size_t d = 0; d < static_cast<std::size_t>(dim); ++d)
      acc[d] = o.gravity[d] + ((lane[0][d] + lane[1][d]) + (lane[2][d] + lane[3][d]));
    if (o.boundary == SphBoundary::penalty) {
      for (const auto& wall : f.scene().walls) {
        double sd = -wall.offset;
        for (int d = 0; d < dim; ++d)
          sd += wall.normal[static_cast<std::size_t>(d)] * x[dim * i + d];
        if (sd < d0) {
          const double qw = 1.0 - sd / d0;
          for (int d = 0; d < dim; ++d)
            acc[static_cast<std::size_t>(d)] +=
                k_wall * qw * qw * wall.normal[static_cast<std::size_t>(d)];
        }
      }
    }
    for (int d = 0; d < dim; ++d) a[dim * i + d] = acc[static_cast<std::size_t>(d)];
  }
  return a;
}

TEST(SphNeighbours, PairPassesAreTheOnePairAtATimeLoopBitForBit) {
  struct Case {
    const char* name;
    std::vector<std::string> params;
  };
  // Monaghan's viscosity with the variational pressure; Müller's with the symmetric one; a 3D
  // tank with penalty walls (particles pressed into them by the moves below).
  const std::vector<Case> cases = {
      {"sph_drop_2d", {"viscosity=artificial", "alpha=0.5"}},
      {"sph_drop_2d", {"viscosity=muller", "mu=0.5", "form=symmetric"}},
      {"sph_dam_break_3d", {"n=6", "boundary=penalty", "viscosity=artificial", "alpha=0.5"}},
      {"sph_dam_break_2d", {"n=10", "boundary=penalty", "viscosity=muller", "mu=0.1"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    auto sys = model(c.name, c.params);
    const SphFluid& f = fluid(*sys);
    for (unsigned seed = 1; seed < 4; ++seed) {
      const Vec y = moved(f, f.initial_state(), 0.2 * f.options().spacing, seed);
      Vec rho;
      const Vec ref = one_pair_at_a_time(f, y, rho);
      const Vec a = acceleration(f, y);
      ASSERT_GT(ref.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_TRUE(a == ref) << "max |diff| " << (a - ref).cwiseAbs().maxCoeff();
      EXPECT_TRUE(f.densities(y.head(f.dofs())) == rho);
    }
  }
}

// The pair loops' AVX2 and AVX-512 builds (chosen at run time on processors that have them) and
// their portable build give the same bits: pair_lanes.inc is one source whose lanes do the same
// operations in the same order in all three, and the AVX-512 build's groups of eight are added as
// the four-lane loop's two groups of four. Scenes with boundary particles (their separate loop),
// Müller's viscosity with the symmetric form, and kernels evaluated lane by lane (spiky gradient,
// cubic spline density), each at a moved state and on both parts of the split, and the densities.
// A 3D particle has tens of kept neighbours, so its rows run eight-lane groups and then the
// four-lane loop for what is left (swapping the two halves' additions makes this test fail).
TEST(SphNeighbours, EveryBuildOfThePairLoopsGivesThePortableBits) {
  struct Case {
    const char* name;
    std::vector<std::string> params;
  };
  const std::vector<Case> cases = {
      {"sph_dam_break_3d", {"n=6", "alpha=0.5", "split=viscosity"}},
      {"sph_dam_break_3d", {"n=5", "viscosity=muller", "mu=0.1", "density_kernel=cubic_spline"}},
      {"sph_dam_break_2d", {"n=10", "viscosity=muller", "mu=0.1", "form=symmetric"}},
      {"sph_tank_2d",
       {"n=8", "width=0.1", "gradient_kernel=spiky", "density_kernel=cubic_spline"}}};
  auto sys0 = model(cases[0].name, cases[0].params);
  if (!fluid(*sys0).uses_avx2()) GTEST_SKIP() << "no AVX2 build of the pair loops runs here";
  // A build with -mavx2 (e.g. -DSTIFFBENCH_NATIVE=ON) compiles the loops once, for AVX2, and has
  // no portable build to switch to.
  SphFluid::allow_avx2(false);
  const bool two_builds = !fluid(*sys0).uses_avx2();
  SphFluid::allow_avx2(true);
  if (!two_builds) GTEST_SKIP() << "the pair loops are built once (for AVX2) here";
  const bool avx512 = fluid(*sys0).uses_avx512();
  if (!avx512) std::cout << "(this processor has no AVX-512: the AVX-512 build is not compared)\n";
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    auto sys = model(c.name, c.params);
    const SphFluid& f = fluid(*sys);
    const Vec y = moved(f, f.initial_state(), 0.2 * f.options().spacing, 7);
    const auto parts = [&] {
      std::vector<Vec> out{acceleration(f, y)};
      if (f.has_imex_split()) {
        Vec ye(y.size()), yi(y.size());
        f.rhs_explicit_part(0.0, y, ye);
        f.rhs_implicit_part(0.0, y, yi);
        out.push_back(ye);
        out.push_back(yi);
      }
      out.push_back(f.densities(y.head(f.dofs())));
      return out;
    };
    std::vector<std::pair<const char*, std::vector<Vec>>> builds;
    if (avx512) {
      ASSERT_TRUE(f.uses_avx512());
      builds.emplace_back("avx512", parts());
    }
    SphFluid::allow_avx512(false);
    EXPECT_FALSE(f.uses_avx512());
    ASSERT_TRUE(f.uses_avx2());
    builds.emplace_back("avx2", parts());
    SphFluid::allow_avx2(false);
    EXPECT_FALSE(f.uses_avx2());
    const std::vector<Vec> portable = parts();
    SphFluid::allow_avx2(true);
    SphFluid::allow_avx512(true);
    for (const auto& [build, out] : builds) {
      SCOPED_TRACE(build);
      ASSERT_EQ(out.size(), portable.size());
      for (std::size_t k = 0; k < out.size(); ++k) {
        ASSERT_GT(out[k].cwiseAbs().maxCoeff(), 0.0);
        EXPECT_TRUE(out[k] == portable[k])
            << "part " << k << ": max |diff| " << (out[k] - portable[k]).cwiseAbs().maxCoeff();
      }
    }
  }
}

// A build happens exactly when max_i |x_i - x_i(last build)| > s/2: never for moves up to
// 0.49 s (one particle, then all of them), always for a move of 0.51 s of a single particle, and
// the counter in counters() counts the same builds.
TEST(SphNeighbours, ListIsRebuiltExactlyWhenAParticleMovedHalfTheSkin) {
  auto sys = model("sph_tank_2d", {"n=8", "width=0.1"});
  const SphFluid& f = fluid(*sys);
  const double s = f.neighbour_skin();
  const Vec y0 = f.initial_state();
  Vec a(f.dofs());
  auto eval = [&](const Vec& y) { f.acceleration(0.0, y.head(f.dofs()), y.tail(f.dofs()), a); };
  eval(y0);
  const long b0 = f.neighbour_list_builds();
  EXPECT_GE(b0, 1);
  EXPECT_EQ(sys->counters().neighbour_builds, b0);
  Vec y = y0;
  y[0] += 0.49 * s;  // particle 0 along x
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0);
  for (Index i = 0; i < f.fluid_particles(); ++i) y[2 * i + 1] = y0[2 * i + 1] - 0.49 * s;
  y[1] = y0[1];  // particle 0 stays at 0.49 s along x
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0);
  // Diagonal: 0.3 s along both axes is 0.42 s < 0.5 s.
  y = y0;
  y[4] += 0.3 * s;
  y[5] += 0.3 * s;
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0);
  y = y0;
  y[2] += 0.51 * s;  // particle 1: beyond half the skin
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0 + 1);
  eval(y);  // the same state again: the list just built is current
  EXPECT_EQ(f.neighbour_list_builds(), b0 + 1);
  eval(y0);  // back: particle 1 moves 0.51 s from the last build
  EXPECT_EQ(f.neighbour_list_builds(), b0 + 2);
  // Diagonal beyond: 0.36 s along both axes is 0.509 s.
  y = y0;
  y[6] += 0.36 * s;
  y[7] += 0.36 * s;
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0 + 3);
  EXPECT_EQ(sys->counters().neighbour_builds, b0 + 3);
  // The velocities never trigger a build.
  y.tail(f.dofs()).setConstant(5.0);
  eval(y);
  EXPECT_EQ(f.neighbour_list_builds(), b0 + 3);
}

// The pair passes' block queue (block_queue.hpp). One thread: 10 blocks in 3 segments are
// [0, 3), [3, 6), [6, 10) (floor(10 s / 3)); thread 0 takes its own front to back, then the
// others' back to front -- the order follows from the definition.
TEST(SphBlockQueue, OneThreadTakesItsSegmentThenTheOthersFromTheBack) {
  sph::BlockQueue q;
  q.reset(10, 3);
  std::vector<std::int64_t> got;
  for (std::int64_t b; (b = q.next(0)) >= 0;) got.push_back(b);
  EXPECT_EQ(got, (std::vector<std::int64_t>{0, 1, 2, 5, 4, 3, 9, 8, 7, 6}));
  q.reset(0, 2);
  EXPECT_EQ(q.next(1), -1);
  // A thread beyond the segments only steals, first from segment (5 + 1) mod 2 = 0 = [0, 2):
  // its back, block 1. A copy starts empty until reset.
  q.reset(4, 2);
  EXPECT_EQ(q.next(5), 1);
  sph::BlockQueue copy(q);
  EXPECT_EQ(copy.next(0), -1);
}

// Four threads on two segments (two of them only steal): every block is handed out exactly once.
TEST(SphBlockQueue, ThreadsShareEveryBlockExactlyOnce) {
  constexpr std::int64_t kBlocks = 20000;
  sph::BlockQueue q;
  q.reset(kBlocks, 2);
  std::vector<std::vector<std::int64_t>> got(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (std::int64_t b; (b = q.next(t)) >= 0;) got[static_cast<std::size_t>(t)].push_back(b);
    });
  for (auto& th : threads) th.join();
  std::vector<int> times(kBlocks, 0);
  for (const auto& g : got)
    for (std::int64_t b : g) ++times[static_cast<std::size_t>(b)];
  EXPECT_EQ(std::count(times.begin(), times.end(), 1), kBlocks);
  // Each owner takes its own segment front to back: its blocks below the midpoint rise.
  for (int t = 0; t < 2; ++t) {
    std::int64_t last = -1;
    for (std::int64_t b : got[static_cast<std::size_t>(t)])
      if ((b < kBlocks / 2) == (t == 0)) {
        EXPECT_GT(b, last);
        last = b;
      }
  }
}

}  // namespace
}  // namespace stiffbench
