// Mass-spring networks (models/mass_spring), checked against theory and independent
// computations: analytic K = ∂a/∂x and D = ∂a/∂v against central finite differences of the
// acceleration; conservation laws under integrators that preserve them; the chain's normal-mode
// frequencies and exact solution (docs/reference-values.md); Lanczos against Eigen's dense
// eigensolvers; bitwise thread-count independence; pinned points; the constraint projection; and
// the stiff-spring pendulum chain converging to the constrained one as k → ∞.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "models/mass_spring/builders.hpp"
#include "models/mass_spring/network.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::model;

const MassSpringNetwork& net(const OdeSystem& sys) {
  const auto* n = dynamic_cast<const MassSpringNetwork*>(&sys);
  if (!n) throw std::logic_error(sys.name() + " is not a MassSpringNetwork");
  return *n;
}

std::unique_ptr<Integrator> integrator(const std::string& name) {
  return integrator_registry().create(name, Params{});
}

RunResult run(const OdeSystem& sys, const std::string& method, double h, double t_end,
              const Vec& y0) {
  auto integ = integrator(method);
  FixedStepOptions opt;
  opt.t_end = t_end;
  opt.h = h;
  return run_fixed_step_from(sys, *integ, 0.0, y0, opt);
}

// y0 with every free coordinate displaced uniformly in [-dx, dx] and every free velocity set
// uniformly in [-dv, dv] (pinned points untouched).
Vec random_state(const MassSpringNetwork& n, double dx, double dv, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = n.initial_state();
  const Index dofs = n.dofs();
  for (Index p = 0; p < n.num_points(); ++p) {
    if (n.points()[static_cast<std::size_t>(p)].pinned) continue;
    for (int c = 0; c < n.dim(); ++c) {
      y[n.dim() * p + c] += dx * u(rng);
      y[dofs + n.dim() * p + c] = dv * u(rng);
    }
  }
  return y;
}

double spring_length(const MassSpringNetwork& n, const Spring& s, CVecRef x) {
  return (x.segment(n.dim() * s.j, n.dim()) - x.segment(n.dim() * s.i, n.dim())).norm();
}

Vec accel(const MassSpringNetwork& n, const Vec& x, const Vec& v) {
  Vec a(n.dofs());
  n.acceleration(0.0, x, v, a);
  return a;
}

// Central differences of the acceleration, column by column: truncation δ²|a'''|/6 and
// round-off ε|a|/δ, both far below 1e-6 of the largest entry with δ = 1e-6 here.
Mat fd_block(const MassSpringNetwork& n, const Vec& x, const Vec& v, bool wrt_x) {
  const Index dofs = n.dofs();
  Mat j(dofs, dofs);
  for (Index col = 0; col < dofs; ++col) {
    Vec xp = x, xm = x, vp = v, vm = v;
    const double delta = 1e-6 * std::max(1.0, std::abs(wrt_x ? x[col] : v[col]));
    (wrt_x ? xp : vp)[col] += delta;
    (wrt_x ? xm : vm)[col] -= delta;
    j.col(col) = (accel(n, xp, vp) - accel(n, xm, vm)) / (2 * delta);
  }
  return j;
}

