// Additive splits f = f_E + f_I of the models (OdeSystem::imex_split): for every split
// model and split value the parts add up to f, J_I is the Jacobian of f_I, the counters count
// each part; the kaps and advection_diffusion exact solutions; the explicit parts' spectrum
// estimates against dense eigenvalues; split=none leaves the mass-spring right-hand side bitwise
// unchanged, and the parts are bitwise independent of the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "core/split_views.hpp"
#include "models/mass_spring/network.hpp"
#include "models/problems/advection_diffusion.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

constexpr double kEps = 2.220446049250313e-16;  // machine epsilon (double)

struct SplitCase {
  std::string model;
  std::vector<std::string> params;
  std::string split;  // the name imex_split() must report
};

// Every split model and split value, with damping and dashpots switched on where the model has
// them so that every term is present in one part or the other.
std::vector<SplitCase> split_cases() {
  return {
      {"kaps", {"eps=1e-6"}, "stiff"},
      {"kaps", {"eps=0.01"}, "stiff"},
      {"advection_diffusion", {"n=32", "nu=0.003", "r=0.7", "k=3"}, "advection"},
      {"spring_chain", {"n=6", "gamma=0.3", "dashpot=0.2", "split=springs"}, "springs"},
      {"soft_cube", {"n=2", "damping=0.1", "dashpot=0.05", "split=springs"}, "springs"},
      {"cloth", {"n=5", "damping=0.02", "dashpot=0.01", "split=springs"}, "springs"},
      {"cloth", {"n=5", "damping=0.02", "dashpot=0.01", "split=stretch"}, "stretch"},
      {"cloth", {"n=5", "split=stretch"}, "stretch"},  // no dashpots: symmetric K_I, D_I = 0
      // Air drag in f_E, kept out of J_I (drag's blocks would make J_I differ from f_I's).
      {"cloth", {"n=5", "damping=0.02", "dashpot=0.01", "drag=0.6", "split=springs"}, "springs"},
      {"cloth", {"n=5", "drag=0.6", "split=stretch"}, "stretch"},
  };
}

std::string label(const SplitCase& c) {
  std::string s = c.model;
  for (const auto& p : c.params) s += " " + p;
  return s;
}

// A state away from the initial one: first-order models y0 + 0.3 u; mechanical ones move every
// free coordinate by 0.02 u and give it a velocity 0.5 u (u uniform in [-1, 1]); pinned dofs stay.
Vec random_state(const OdeSystem& sys, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec y = sys.initial_state();
  const MechanicalSystem* mech = sys.as_mechanical();
  if (!mech) {
    for (Index i = 0; i < y.size(); ++i) y[i] += 0.3 * u(rng);
    return y;
  }
  const Index n = mech->dofs();
  const std::vector<Index> fixed = mech->fixed_dofs();
  for (Index i = 0; i < n; ++i) {
    if (std::find(fixed.begin(), fixed.end(), i) != fixed.end()) continue;
    y[i] += 0.02 * u(rng);
    y[n + i] = 0.5 * u(rng);
  }
  return y;
}

Vec eval(const OdeSystem& sys, const Vec& y, int part) {  // part: 0 f, 1 f_E, 2 f_I
  Vec f(sys.dimension());
  if (part == 0) sys.rhs(0.0, y, f);
  if (part == 1) sys.rhs_explicit_part(0.0, y, f);
  if (part == 2) sys.rhs_implicit_part(0.0, y, f);
  return f;
}

Mat dense_jacobian(const OdeSystem& sys, const Vec& y, bool implicit_part) {
  SparseMat j;
  if (implicit_part)
    sys.implicit_part_jacobian(0.0, y, j);
  else
    sys.jacobian(0.0, y, j);
  return Mat(j);
}