// Networks with stretched and compressed springs, dashpots and point damping, in 1D, 2D, 3D.
std::vector<std::unique_ptr<OdeSystem>> jacobian_cases(bool compressed_dd) {
  const std::string dd = compressed_dd ? "compressed_dd=true" : "compressed_dd=false";
  std::vector<std::unique_ptr<OdeSystem>> out;
  out.push_back(model("spring_chain", {"n=4", "dashpot=0.3", "gamma=0.2", "k=2", "mass=0.7"}));
  out.push_back(model("pendulum_chain", {"n=3", "k=50"}));
  out.push_back(model("cloth", {"n=4", "m=3", "pin=corners", "dashpot=0.05", "damping=0.02",
                                "perturbation=0", "prestretch=1.02", dd}));
  out.push_back(model(
      "soft_cube", {"n=2", "dashpot=0.2", "damping=0.01", "scenario=compress", "factor=0.9", dd}));
  // Air drag on the triangles (without dashpots: D on K's pattern for the drag alone).
  out.push_back(model(
      "cloth", {"n=4", "m=3", "pin=corners", "drag=0.8", "perturbation=0", "prestretch=1.02", dd}));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Jacobians.

TEST(MassSpringJacobian, MatchesFiniteDifferencesAtRandomStates) {
  for (const auto& sys : jacobian_cases(false)) {
    const MassSpringNetwork& n = net(*sys);
    SCOPED_TRACE(n.name());
    for (unsigned seed : {1u, 2u, 3u}) {
      // Displacements of ~30% of a spring length give both stretched and compressed springs.
      const Vec y = random_state(n, 0.3 * n.springs()[0].rest, 1.0, seed);
      const Vec x = y.head(n.dofs()), v = y.tail(n.dofs());
      int stretched = 0, compressed = 0;
      for (const Spring& s : n.springs())
        (spring_length(n, s, x) > s.rest ? stretched : compressed)++;
      EXPECT_GT(stretched, 0);
      EXPECT_GT(compressed, 0);

      SparseMat ks, ds;
      n.stiffness_block(0.0, x, v, ks);
      n.damping_block(0.0, x, v, ds);
      const Mat k(ks), d(ds), k_fd = fd_block(n, x, v, true), d_fd = fd_block(n, x, v, false);
      EXPECT_LE((k - k_fd).cwiseAbs().maxCoeff(), 1e-6 * k.cwiseAbs().maxCoeff())
          << "seed " << seed;
      EXPECT_LE((d - d_fd).cwiseAbs().maxCoeff(), 1e-6 * d.cwiseAbs().maxCoeff())
          << "seed " << seed;
      // Damped cases: the dashpot terms are present and D is not trivially zero.
      EXPECT_EQ(n.velocity_dependent(), !d.isZero(0.0));
    }
  }
}

// The compressed-spring option drops exactly k (1 - L/l)(I - d dᵀ)/m_i from the spring's blocks
// (minus at (i, i), plus at (i, j), and the same from j's end) for every compressed spring; the
// forces and D are unchanged. The dropped term is computed here from the positions.
TEST(MassSpringJacobian, CompressedOptionDropsExactlyTheTransverseTerm) {
  auto exact_cases = jacobian_cases(false);
  auto dd_cases = jacobian_cases(true);
  for (std::size_t c = 2; c < exact_cases.size(); ++c) {  // the models with compressed_dd
    const MassSpringNetwork& exact = net(*exact_cases[c]);
    const MassSpringNetwork& dd = net(*dd_cases[c]);
    SCOPED_TRACE(exact.name());
    const Vec y = random_state(exact, 0.3 * exact.springs()[0].rest, 1.0, 7);
    const Index nd = exact.dofs();
    const int dim = exact.dim();
    const Vec x = y.head(nd), v = y.tail(nd);
    SparseMat k1, k2, d1, d2;
    exact.stiffness_block(0.0, x, v, k1);
    dd.stiffness_block(0.0, x, v, k2);
    exact.damping_block(0.0, x, v, d1);
    dd.damping_block(0.0, x, v, d2);
    Mat dropped = Mat::Zero(nd, nd);
    int n_compressed = 0;
    for (const Spring& s : exact.springs()) {
      const Vec r = x.segment(dim * s.j, dim) - x.segment(dim * s.i, dim);
      const double l = r.norm();
      if (l >= s.rest) continue;
      ++n_compressed;
      const Vec u = r / l;
      const Mat t = s.k * (1 - s.rest / l) * (Mat::Identity(dim, dim) - u * u.transpose());
      for (auto [p, q] : {std::pair{s.i, s.j}, std::pair{s.j, s.i}}) {
        if (exact.points()[static_cast<std::size_t>(p)].pinned) continue;
        const double m = exact.points()[static_cast<std::size_t>(p)].mass;
        dropped.block(dim * p, dim * p, dim, dim) -= t / m;
        dropped.block(dim * p, dim * q, dim, dim) += t / m;
      }
    }
    EXPECT_GT(n_compressed, 0);
    const Mat diff = Mat(k1) - Mat(k2);
    EXPECT_LE((diff - dropped).cwiseAbs().maxCoeff(), 1e-13 * Mat(k1).cwiseAbs().maxCoeff());
    EXPECT_GT(dropped.cwiseAbs().maxCoeff(), 1e-3 * Mat(k1).cwiseAbs().maxCoeff());
    EXPECT_TRUE(Mat(d1) == Mat(d2));
    EXPECT_TRUE(accel(exact, x, v) == accel(dd, x, v));
  }
}

// One pattern for K and D at every state (pinned rows included, as explicit zeros), and the
// first-order Jacobian keeps it: implicit solvers analyse it once.
TEST(MassSpringJacobian, FixedPatternAndZeroPinnedRows) {
  auto sys = model("cloth", {"n=5", "pin=corners", "dashpot=0.1"});
  const MassSpringNetwork& n = net(*sys);
  const Index nd = n.dofs();
  SparseMat k0, d0;
  const Vec y0 = n.initial_state();
  n.stiffness_block(0, y0.head(nd), y0.tail(nd), k0);
  n.damping_block(0, y0.head(nd), y0.tail(nd), d0);
  auto same_pattern = [](const SparseMat& a, const SparseMat& b) {
    if (a.nonZeros() != b.nonZeros() || a.outerSize() != b.outerSize()) return false;
    for (Index c = 0; c <= a.outerSize(); ++c)
      if (a.outerIndexPtr()[c] != b.outerIndexPtr()[c]) return false;
    for (Index k = 0; k < a.nonZeros(); ++k)
      if (a.innerIndexPtr()[k] != b.innerIndexPtr()[k]) return false;
    return true;
  };
  EXPECT_TRUE(same_pattern(k0, d0));
  for (unsigned seed : {4u, 5u}) {
    const Vec y = random_state(n, 0.03, 0.5, seed);
    SparseMat k, d;
    n.stiffness_block(0, y.head(nd), y.tail(nd), k);
    n.damping_block(0, y.head(nd), y.tail(nd), d);
    EXPECT_TRUE(same_pattern(k, k0));
    EXPECT_TRUE(same_pattern(d, k0));
    const Mat kd(k), dd(d);
    for (Index p = 0; p < n.num_points(); ++p) {
      if (!n.points()[static_cast<std::size_t>(p)].pinned) continue;
      EXPECT_TRUE(kd.middleRows(3 * p, 3).isZero(0.0));
      EXPECT_TRUE(dd.middleRows(3 * p, 3).isZero(0.0));
    }
    SparseMat j, j0;
    sys->jacobian(0, y, j);
    sys->jacobian(0, y0, j0);
    EXPECT_TRUE(same_pattern(j, j0));
  }
}

// ---------------------------------------------------------------------------------------------
// Conservation laws.

// Internal forces (springs and dashpots) come in equal and opposite pairs along d, so without
// gravity, pins and point damping Σ m v is constant; RK4 preserves linear invariants exactly,
// so only round-off remains. Velocity Verlet's kicks (central forces) and drifts (x += h v)
// each leave Σ m x × v unchanged, so angular momentum is also kept to round-off.
TEST(MassSpringConservation, MomentumOfFreeBodies) {
  struct Case {
    std::string model;
    std::vector<std::string> params;
  };
  const std::vector<Case> cases = {
      {"soft_cube", {"n=3", "gravity=0", "dashpot=0.1", "spin=0"}},
      {"cloth", {"n=5", "pin=none", "gravity=0", "dashpot=0.02"}},
  };
  for (const Case& c : cases) {
    auto sys = model(c.model, c.params);
    const MassSpringNetwork& n = net(*sys);
    SCOPED_TRACE(c.model);
    const Vec y0 = random_state(n, 0.1 * n.springs()[0].rest, 1.0, 11);
    double scale = 0.0;  // Σ m |v|: the size of the momenta being summed
    for (Index p = 0; p < n.num_points(); ++p)
      scale +=
          n.points()[static_cast<std::size_t>(p)].mass * y0.segment(n.dofs() + 3 * p, 3).norm();
    const RunResult r = run(n, "rk4", 1e-3, 0.5, y0);
    ASSERT_EQ(r.stats.status, Status::ok);
    const Vec p0 = n.linear_momentum(y0), p1 = n.linear_momentum(r.y);
    EXPECT_GT(p0.cwiseAbs().maxCoeff(), 1e-3 * scale);  // a non-trivial momentum
    EXPECT_LE(max_abs_diff(p0, p1), 1e-14 * scale) << p0.transpose() << " vs " << p1.transpose();
    // The invariants() list offers all three components in this configuration.
    int momenta = 0;
    for (const Invariant& inv : sys->invariants()) {
      if (inv.name.rfind("momentum_", 0) != 0) continue;
      ++momenta;
      EXPECT_NEAR(inv.value(0, r.y), inv.value(0, y0), 1e-14 * scale) << inv.name;
    }
    EXPECT_EQ(momenta, 3);
  }
  // Angular momentum under velocity Verlet (undamped: Verlet refuses dashpots).
  auto cube = model("soft_cube", {"n=3", "gravity=0"});
  const MassSpringNetwork& n = net(*cube);
  const Vec y0 = random_state(n, 0.02, 1.0, 12);
  const RunResult r = run(n, "velocity_verlet", 1e-3, 0.5, y0);
  const Vec l0 = n.angular_momentum(y0), l1 = n.angular_momentum(r.y);
  double l_scale = 0.0;  // Σ m |x||v|: the size of the terms being summed
  for (Index p = 0; p < n.num_points(); ++p)
    l_scale += n.points()[static_cast<std::size_t>(p)].mass * y0.segment(3 * p, 3).norm() *
               y0.segment(n.dofs() + 3 * p, 3).norm();
  EXPECT_GT(l0.norm(), 1e-2 * l_scale);
  EXPECT_LE(max_abs_diff(l0, l1), 1e-13 * l_scale) << l0.transpose() << " vs " << l1.transpose();
}

// Undamped chain with a random (all-mode) initial displacement: RK4's energy error per step is
// O((hω)⁶); with hω_max = 0.02 over 10 time units the drift is far below 1e-8.
TEST(MassSpringConservation, UndampedChainEnergyUnderRk4) {
  auto sys = model("spring_chain", {"perturbation=0.2", "seed=3"});
  const Vec y0 = sys->initial_state();
  const auto inv = sys->invariants();
  ASSERT_EQ(inv[0].name, "energy");
  const double e0 = inv[0].value(0, y0);
  const RunResult r = run(*sys, "rk4", 0.01, 10.0, y0);
  EXPECT_NEAR(inv[0].value(10.0, r.y), e0, 1e-8 * e0);
  // A 3D nonlinear case: the default cloth (gravity, pins) over 0.5 time units.
  auto cloth = model("cloth", {"n=6"});
  const Vec c0 = cloth->initial_state();
  const double ec0 = cloth->invariants()[0].value(0, c0);
  const RunResult rc = run(*cloth, "rk4", 2.5e-4, 0.5, c0);
  EXPECT_NEAR(cloth->invariants()[0].value(0.5, rc.y), ec0, 1e-8 * std::abs(ec0));
}

// With damping dE/dt = -γ Σ|v|² - Σ c ((v_j - v_i)·d)² (power of the dissipative forces); the
// left side is ∇E·f with ∇E by central differences of energy().
TEST(MassSpringConservation, DampedEnergyRateIsDissipatedPower) {
  auto sys = model("cloth", {"n=4", "pin=corners", "damping=0.03", "dashpot=0.05"});
  const MassSpringNetwork& n = net(*sys);
  const Vec y = random_state(n, 0.02, 0.7, 21);
  const Index nd = n.dofs();
  Vec grad(2 * nd), f(2 * nd);
  for (Index i = 0; i < 2 * nd; ++i) {
    Vec yp = y, ym = y;
    const double d = 1e-6;
    yp[i] += d;
    ym[i] -= d;
    grad[i] = (n.energy(yp) - n.energy(ym)) / (2 * d);
  }
  sys->rhs(0, y, f);
  double power = 0.0;
  for (Index p = 0; p < n.num_points(); ++p)
    if (!n.points()[static_cast<std::size_t>(p)].pinned)
      power -= 0.03 * y.segment(nd + 3 * p, 3).squaredNorm();
  for (const Spring& s : n.springs()) {
    const Vec r = y.segment(3 * s.j, 3) - y.segment(3 * s.i, 3);
    const double sd = (y.segment(nd + 3 * s.j, 3) - y.segment(nd + 3 * s.i, 3)).dot(r / r.norm());
    power -= s.damping * sd * sd;
  }
  EXPECT_LT(power, 0.0);
  EXPECT_NEAR(grad.dot(f), power, 1e-7 * std::abs(power));
}

// ---------------------------------------------------------------------------------------------
// The chain: normal modes and stiffness.

// docs/reference-values.md: ω_max = 2√(k/m) sin(Nπ/(2(N+1))) = 1.979643 (fixed–fixed) and
// 2√(k/m) sin((2N-1)π/(2(2N+1))) = 1.977662 (fixed–free) for k = m = 1, N = 10. The top two
// frequencies differ by 0.03 (fixed–fixed), which is what makes plain power iteration slow.
TEST(MassSpringStiffness, ChainOmegaMaxFromLanczos) {
  for (const auto& [ends, expected] :
       {std::pair{"fixed_fixed", 1.979643}, std::pair{"fixed_free", 1.977662}}) {
    SCOPED_TRACE(ends);
    auto sys = model("spring_chain", {std::string("ends=") + ends});
    const MassSpringNetwork& n = net(*sys);
    const Vec y0 = sys->initial_state();
    const double w = *sys->stiffness(0, y0);
    EXPECT_NEAR(w, expected, 1e-6);
    EXPECT_EQ(w, n.omega_max_estimate(y0.head(n.dofs())));
    SpringChainOptions o;
    o.fixed_free = std::string(ends) == "fixed_free";
    EXPECT_NEAR(w, spring_chain_frequency(o, 10), 1e-12);  // the formula in double precision
    // Bound: ω² <= (2/m)·2k·max(1, |1 - L/l|) = 4, since |1 - L/l| < 1 for l > L/2.
    const double bound = n.omega_max_bound(y0.head(n.dofs()));
    EXPECT_GE(bound, w);
    EXPECT_NEAR(bound, 2.0, 1e-15);
  }
}

// Lanczos against Eigen's dense symmetric eigensolver on M^{-1/2}(-∂f/∂x)M^{-1/2} over free
// dofs (assembled here from -M K with the dashpot-free network, so K is exactly the spring
// part), at a random state with compressed springs (an indefinite matrix): both extreme
// eigenvalues agree. stiffness() is then the spectral radius of the first-order Jacobian
// [[0, I], [K, 0]], checked with Eigen's general eigensolver.
TEST(MassSpringStiffness, LanczosMatchesDenseEigensolvers) {
  auto sys = model("cloth", {"n=5", "m=4", "pin=corners", "prestretch=0.97"});
  const MassSpringNetwork& n = net(*sys);
  const Index nd = n.dofs();
  const Vec y = random_state(n, 0.02, 0.0, 31);
  SparseMat ks;
  n.stiffness_block(0, y.head(nd), y.tail(nd), ks);
  std::vector<Index> free_dofs;
  for (Index i = 0; i < nd; ++i)
    if (!n.points()[static_cast<std::size_t>(i / 3)].pinned) free_dofs.push_back(i);
  const Index nf = static_cast<Index>(free_dofs.size());
  const Mat k(ks);
  Mat s(nf, nf);
  const Vec m = n.masses();
  for (Index a = 0; a < nf; ++a)
    for (Index b = 0; b < nf; ++b)
      s(a, b) = -m[free_dofs[a]] * k(free_dofs[a], free_dofs[b]) /
                std::sqrt(m[free_dofs[a]] * m[free_dofs[b]]);
  const Vec eig = Eigen::SelfAdjointEigenSolver<Mat>(s, Eigen::EigenvaluesOnly).eigenvalues();
  ASSERT_LT(eig[0], 0.0);  // compressed springs: indefinite
  const auto [lo, hi] = n.stiffness_eigen_range(y.head(nd));
  const double scale = eig.cwiseAbs().maxCoeff();
  EXPECT_NEAR(lo, eig[0], 1e-9 * scale);
  EXPECT_NEAR(hi, eig[nf - 1], 1e-9 * scale);
  SparseMat jac;
  sys->jacobian(0, y, jac);
  const double rho = Eigen::EigenSolver<Mat>(Mat(jac), false).eigenvalues().cwiseAbs().maxCoeff();
  EXPECT_NEAR(*sys->stiffness(0, y), rho, 1e-8 * rho);
  EXPECT_GE(n.omega_max_bound(y.head(nd)), rho);
}

// Mode j of the chain moves as the damped oscillator q'' + (γ/m + cω_j²/k) q' + ω_j² q = 0
// (header of builders.hpp); RK4 at h = 1e-3 (global error ~ (hω)⁴ ≈ 1e-12) is the independent
// computation.
TEST(MassSpringChain, ExactModalSolutionMatchesRk4) {
  const std::vector<std::vector<std::string>> cases = {
      {},
      {"mode=7", "amplitude=0.3", "ends=fixed_free"},
      {"mode=3", "gamma=0.2", "dashpot=0.1"},
      {"mode=10", "dashpot=1.2", "k=2", "mass=0.5"},  // overdamped top mode
  };
  for (const auto& params : cases) {
    SCOPED_TRACE(join(params));
    auto sys = model("spring_chain", params);
    ASSERT_TRUE(sys->has_exact());
    const Vec y0 = sys->initial_state();
    Vec e0(sys->dimension());
    sys->exact(0, e0);
    EXPECT_TRUE(e0 == y0);
    const RunResult r = run(*sys, "rk4", 1e-3, 3.0, y0);
    Vec e(sys->dimension());
    sys->exact(3.0, e);
    EXPECT_LE(max_abs_diff(r.y, e), 1e-10) << (r.y - e).transpose();
  }
  EXPECT_FALSE(model("spring_chain", {"perturbation=0.1"})->has_exact());
}

// ---------------------------------------------------------------------------------------------
// Parallel right-hand side.

// 64 × 64 = 4096 points take the OpenMP path (threshold 2048). Each point sums its own springs
// in a fixed order, so 1 and 2 threads, and the serial path, agree bit for bit.
TEST(MassSpringParallel, BitwiseIdenticalForAnyThreadCount) {
  auto par = model("cloth", {"n=64", "dashpot=0.02", "damping=0.01", "pin=corners", "drag=0.5"});
  auto ser = model("cloth", {"n=64", "dashpot=0.02", "damping=0.01", "pin=corners", "drag=0.5",
                             "parallel_threshold=100000"});
  const MassSpringNetwork& np = net(*par);
  ASSERT_TRUE(np.parallel());
  ASSERT_FALSE(net(*ser).parallel());
  const Vec y = random_state(np, 0.02, 0.5, 41);
  const Index nd = np.dofs();
  const int saved = omp_get_max_threads();
  auto eval = [&](const MassSpringNetwork& n, int threads) {
    omp_set_num_threads(threads);
    EXPECT_EQ(omp_get_max_threads(), threads);
    Vec f(2 * nd);
    n.rhs(0, y, f);
    SparseMat k, d;
    n.stiffness_block(0, y.head(nd), y.tail(nd), k);
    n.damping_block(0, y.head(nd), y.tail(nd), d);
    return std::tuple{f, k, d};
  };
  // Same structure and bitwise the same values (a dense copy would need 1.2 GB).
  auto same = [](const SparseMat& a, const SparseMat& b) {
    if (a.nonZeros() != b.nonZeros() || a.outerSize() != b.outerSize()) return false;
    return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1,
                      b.outerIndexPtr()) &&
           std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr()) &&
           std::equal(a.valuePtr(), a.valuePtr() + a.nonZeros(), b.valuePtr());
  };
  const auto [f1, k1, d1] = eval(np, 1);
  const auto [f2, k2, d2] = eval(np, 2);
  const auto [fs, ks, ds] = eval(net(*ser), 2);
  omp_set_num_threads(saved);
  EXPECT_TRUE(f1 == f2);
  EXPECT_TRUE(f1 == fs);
  EXPECT_TRUE(same(k1, k2) && same(k1, ks));
  EXPECT_TRUE(same(d1, d2) && same(d1, ds));
  EXPECT_GT(f1.tail(nd).cwiseAbs().maxCoeff(), 0.0);
}