// f_E + f_I = f up to rounding. Each component of f is a sum of at most ~30 terms (a cloth
// point has 12 springs, each spring a few products) that the parts sum in two groups: the
// difference is bounded by a few tens of ulps of the terms' magnitude, which the parts'
// magnitudes bound: 64 eps (‖f_E‖∞ + ‖f_I‖∞) per component. Kaps' f1 adds -(2 + 1/ε) y1 and
// y2²/ε where the parts add -y1/ε + y2²/ε and -2 y1: the same bound holds.
TEST(Splits, PartsAddUpToTheRightHandSide) {
  for (const SplitCase& c : split_cases()) {
    SCOPED_TRACE(label(c));
    auto sys = model(c.model, c.params);
    ASSERT_TRUE(sys->has_imex_split());
    ASSERT_TRUE(sys->imex_split().has_value());
    EXPECT_EQ(sys->imex_split()->name, c.split);
    EXPECT_FALSE(sys->imex_split()->explicit_part.empty());
    EXPECT_FALSE(sys->imex_split()->implicit_part.empty());
    for (unsigned seed : {1u, 2u}) {
      const Vec y = random_state(*sys, seed);
      const Vec f = eval(*sys, y, 0), fe = eval(*sys, y, 1), fi = eval(*sys, y, 2);
      const double scale = fe.cwiseAbs().maxCoeff() + fi.cwiseAbs().maxCoeff();
      EXPECT_GT(fe.cwiseAbs().maxCoeff(), 0.0);  // both parts are non-trivial here
      EXPECT_GT(fi.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_LE(max_abs_diff(fe + fi, f), 64 * kEps * scale);
    }
  }
}

// J_I against central differences of f_I (through the implicit part's view, whose rhs is f_I).
// Central differences with the increment eps^(1/3)·|y_j| (fd_increment) are accurate to about
// eps^(2/3) ≈ 4e-11 relative to the Jacobian's scale for these smooth f_I (truncation O(δ²
// f'''), rounding O(eps f/δ)); 1e-6 of the largest entry leaves a wide margin and still catches
// any wrong entry, sign or missing term (the smallest structural entries are ~1e-3 of the
// largest here).
TEST(Splits, ImplicitPartJacobianMatchesFiniteDifferences) {
  for (const SplitCase& c : split_cases()) {
    SCOPED_TRACE(label(c));
    auto sys = model(c.model, c.params);
    ASSERT_TRUE(sys->has_implicit_part_jacobian());
    const Vec y = random_state(*sys, 3);
    const Mat ji = dense_jacobian(*sys, y, true);
    const auto view = implicit_part_view(*sys);
    const Mat fd = finite_difference_jacobian(*view, 0.0, y);
    const double scale = ji.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_LE((ji - fd).cwiseAbs().maxCoeff(), 1e-6 * scale);
  }
}

// One call of a part adds one to f_evals and one to its own counter; the Jacobian of f_I one to
// jac_evals.
TEST(Splits, CountersCountEachPart) {
  for (const SplitCase& c : split_cases()) {
    SCOPED_TRACE(label(c));
    auto sys = model(c.model, c.params);
    const Vec y = sys->initial_state();
    sys->reset_counters();
    eval(*sys, y, 1);
    EXPECT_EQ(sys->counters().f_evals, 1);
    EXPECT_EQ(sys->counters().fe_evals, 1);
    EXPECT_EQ(sys->counters().fi_evals, 0);
    eval(*sys, y, 2);
    eval(*sys, y, 2);
    EXPECT_EQ(sys->counters().f_evals, 3);
    EXPECT_EQ(sys->counters().fe_evals, 1);
    EXPECT_EQ(sys->counters().fi_evals, 2);
    SparseMat j;
    sys->implicit_part_jacobian(0.0, y, j);
    EXPECT_EQ(sys->counters().jac_evals, 1);
    EXPECT_EQ(sys->counters().f_evals, 3);
  }
}

// ---------------------------------------------------------------------------------------------
// kaps

// The exact solution y = (e^{-2t}, e^{-t}) satisfies y' = f(y): the derivative (-2e^{-2t},
// -e^{-t}) by hand, and independently a central difference of exact() (step 1e-5: truncation
// h²/6 |y'''| ≤ 8e-10/6, rounding eps/h ≈ 2e-11). In f1 the 1/ε terms cancel exactly in exact
// arithmetic (y2² = y1); in floating point they leave a few ulps of y1 times 1/ε: 4 eps/ε ≈ 1e-9
// at ε = 1e-6.
TEST(Kaps, ExactSolutionSatisfiesTheOde) {
  for (double eps : {1e-2, 1e-6}) {
    auto sys = model("kaps", {"eps=" + std::to_string(eps)});
    ASSERT_TRUE(sys->has_exact());
    for (double t : {0.0, 0.3, 1.0, 2.5}) {
      Vec y(2), yp(2), ym(2), f(2);
      sys->exact(t, y);
      EXPECT_DOUBLE_EQ(y[0], std::exp(-2 * t));
      EXPECT_DOUBLE_EQ(y[1], std::exp(-t));
      sys->rhs(t, y, f);
      const double tol = 4 * kEps / eps + 1e-14;
      EXPECT_NEAR(f[0], -2 * std::exp(-2 * t), tol);
      EXPECT_NEAR(f[1], -std::exp(-t), 1e-14);
      const double h = 1e-5;
      sys->exact(t + h, yp);
      sys->exact(t - h, ym);
      EXPECT_LE(max_abs_diff((yp - ym) / (2 * h), f), 3e-10 + tol);
    }
  }
}

// J and J_I against the formulas: J - J_I = ∂f_E/∂y = [[-2, 0], [1, -1 - 2 y2]] (the split's
// Jacobians add up), whose eigenvalues -2 and -1 - 2y2 give the explicit part's spectrum exactly.
TEST(Kaps, ExplicitPartSpectrumIsTheEigenvaluesOfJMinusJI) {
  auto sys = model("kaps", {"eps=1e-6"});
  const Vec y{{0.7, -1.9}};
  const Mat je = dense_jacobian(*sys, y, false) - dense_jacobian(*sys, y, true);
  EXPECT_NEAR(je(0, 0), -2.0, 1e-9);  // rounding of (2 + 1e6) - 1e6
  EXPECT_EQ(je(0, 1), 0.0);
  EXPECT_EQ(je(1, 0), 1.0);
  EXPECT_DOUBLE_EQ(je(1, 1), -1.0 - 2.0 * y[1]);
  const Eigen::VectorXcd ev = Eigen::EigenSolver<Mat>(je).eigenvalues();
  const auto spec = sys->explicit_part_spectrum(0.0, y);
  ASSERT_TRUE(spec.has_value());
  EXPECT_EQ(spec->ray, SpectrumEstimate::Ray::negative_real);
  EXPECT_NEAR(spec->radius, ev.cwiseAbs().maxCoeff(), 1e-8);  // 2.8 = |-1 + 3.8|
  EXPECT_NEAR(spec->radius, 2.8, 1e-12);
  // The Gershgorin stiffness bounds the spectral radius of J and is close to it (≈ 1/ε).
  const Eigen::VectorXcd evj =
      Eigen::EigenSolver<Mat>(dense_jacobian(*sys, y, false)).eigenvalues();
  EXPECT_GE(*sys->stiffness(0.0, y), evj.cwiseAbs().maxCoeff());
  EXPECT_LE(*sys->stiffness(0.0, y), 1.01 * evj.cwiseAbs().maxCoeff());
}

TEST(Kaps, RejectsNonPositiveEps) {
  EXPECT_THROW(model("kaps", {"eps=0"}), BadInput);
  EXPECT_THROW(model("kaps", {"eps=-1"}), BadInput);
  EXPECT_THROW(model("kaps", {"split=springs"}), BadInput);
}

// ---------------------------------------------------------------------------------------------
// advection_diffusion

// The exact solution e^{μt} sin(θj - ωt) against an independent computation: rk4 at h = 2.5e-4
// to t = 1 on n = 32, a = 1, ν = 3e-3, r = 0.7, k = 3. The fastest mode has |λ| ≈ 33, so
// h|λ| ≈ 0.008 and rk4's global error ≈ t |λ|^5 h^4/120 ≈ 1e-10 at worst (the initial mode itself,
// |λ| ≈ 18, much less): agreement to 1e-9 checks the formula for μ and ω, including the sign of
// the travel direction and the discrete phase speed (an error in ω of 1e-6 would show).
TEST(AdvectionDiffusion, ExactSolutionMatchesATightRk4Run) {
  auto sys = model("advection_diffusion", {"n=32", "nu=0.003", "r=0.7", "k=3"});
  ASSERT_TRUE(sys->has_exact());
  auto rk4 = make("rk4");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 2.5e-4;
  const RunResult r = run_fixed_step(*sys, *rk4, opt);
  ASSERT_EQ(r.stats.status, Status::ok);
  Vec exact(32);
  sys->exact(1.0, exact);
  EXPECT_LE(max_abs_diff(r.y, exact), 1e-9);
  // The solution has decayed and moved: the check is not of a state near y0.
  EXPECT_GT(max_abs_diff(exact, sys->initial_state()), 0.5);
  Vec y0(32);
  sys->exact(0.0, y0);
  EXPECT_LE(max_abs_diff(y0, sys->initial_state()), 1e-15);
}

// The explicit part's spectrum against the dense eigenvalues of J - J_I (the central advection
// operator): purely imaginary, largest modulus (a/Δx) max_m |sin(2πm/N)| — a/Δx = 32 for N = 32
// (m = 8 gives sin(π/2) = 1) and 30·sin(14π/30) for N = 30. stiffness() against the dense
// eigenvalues of J.
TEST(AdvectionDiffusion, SpectraMatchDenseEigenvalues) {
  for (int n : {32, 30}) {
    SCOPED_TRACE(n);
    auto sys =
        model("advection_diffusion", {"n=" + std::to_string(n), "a=1.5", "nu=0.01", "r=2", "k=1"});
    const Vec y = sys->initial_state();
    const Mat j = dense_jacobian(*sys, y, false);
    const Mat je = j - dense_jacobian(*sys, y, true);
    const Eigen::VectorXcd ev = Eigen::EigenSolver<Mat>(je).eigenvalues();
    EXPECT_LE(ev.real().cwiseAbs().maxCoeff(), 1e-10);  // skew-symmetric: imaginary axis
    const auto spec = sys->explicit_part_spectrum(0.0, y);
    ASSERT_TRUE(spec.has_value());
    EXPECT_EQ(spec->ray, SpectrumEstimate::Ray::imaginary);
    EXPECT_NEAR(spec->radius, ev.cwiseAbs().maxCoeff(), 1e-10 * spec->radius);
    const double expected = n == 32 ? 1.5 * 32 : 1.5 * 30 * std::sin(14 * 3.141592653589793 / 30);
    EXPECT_NEAR(spec->radius, expected, 1e-12 * expected);
    const Eigen::VectorXcd evj = Eigen::EigenSolver<Mat>(j).eigenvalues();
    EXPECT_NEAR(*sys->stiffness(0.0, y), evj.cwiseAbs().maxCoeff(),
                1e-10 * *sys->stiffness(0.0, y));
  }
}

TEST(AdvectionDiffusion, RejectsBadParameters) {
  EXPECT_THROW(model("advection_diffusion", {"n=2"}), BadInput);
  EXPECT_THROW(model("advection_diffusion", {"nu=-1"}), BadInput);
  EXPECT_THROW(model("advection_diffusion", {"r=-0.1"}), BadInput);
  EXPECT_THROW(model("advection_diffusion", {"split=none"}), BadInput);
}

// ---------------------------------------------------------------------------------------------
// Mass-spring networks

const MassSpringNetwork& net(const OdeSystem& sys) {
  return dynamic_cast<const MassSpringNetwork&>(sys);
}

// split=none is the default and no split; a split network's full f (rhs) is the unsplit one,
// bit for bit (the split adds code paths for the parts only).
TEST(MassSpringSplits, SplitNoneAndTheFullRightHandSideAreBitwiseUnchanged) {
  const std::vector<std::string> base{"n=6", "damping=0.02", "dashpot=0.01"};
  auto plain = model("cloth", base);
  EXPECT_FALSE(plain->has_imex_split());
  EXPECT_FALSE(plain->imex_split().has_value());
  auto none = base, springs = base, stretch = base;
  none.push_back("split=none");
  springs.push_back("split=springs");
  stretch.push_back("split=stretch");
  const Vec y = random_state(*plain, 5);
  const Vec f = eval(*plain, y, 0);
  EXPECT_TRUE(eval(*model("cloth", none), y, 0) == f);
  EXPECT_TRUE(eval(*model("cloth", springs), y, 0) == f);
  EXPECT_TRUE(eval(*model("cloth", stretch), y, 0) == f);
  EXPECT_FALSE(model("cloth", none)->has_imex_split());
}

// K_I and D_I: springs: K_I = K and D_I = D + (γ/m) I (the dashpots only); stretch: a pattern of
// the structural pairs only. An n × n cloth has 2n(n-1) structural springs (grid edges) and
// n²(≈8) springs in all, so K_I holds 9 (n² + 2·2n(n-1)) entries (a 3×3 block per point and per
// ordered structural pair), fewer than K's. Written in place: a second call keeps the storage.
TEST(MassSpringSplits, ImplicitForceJacobians) {
  const long n = 6;
  auto sp = model("cloth", {"n=6", "damping=0.02", "dashpot=0.01", "split=springs"});
  auto st = model("cloth", {"n=6", "damping=0.02", "dashpot=0.01", "split=stretch"});
  const MechanicalSystem& ms = *sp->as_mechanical();
  const Vec y = random_state(*sp, 6);
  const Index nd = ms.dofs();
  SparseMat k, d, ki, di;
  ms.force_jacobians(0.0, y.head(nd), y.tail(nd), k, d);
  ms.implicit_force_jacobians(0.0, y.head(nd), y.tail(nd), ki, di);
  EXPECT_EQ(Mat(ki - k).cwiseAbs().maxCoeff(), 0.0);
  const Vec m = ms.masses();
  Mat d_expected = Mat(d);
  for (Index i = 0; i < nd; ++i)
    if (d_expected(i, i) != 0.0 || Mat(d).row(i).cwiseAbs().maxCoeff() != 0.0)
      d_expected(i, i) += 0.02 / m[i];
  // Pinned rows are zero in both.
  for (Index i : ms.fixed_dofs()) d_expected(i, i) = 0.0;
  EXPECT_LE((Mat(di) - d_expected).cwiseAbs().maxCoeff(), 1e-14 * Mat(d).cwiseAbs().maxCoeff());
  EXPECT_TRUE(ms.implicit_part_velocity_dependent());
  EXPECT_FALSE(ms.symmetric_implicit_force_jacobians());

  const MechanicalSystem& mt = *st->as_mechanical();
  SparseMat kt, dt;
  mt.implicit_force_jacobians(0.0, y.head(nd), y.tail(nd), kt, dt);
  EXPECT_EQ(kt.nonZeros(), 9 * (n * n + 4 * n * (n - 1)));
  EXPECT_LT(kt.nonZeros(), k.nonZeros());
  const double* values = kt.valuePtr();
  const Vec y2 = random_state(*st, 7);
  mt.implicit_force_jacobians(0.0, y2.head(nd), y2.tail(nd), kt, dt);
  EXPECT_EQ(kt.valuePtr(), values);  // same storage: values written in place
  auto nodash = model("cloth", {"n=6", "split=stretch"});
  EXPECT_FALSE(nodash->as_mechanical()->implicit_part_velocity_dependent());
  EXPECT_TRUE(nodash->as_mechanical()->symmetric_implicit_force_jacobians());
}

// Explicit part's spectrum. springs: J - J_I = [[0, 0], [0, -(γ/m) I]] on free points, so the
// eigenvalues are 0 and -γ/m = -0.02/0.01 = -2: exact. stretch (no damping): J - J_I =
// [[0, 0], [K_E, 0]] is nilpotent; what limits an explicit treatment of a_E is the oscillation
// of the explicit springs under x' = v, the eigenvalues ±iω of [[0, I], [K_E, 0]], i.e. ω² the
// eigenvalues of -K_E = -(K - K_I). The Gershgorin bound of ω_max bounds the largest ω from
// above, and is within a factor 2 of it on this lattice.
TEST(MassSpringSplits, ExplicitPartSpectrum) {
  auto sp = model("cloth", {"n=5", "damping=0.02", "split=springs"});
  const Vec y = random_state(*sp, 8);
  const Mat je = dense_jacobian(*sp, y, false) - dense_jacobian(*sp, y, true);
  const Eigen::VectorXcd ev = Eigen::EigenSolver<Mat>(je).eigenvalues();
  auto spec = sp->explicit_part_spectrum(0.0, y);
  ASSERT_TRUE(spec.has_value());
  EXPECT_EQ(spec->ray, SpectrumEstimate::Ray::negative_real);
  EXPECT_NEAR(spec->radius, 2.0, 1e-14);
  EXPECT_NEAR(ev.cwiseAbs().maxCoeff(), 2.0, 1e-12);

  auto st = model("cloth", {"n=5", "split=stretch"});
  const MechanicalSystem& ms = *st->as_mechanical();
  const Vec ys = random_state(*st, 9);
  const Index nd = ms.dofs();
  SparseMat k, d, ki, di;
  ms.force_jacobians(0.0, ys.head(nd), ys.tail(nd), k, d);
  ms.implicit_force_jacobians(0.0, ys.head(nd), ys.tail(nd), ki, di);
  const Mat minus_ke = -(Mat(k) - Mat(ki));
  const double largest =
      std::sqrt(Eigen::EigenSolver<Mat>(minus_ke).eigenvalues().real().maxCoeff());
  spec = st->explicit_part_spectrum(0.0, ys);
  ASSERT_TRUE(spec.has_value());
  EXPECT_EQ(spec->ray, SpectrumEstimate::Ray::imaginary);
  EXPECT_GE(spec->radius, largest);
  EXPECT_LE(spec->radius, 2.0 * largest);
}

// 64 × 64 = 4096 points take the OpenMP path: both parts are bitwise the same for 1 and 2 threads
// and for the serial path.
TEST(MassSpringSplits, PartsBitwiseIdenticalForAnyThreadCount) {
  for (const std::string split : {"springs", "stretch"}) {
    SCOPED_TRACE(split);
    const std::vector<std::string> p{"n=64",        "dashpot=0.02", "damping=0.01",
                                     "pin=corners", "drag=0.5",     "split=" + split};
    auto par = model("cloth", p);
    auto sp = p;
    sp.push_back("parallel_threshold=100000");
    auto ser = model("cloth", sp);
    ASSERT_TRUE(net(*par).parallel());
    ASSERT_FALSE(net(*ser).parallel());
    const Vec y = random_state(*par, 10);
    const int saved = omp_get_max_threads();
    for (int part : {1, 2}) {
      omp_set_num_threads(1);
      const Vec f1 = eval(*par, y, part);
      omp_set_num_threads(2);
      const Vec f2 = eval(*par, y, part);
      const Vec fs = eval(*ser, y, part);
      EXPECT_TRUE(f1 == f2);
      EXPECT_TRUE(f1 == fs);
    }
    omp_set_num_threads(saved);
  }
}

// The implicit part of a split cloth is a cloth of its implicit springs alone. Independent
// systems with the same a: for stretch, a cloth with k_shear = k_bend = 0, no gravity and no
// point damping (its K has zero shear and bend blocks; K_I of the split has none; no dashpots,
// which the zero-stiffness springs would keep); for springs (with dashpots: D_I), the same cloth
// without gravity and point damping. backward_euler (velocity-form Newton on the implicit part's
// view: K_I, D_I, masses, pinned dofs) on both, 20 steps of 0.01: the trajectories agree to the
// Newton tolerance (1e-10 allows for the different patterns' rounding in the linear solves).
TEST(MassSpringSplits, ImplicitViewIsTheClothOfTheImplicitSprings) {
  struct Case {
    std::vector<std::string> split, alone;
  };
  const std::vector<Case> cases{
      {{"split=stretch", "damping=0.05", "gravity=2"}, {"k_shear=0", "k_bend=0", "gravity=0"}},
      {{"split=springs", "dashpot=0.01", "damping=0.05", "gravity=2"},
       {"dashpot=0.01", "gravity=0"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.split[0]);
    auto with = [&](std::vector<std::string> extra) {
      extra.insert(extra.end(), {"n=6", "perturbation=0.01"});
      return model("cloth", extra);
    };
    auto split = with(c.split);
    auto alone = with(c.alone);
    const auto view = implicit_part_view(*split);
    ASSERT_NE(view->as_mechanical(), nullptr);
    FixedStepOptions opt;
    opt.t_end = 0.2;
    opt.h = 0.01;
    const RunResult a = run_fixed_step(*view, *make("backward_euler"), opt);
    const RunResult b = run_fixed_step(*alone, *make("backward_euler"), opt);
    ASSERT_EQ(a.stats.status, Status::ok);
    ASSERT_EQ(b.stats.status, Status::ok);
    EXPECT_GT(max_abs_diff(a.y, split->initial_state()), 1e-3);  // the cloth has moved
    EXPECT_LE(max_abs_diff(a.y, b.y), 1e-10);
    EXPECT_GT(split->counters().fi_evals, 0);  // the view evaluates through the model
    EXPECT_EQ(split->counters().fe_evals, 0);
  }
}

TEST(MassSpringSplits, RejectsUnknownSplits) {
  EXPECT_THROW(model("cloth", {"split=bogus"}), BadInput);
  EXPECT_THROW(model("spring_chain", {"split=stretch"}), BadInput);
  EXPECT_THROW(model("soft_cube", {"split=stretch"}), BadInput);
}

}  // namespace
}  // namespace stiffbench