// The explicit and symplectic steppers update their vectors in fused passes, over OpenMP threads
// above 50,000 entries (cloth 130² has 50,700 dofs, 101,400 entries). Independent computation:
// the textbook RK4 and velocity Verlet written with Eigen vector operations. Velocity Verlet's
// per-entry arithmetic (terms added left to right) is the fused passes' own, so it agrees bit for
// bit; rk4 runs in its accelerations alone and agrees to within rounding. 1 and 2 threads agree
// bit for bit for every method.
TEST(MassSpringParallel, ExplicitAndSymplecticStepsBitwiseForAnyThreadCount) {
  auto sys = model("cloth", {"n=130", "pin=corners"});
  const MassSpringNetwork& nw = net(*sys);
  const Index nd = nw.dofs();
  ASSERT_GE(nd, 50000);
  const Vec y0 = random_state(nw, 0.01, 0.2, 7);
  const double h = 1e-4;
  const int saved = omp_get_max_threads();
  auto steps = [&](const std::string& name, int threads) {
    omp_set_num_threads(threads);
    auto integ = integrator(name);
    Vec y = y0;
    SolveStats stats;
    integ->reset(*sys, 0.0, y);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(integ->step(*sys, k * h, y, h, stats), Status::ok);
    return y;
  };
  std::map<std::string, Vec> two;
  for (const std::string name :
       {"euler", "rk4", "rk38", "symplectic_euler", "velocity_verlet", "verlet", "leapfrog"}) {
    const Vec a = steps(name, 1), b = steps(name, 2);
    EXPECT_TRUE(a == b) << name << ": 1 and 2 threads differ by " << max_abs_diff(a, b);
    two[name] = b;
  }
  omp_set_num_threads(saved);

  // Textbook RK4 (Eigen expressions, one axpy at a time).
  Vec y = y0, k1(2 * nd), k2(2 * nd), k3(2 * nd), k4(2 * nd), tmp(2 * nd);
  for (int k = 0; k < 3; ++k) {
    const double t = k * h;
    sys->rhs(t, y, k1);
    tmp = y;
    tmp.noalias() += (h * 0.5) * k1;
    sys->rhs(t + 0.5 * h, tmp, k2);
    tmp = y;
    tmp.noalias() += (h * 0.5) * k2;
    sys->rhs(t + 0.5 * h, tmp, k3);
    tmp = y;
    tmp.noalias() += (h * 1.0) * k3;
    sys->rhs(t + h, tmp, k4);
    y.noalias() += (h * (1.0 / 6.0)) * k1;
    y.noalias() += (h * (1.0 / 3.0)) * k2;
    y.noalias() += (h * (1.0 / 3.0)) * k3;
    y.noalias() += (h * (1.0 / 6.0)) * k4;
  }
  // rk4 runs a mechanical system in its accelerations alone (explicit_rk.hpp): the same values
  // as the first-order form to within rounding, 64 ε ‖y‖∞ a step (tests/integrators/
  // test_step_norm.cpp derives the bound).
  EXPECT_LE(max_abs_diff(y, two["rk4"]),
            3 * 64 * std::numeric_limits<double>::epsilon() * y.cwiseAbs().maxCoeff());
  EXPECT_GT(max_abs_diff(y, y0), 1e-6);

  // Velocity Verlet: v += h/2 a(x); x += h v; v += h/2 a(x), a evaluated once per step.
  Vec x = y0.head(nd), v = y0.tail(nd), a(nd);
  nw.acceleration(0, x, v, a);
  for (int k = 0; k < 3; ++k) {
    v.noalias() += (h * 0.5) * a;
    x.noalias() += (h * 1.0) * v;
    nw.acceleration((k + 1) * h, x, v, a);
    v.noalias() += (h * 0.5) * a;
  }
  Vec vv(2 * nd);
  vv << x, v;
  EXPECT_TRUE(vv == two["velocity_verlet"]) << max_abs_diff(vv, two["velocity_verlet"]);
}

// Velocity Verlet reuses the last acceleration without comparing positions: one evaluation per
// step after the first. Handing it another state (another storage) makes it evaluate afresh,
// so the step from that state equals a fresh integrator's (bitwise).
TEST(MassSpringIntegrators, VelocityVerletReusesAccelerationAndRestartsOnAnotherState) {
  auto sys = model("cloth", {"n=6"});
  auto integ = integrator("velocity_verlet");
  Vec y = sys->initial_state();
  SolveStats stats;
  integ->reset(*sys, 0.0, y);
  sys->reset_counters();
  for (int k = 0; k < 10; ++k) integ->step(*sys, k * 1e-3, y, 1e-3, stats);
  EXPECT_EQ(sys->counters().f_evals, 11);  // 2 in the first step, then 1 per step

  Vec other = sys->initial_state();
  integ->step(*sys, 0.0, other, 1e-3, stats);  // another storage: fresh evaluation
  auto fresh = integrator("velocity_verlet");
  Vec expected = sys->initial_state();
  fresh->reset(*sys, 0.0, expected);
  fresh->step(*sys, 0.0, expected, 1e-3, stats);
  EXPECT_TRUE(other == expected) << max_abs_diff(other, expected);
}

// ---------------------------------------------------------------------------------------------
// Pinned points and velocity dependence.

// a = 0 and v = 0 at pinned points, so every stage leaves them where they are, bit for bit.
TEST(MassSpringPinned, StayExactlyFixedUnderSeveralIntegrators) {
  for (const char* pin : {"corners", "top_edge"}) {
    auto sys = model("cloth", {"n=6", std::string("pin=") + pin});
    const MassSpringNetwork& n = net(*sys);
    const Vec y0 = n.initial_state();
    const Index nd = n.dofs();
    for (const char* method : {"euler", "heun", "rk4", "symplectic_euler", "velocity_verlet"}) {
      SCOPED_TRACE(std::string(pin) + " " + method);
      const RunResult r = run(n, method, 2e-3, 0.5, y0);
      ASSERT_EQ(r.stats.status, Status::ok);
      int pinned = 0;
      for (Index p = 0; p < n.num_points(); ++p) {
        if (!n.points()[static_cast<std::size_t>(p)].pinned) continue;
        ++pinned;
        EXPECT_TRUE(r.y.segment(3 * p, 3) == y0.segment(3 * p, 3));
        EXPECT_TRUE(r.y.segment(nd + 3 * p, 3).isZero(0.0));
      }
      EXPECT_EQ(pinned, std::string(pin) == "corners" ? 2 : 6);
      EXPECT_GT(max_abs_diff(r.y, y0), 1e-3);  // the rest of the cloth moved
    }
  }
}

// velocity_dependent() is true exactly when point damping or a dashpot is non-zero, and the
// Verlet family refuses such networks.
TEST(MassSpringPinned, VelocityDependenceFlag) {
  EXPECT_FALSE(net(*model("cloth", {"n=3"})).velocity_dependent());
  EXPECT_TRUE(net(*model("cloth", {"n=3", "damping=0.1"})).velocity_dependent());
  EXPECT_TRUE(net(*model("cloth", {"n=3", "dashpot=0.1"})).velocity_dependent());
  auto damped = model("cloth", {"n=3", "dashpot=0.1"});
  EXPECT_THROW(run(*damped, "velocity_verlet", 1e-3, 0.01, damped->initial_state()), BadInput);
}

// ---------------------------------------------------------------------------------------------
// Free fall of the centre of mass.

// Internal forces cancel in pairs, so the centre of mass of the soft cube moves as
// x_cm(t) = x_cm(0) + v_cm(0) t + ½ g t² (g = -9.81 e_z) whatever the vibration; RK4 integrates
// this quadratic exactly, leaving round-off.
TEST(MassSpringCube, CentreOfMassFallsFreely) {
  for (const char* scenario : {"scenario=drop", "scenario=compress"}) {
    SCOPED_TRACE(scenario);
    auto sys = model("soft_cube", {scenario});
    const MassSpringNetwork& n = net(*sys);
    const Vec y0 = sys->initial_state();
    const double t = 0.4;
    const RunResult r = run(n, "rk4", 1e-3, t, y0);
    auto cm = [&](const Vec& y, Index offset) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (Index p = 0; p < n.num_points(); ++p) c += y.segment<3>(offset + 3 * p);
      return Eigen::Vector3d(c / static_cast<double>(n.num_points()));
    };
    const Eigen::Vector3d x0 = cm(y0, 0), v0 = cm(y0, n.dofs());
    const Eigen::Vector3d expected = x0 + v0 * t + 0.5 * t * t * Eigen::Vector3d(0, 0, -9.81);
    EXPECT_LE((cm(r.y, 0) - expected).cwiseAbs().maxCoeff(), 1e-12);
    // and the body does deform: some spring is off its rest length by more than round-off
    double worst = 0.0;
    for (const Spring& s : n.springs())
      worst = std::max(worst, std::abs(spring_length(n, s, r.y.head(n.dofs())) - s.rest));
    EXPECT_GT(worst, 1e-6);
  }
}

// ---------------------------------------------------------------------------------------------
// Constraints.

// 10,000 velocity Verlet steps of the constrained pendulum chain keep
// max|C| below 1e-10 (the projection stops at 1e-13 L), and velocities are tangent.
TEST(MassSpringConstraints, ResidualAfterTenThousandVerletSteps) {
  auto sys = model("pendulum_chain", {"constrained=true"});
  ASSERT_TRUE(sys->has_constraints());
  EXPECT_FALSE(sys->stiffness(0, sys->initial_state()).has_value());
  const Vec y0 = sys->initial_state();
  EXPECT_LE(sys->constraint_residual(y0), 1e-15);
  const RunResult r = run(*sys, "velocity_verlet", 1e-3, 10.0, y0);
  ASSERT_EQ(r.n_steps, 10000);
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_LT(sys->constraint_residual(r.y), 1e-10);
  const MassSpringNetwork& n = net(*sys);
  for (const DistanceConstraint& c : n.constraints()) {
    const Eigen::Vector2d d = r.y.segment<2>(2 * c.j) - r.y.segment<2>(2 * c.i);
    const Eigen::Vector2d dv =
        r.y.segment<2>(n.dofs() + 2 * c.j) - r.y.segment<2>(n.dofs() + 2 * c.i);
    EXPECT_LE(std::abs(dv.dot(d.normalized())), 1e-12);
  }
  EXPECT_GT(max_abs_diff(r.y, y0), 0.1);  // it swung
}

// project(): on the manifold afterwards, idempotent, pinned points untouched; the Gauss–Seidel
// fallback (taken when a duplicated constraint makes G M⁻¹ Gᵀ singular) reaches the same
// tolerance.
TEST(MassSpringConstraints, ProjectionPutsStateOnManifold) {
  for (bool duplicate : {false, true}) {
    SCOPED_TRACE(duplicate ? "duplicated constraint (Gauss-Seidel fallback)" : "direct");
    std::vector<MassPoint> pts(4);
    for (int i = 0; i < 4; ++i) {
      pts[static_cast<std::size_t>(i)].x = {0.3 * i, -0.1 * i * i, 0.0};
      pts[static_cast<std::size_t>(i)].mass = 0.5 + 0.25 * i;
    }
    pts[0].pinned = true;
    std::vector<DistanceConstraint> cons = {{0, 1, 0.3}, {1, 2, 0.35}, {2, 3, 0.3}};
    if (duplicate) cons.push_back({2, 1, 0.35});
    NetworkOptions opt;
    opt.gravity = {0.0, -9.81, 0.0};
    const MassSpringNetwork n("constrained_test", 2, pts, {}, opt, cons);
    Vec y = random_state(n, 0.02, 1.0, 51);
    const Vec before = y;
    n.project(0, y);
    EXPECT_LE(n.constraint_residual(y), 5e-14);  // 1e-13 L plus the round-off floor
    EXPECT_TRUE(y.segment(0, 2) == before.segment(0, 2));
    EXPECT_TRUE(y.segment(n.dofs(), 2).isZero(0.0));
    for (const DistanceConstraint& c : n.constraints()) {
      const Eigen::Vector2d d = y.segment<2>(2 * c.j) - y.segment<2>(2 * c.i);
      const Eigen::Vector2d dv =
          y.segment<2>(n.dofs() + 2 * c.j) - y.segment<2>(n.dofs() + 2 * c.i);
      EXPECT_LE(std::abs(dv.dot(d.normalized())), 1e-12);
    }
    Vec again = y;
    n.project(0, again);
    // Direct: an exact no-op. Gauss–Seidel applies one more sweep of corrections below its
    // stopping tolerance 1e-13 max|v| before it sees convergence.
    EXPECT_LE(max_abs_diff(again, y), duplicate ? 1e-13 : 0.0);
  }
}

// The projection after free flight is first order (header of network.hpp): differences of
// successive halvings of h shrink by 2. Measured with velocity Verlet at T = 1:
// d(h) = |y_h - y_{h/2}| ≈ 3.0 h for the default 5-link chain.
TEST(MassSpringConstraints, ProjectedVerletIsFirstOrder) {
  auto sys = model("pendulum_chain", {"constrained=true"});
  std::vector<Vec> ys;
  for (double h : {2e-3, 1e-3, 5e-4})
    ys.push_back(run(*sys, "velocity_verlet", h, 1.0, sys->initial_state()).y);
  const double d1 = max_abs_diff(ys[0], ys[1]), d2 = max_abs_diff(ys[1], ys[2]);
  EXPECT_NEAR(std::log2(d1 / d2), 1.0, 0.1) << d1 << " " << d2;
}

// As k → ∞ the stiff-spring chain converges to the constrained one. Reference: the constrained
// chain by velocity Verlet + projection at h = 4e-5 and 2e-5, Richardson-extrapolated
// (2 y_{h/2} - y_h removes the first-order error; extrapolating from 2e-5/1e-5 instead changes
// it by 7.6e-9). Spring chains by RK4 with h = 0.1/√(k/m) (halving h changes them by < 1e-7).
// Measured max position difference at t = 1 (n = 3): 2.18e-2 (k = 1e3), 1.89e-3 (1e4),
// 1.97e-4 (1e5), 1.88e-5 (1e6, not run here): like 1/k (the links stretch by O(mg/k) and
// oscillate with that amplitude), not 1/√k.
TEST(MassSpringConstraints, StiffSpringChainConvergesToConstrained) {
  const double t = 1.0;
  auto constrained = model("pendulum_chain", {"n=3", "constrained=true"});
  const Vec y_h = run(*constrained, "velocity_verlet", 4e-5, t, constrained->initial_state()).y;
  const Vec y_h2 = run(*constrained, "velocity_verlet", 2e-5, t, constrained->initial_state()).y;
  const Index nd = net(*constrained).dofs();
  const Vec ref = (2 * y_h2 - y_h).head(nd);
  std::vector<double> diff;
  for (double k : {1e3, 1e4, 1e5}) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "k=%g", k);
    auto springs = model("pendulum_chain", {"n=3", buf});
    const double h = 0.1 / std::sqrt(k / 0.2);
    const RunResult r = run(*springs, "rk4", h, t, springs->initial_state());
    ASSERT_EQ(r.stats.status, Status::ok);
    diff.push_back(max_abs_diff(r.y.head(nd), ref));
  }
  for (std::size_t i = 0; i + 1 < diff.size(); ++i) {
    EXPECT_GT(diff[i] / diff[i + 1], 5.0) << diff[i] << " -> " << diff[i + 1];  // ~10: 1/k
    EXPECT_LT(diff[i] / diff[i + 1], 20.0) << diff[i] << " -> " << diff[i + 1];
  }
  EXPECT_NEAR(diff[2], 1.97e-4, 0.2e-4);
}

// ---------------------------------------------------------------------------------------------
// Registration.

TEST(MassSpringRegistry, EveryModelIsMechanicalWithDefaultsThatReachTheBuilders) {
  for (const char* name : {"spring_chain", "cloth", "soft_cube", "pendulum_chain"}) {
    const auto* entry = model_registry().find(name);
    ASSERT_NE(entry, nullptr) << name;
    EXPECT_TRUE(entry->info.mechanical);
    for (const ParamSpec& p : entry->params) EXPECT_FALSE(p.default_value.empty()) << p.key;
  }
  // The builders' defaults reach the registry: 16 × 16 cloth, 3 dofs per point.
  EXPECT_EQ(model("cloth")->dimension(), 2 * 3 * 16 * 16);
  EXPECT_EQ(model("cloth", {"n=5", "m=3"})->dimension(), 2 * 3 * 15);
}

TEST(MassSpringRegistry, BadParametersNameTheKey) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"spring_chain", {"n=0"}},           {"spring_chain", {"mode=11"}},
      {"spring_chain", {"amplitude=0.6"}}, {"cloth", {"n=1"}},
      {"cloth", {"k_shear=-1"}},           {"cloth", {"perturbation=0.05"}},
      {"soft_cube", {"factor=0"}},         {"pendulum_chain", {"length=0"}},
  };
  for (const auto& [name, params] : cases) {
    const std::string key = params[0].substr(0, params[0].find('='));
    try {
      model(name, params);
      ADD_FAILURE() << name << " " << params[0] << ": no BadInput";
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace stiffbench

namespace stiffbench {
namespace {

// Without dashpots K is filled column block by column block (K_qp = J_s/m_q,
// force_jacobians.cpp) and D is diagonal: both checked against central finite differences of the
// accelerations (an independent computation) on a 3D network with unequal masses, a pinned
// point, point damping and stretched and compressed springs; a second evaluation into the same
// matrices writes in place (same storage) and gives the same values, and force_jacobians equals
// the separate calls.
TEST(MassSpringJacobian, InPlaceColumnFillWithUnequalMassesAndPins) {
  std::vector<MassPoint> pts(5);
  const double masses[] = {0.5, 1.7, 3.0, 0.9, 2.2};
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i].mass = masses[i];
    const double s = static_cast<double>(i);
    pts[i].x = {std::cos(s), std::sin(1.3 * s), 0.4 * s};
    pts[i].v = {0.1 * s, -0.2, 0.05 * s};
  }
  pts[0].pinned = true;
  std::vector<Spring> springs;
  for (Index i = 0; i < 5; ++i)
    for (Index j = i + 1; j < 5; ++j)
      springs.push_back({i, j, 10.0 + static_cast<double>(i + 2 * j), (i + j) % 2 ? 0.6 : 1.9});
  NetworkOptions opt;
  opt.point_damping = 0.3;
  opt.gravity = {0.0, 0.0, -9.81};
  const MassSpringNetwork n("net", 3, pts, springs, opt);
  ASSERT_TRUE(n.symmetric_force_jacobians());
  const Vec y = n.initial_state();
  const Vec x = y.head(n.dofs()), v = y.tail(n.dofs());
  SparseMat k, d;
  n.force_jacobians(0.0, x, v, k, d);
  const Mat k_fd = fd_block(n, x, v, true), d_fd = fd_block(n, x, v, false);
  EXPECT_LE((Mat(k) - k_fd).cwiseAbs().maxCoeff(), 1e-6 * k_fd.cwiseAbs().maxCoeff());
  EXPECT_LE((Mat(d) - d_fd).cwiseAbs().maxCoeff(), 1e-6 * d_fd.cwiseAbs().maxCoeff());
  EXPECT_EQ(d.nonZeros(), n.dofs());  // diagonal pattern without dashpots
  const double* kp = k.valuePtr();
  const Mat k1(k);
  n.force_jacobians(0.0, x, v, k, d);
  EXPECT_EQ(k.valuePtr(), kp);
  EXPECT_EQ(Mat(k), k1);
  SparseMat ks, ds;
  n.stiffness_block(0.0, x, v, ks);
  n.damping_block(0.0, x, v, ds);
  EXPECT_EQ(Mat(ks), Mat(k));
  EXPECT_EQ(Mat(ds), Mat(d));
}

}  // namespace
}  // namespace stiffbench
