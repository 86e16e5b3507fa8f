// The problem models, checked against theory and independent computations: exact solutions
// satisfy the ODE and start at the initial state, harmonic-oscillator solutions equal exp(At)y0,
// Kepler orbits close after one period with the textbook energy and angular momentum, analytic
// Jacobians equal finite differences, invariants are conserved, evaluations are counted at the
// boundary, bad parameters are BadInput naming the key, and stiffness() is the spectral radius.
// Only the five problem models of models/problems/ are covered here.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "core/ode_system.hpp"
#include "core/params.hpp"
#include "experiments/framework/catalog.hpp"

namespace stiffbench {
namespace {

using Assignments = std::vector<std::string>;

struct Case {
  std::string model;
  Assignments params;
};

std::string describe(const Case& c) { return c.model + " {" + join(c.params, ", ") + "}"; }

std::unique_ptr<OdeSystem> make(const Case& c) {
  return model_registry().create(c.model, Params::from_assignments(c.params));
}

Vec exact_at(const OdeSystem& sys, double t) {
  Vec y(sys.dimension());
  sys.exact(t, y);
  return y;
}

Vec rhs_at(const OdeSystem& sys, double t, const Vec& y) {
  Vec f(sys.dimension());
  sys.rhs(t, y, f);
  return f;
}

Mat analytic_jacobian(const OdeSystem& sys, double t, const Vec& y) {
  SparseMat j;
  sys.jacobian(t, y, j);
  return Mat(j);
}

double inf_norm(const Vec& v) { return v.cwiseAbs().maxCoeff(); }

// Largest |eigenvalue| of a dense matrix (Eigen's QR-based solver: independent of the models).
double spectral_radius(const Mat& m) {
  return Eigen::EigenSolver<Mat>(m, false).eigenvalues().cwiseAbs().maxCoeff();
}

// The problem models this file covers (models/problems/; the mass-spring models have their own
// tests).
const std::vector<std::string> kProblemModels = {"dahlquist", "harmonic_oscillator", "kepler",
                                                 "pendulum", "prothero_robinson"};

// Every problem model with its defaults, then the parameter sets the models are known for.
std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (const auto& name : kProblemModels) cases.push_back({name, {}});
  const std::vector<Case> extra = {
      {"dahlquist", {"lambda_re=-0.5", "lambda_im=3"}},
      {"dahlquist", {"lambda_re=-0.5", "lambda_im=3", "y0_re=0.4", "y0_im=-1.2"}},
      {"harmonic_oscillator", {"m=2", "k=3", "x0=0.7", "v0=-1.3"}},
      {"harmonic_oscillator", {"gamma=0.5"}},                        // underdamped
      {"harmonic_oscillator", {"gamma=0.5", "x0=0.7", "v0=-1.3"}},   // underdamped
      {"harmonic_oscillator", {"gamma=2"}},                          // critical (m = k = 1)
      {"harmonic_oscillator", {"gamma=2", "x0=0.7", "v0=-1.3"}},     // critical
      {"harmonic_oscillator", {"m=2", "k=8", "gamma=8", "v0=0.9"}},  // critical: γ = 2√(km)
      {"harmonic_oscillator", {"gamma=5"}},                          // overdamped
      {"harmonic_oscillator", {"gamma=5", "x0=0.7", "v0=-1.3"}},     // overdamped
      {"kepler", {"e=0"}},
      {"kepler", {"e=0.7"}},
      {"kepler", {"e=0.7", "gm=2", "a=1.5"}},
      {"kepler", {"e=0.9"}},
      {"pendulum", {"theta0=2.5", "omega0=-0.4", "g=9.81", "length=2"}},
      {"prothero_robinson", {"lambda=-20", "y0_offset=0.3", "phi=sin"}},
      {"prothero_robinson", {"lambda=-20", "y0_offset=0.3", "phi=cos"}},
      {"prothero_robinson", {"lambda=-20", "y0_offset=0.3", "phi=exp"}},
  };
  cases.insert(cases.end(), extra.begin(), extra.end());
  return cases;
}

// A few states per model at which to compare derivatives: the initial state, points on the exact
// trajectory when there is one, and the initial state pushed off in a fixed direction.
std::vector<Vec> sample_states(const OdeSystem& sys) {
  const Vec y0 = sys.initial_state();
  std::vector<Vec> states{y0};
  if (sys.has_exact()) {
    for (double t : {0.4, 1.3, 2.9}) states.push_back(exact_at(sys, sys.initial_time() + t));
  }
  const Vec dir = Vec{{0.31, -0.17, 0.23, -0.41}}.head(sys.dimension());
  states.push_back(y0 + dir);
  states.push_back(y0 - 0.5 * dir);
  return states;
}

// ---------------------------------------------------------------------------------------------
// 1. Exact solutions satisfy the ODE and start at the initial state.

// Metadata agrees with the object the factory builds.
TEST(ModelsRegistry, InfoMatchesCreatedModel) {
  ASSERT_FALSE(model_registry().entries().empty());
  for (const auto& entry : model_registry().entries()) {
    SCOPED_TRACE(entry.info.name);
    auto sys = model_registry().create(entry.info.name, Params{});
    EXPECT_EQ(sys->name(), entry.info.name);
    EXPECT_EQ(sys->has_exact(), entry.info.exact);
    EXPECT_EQ(sys->as_mechanical() != nullptr, entry.info.mechanical);
    EXPECT_EQ(sys->initial_state().size(), sys->dimension());
    if (const MechanicalSystem* mech = sys->as_mechanical()) {
      EXPECT_EQ(sys->dimension(), 2 * mech->dofs());
      EXPECT_EQ(mech->masses().size(), mech->dofs());
    }
  }
}

// Central difference (y(t+δ) - y(t-δ))/(2δ) has truncation error δ²|y'''|/6 and round-off
// ε|y|/δ; with δ = 1e-5 and the time scales here (>= 0.05) both are below 1e-8 relative.
TEST(ModelsExact, SatisfiesOdeByCentralDifference) {
  int checked = 0;
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    if (!sys->has_exact()) continue;
    ++checked;
    const double delta = 1e-5;
    for (double dt : {0.05, 0.3, 1.1, 2.7, 5.3}) {
      const double t = sys->initial_time() + dt;
      SCOPED_TRACE("t = " + std::to_string(t));
      const Vec fd = (exact_at(*sys, t + delta) - exact_at(*sys, t - delta)) / (2 * delta);
      const Vec f = rhs_at(*sys, t, exact_at(*sys, t));
      EXPECT_LE(max_abs_diff(fd, f), 1e-6 * inf_norm(f) + 1e-12)
          << "fd = " << fd.transpose() << "\nf  = " << f.transpose();
    }
  }
  EXPECT_GE(checked, 4);  // dahlquist, harmonic_oscillator, kepler, prothero_robinson
}

TEST(ModelsExact, StartsAtInitialState) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    if (!sys->has_exact()) continue;
    const Vec y0 = sys->initial_state();
    EXPECT_LE(max_abs_diff(exact_at(*sys, sys->initial_time()), y0), 1e-15 * inf_norm(y0));
  }
}

// ---------------------------------------------------------------------------------------------
// 2. Independent checks of exact solutions.

// y(t) = exp(At) y0 with A = [[0, 1], [-k/m, -γ/m]], exp from Eigen's Padé scaling-and-squaring.
TEST(ModelsExact, HarmonicOscillatorEqualsMatrixExponential) {
  struct HoCase {
    double m, k, gamma, x0, v0;
  };
  const std::vector<HoCase> cases = {
      {1, 1, 0, 1, 0},
      {2, 3, 0, 0.7, -1.3},
      {1, 1, 0.5, 1, 0},
      {1, 1, 0.5, 0.7, -1.3},
      {1, 1, 2, 1, 0},
      {1, 1, 2, 0.7, -1.3},
      {2, 8, 8, 0, 0.9},
      {1, 1, 5, 1, 0},
      {1, 1, 5, 0.7, -1.3},
      {0.5, 40, 1, 0.2, 3.0},
      {1, 1, 2.000002, 0.7, -1.3},  // just overdamped: β² - ω0² ≈ 2e-6
      {1, 1, 1.999998, 0.7, -1.3},  // just underdamped
  };
  for (const HoCase& hc : cases) {
    const Case c{"harmonic_oscillator",
                 {"m=" + std::to_string(hc.m), "k=" + std::to_string(hc.k),
                  "gamma=" + std::to_string(hc.gamma), "x0=" + std::to_string(hc.x0),
                  "v0=" + std::to_string(hc.v0)}};
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    Eigen::Matrix2d a;
    a << 0, 1, -hc.k / hc.m, -hc.gamma / hc.m;
    const Eigen::Vector2d y0(hc.x0, hc.v0);
    for (double t : {0.3, 1.7, 4.2, 10.0}) {
      const Eigen::Matrix2d at = a * t;
      const Eigen::Vector2d expected = at.exp() * y0;
      EXPECT_LE(max_abs_diff(exact_at(*sys, t), expected), 1e-12 * y0.cwiseAbs().maxCoeff())
          << "t = " << t << " expected " << expected.transpose() << " got "
          << exact_at(*sys, t).transpose();
    }
  }
}

struct KeplerCase {
  double e, gm, a;
};

const std::vector<KeplerCase> kKeplerCases = {
    {0, 1, 1}, {0.7, 1, 1}, {0.7, 2, 1.5}, {0.3, 0.5, 2}, {0.9, 1, 1}};

Case kepler_case(const KeplerCase& kc) {
  return {
      "kepler",
      {"e=" + std::to_string(kc.e), "gm=" + std::to_string(kc.gm), "a=" + std::to_string(kc.a)}};
}

// The orbit closes after T = 2π√(a³/GM) (Kepler's third law) and is at apocentre after T/2:
// q = (-a(1+e), 0), v = (0, -√(GM/a·(1-e)/(1+e))) (vis-viva).
TEST(ModelsExact, KeplerPeriodAndApocentre) {
  for (const KeplerCase& kc : kKeplerCases) {
    SCOPED_TRACE(describe(kepler_case(kc)));
    auto sys = make(kepler_case(kc));
    const double period = 2 * std::numbers::pi * std::sqrt(kc.a * kc.a * kc.a / kc.gm);
    const Vec y0 = sys->initial_state();
    const double scale = inf_norm(y0);
    EXPECT_LE(max_abs_diff(exact_at(*sys, period), y0), 1e-12 * scale);
    EXPECT_LE(max_abs_diff(exact_at(*sys, 3 * period), y0), 1e-12 * scale);
    const Vec apo{
        {-kc.a * (1 + kc.e), 0.0, 0.0, -std::sqrt(kc.gm / kc.a * (1 - kc.e) / (1 + kc.e))}};
    EXPECT_LE(max_abs_diff(exact_at(*sys, period / 2), apo), 1e-12 * scale);
    // Pericentre state from the vis-viva equation v² = GM(2/r - 1/a) at r = a(1 - e).
    const double rp = kc.a * (1 - kc.e);
    EXPECT_NEAR(y0[0], rp, 1e-15 * rp);
    EXPECT_EQ(y0[1], 0.0);
    EXPECT_EQ(y0[2], 0.0);
    const double vp = std::sqrt(kc.gm * (2 / rp - 1 / kc.a));
    EXPECT_NEAR(y0[3], vp, 1e-14 * vp);
  }
}

// Energy -GM/(2a) and angular momentum √(GM a (1 - e²)) (Goldstein §3.7), computed here from the
// state and also through the model's invariants().
TEST(ModelsExact, KeplerEnergyAndAngularMomentum) {
  for (const KeplerCase& kc : kKeplerCases) {
    SCOPED_TRACE(describe(kepler_case(kc)));
    auto sys = make(kepler_case(kc));
    const double energy = -kc.gm / (2 * kc.a);
    const double ang = std::sqrt(kc.gm * kc.a * (1 - kc.e * kc.e));
    const auto inv = sys->invariants();
    ASSERT_EQ(inv.size(), 2u);
    EXPECT_EQ(inv[0].name, "energy");
    EXPECT_EQ(inv[1].name, "angular_momentum");
    for (double t : {0.0, 0.1, 0.77, 2.0, 3.3, 5.9, 41.0}) {
      const Vec y = exact_at(*sys, t);
      const double h = 0.5 * (y[2] * y[2] + y[3] * y[3]) - kc.gm / std::hypot(y[0], y[1]);
      const double l = y[0] * y[3] - y[1] * y[2];
      EXPECT_NEAR(h, energy, 1e-12 * std::abs(energy)) << "t = " << t;
      EXPECT_NEAR(l, ang, 1e-12 * ang) << "t = " << t;
      EXPECT_NEAR(inv[0].value(t, y), energy, 1e-12 * std::abs(energy)) << "t = " << t;
      EXPECT_NEAR(inv[1].value(t, y), ang, 1e-12 * ang) << "t = " << t;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Analytic Jacobians.

// Forward differences with step √ε·max(1, |y_j|) are accurate to about 1e-7 relative here; the
// absolute floor (relative to the largest entry) covers entries that are zero analytically.
TEST(ModelsJacobian, MatchesFiniteDifferences) {
  int checked = 0;
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    if (!sys->has_jacobian()) continue;
    ++checked;
    for (const Vec& y : sample_states(*sys)) {
      for (double t : {sys->initial_time(), sys->initial_time() + 0.9}) {
        SCOPED_TRACE("t = " + std::to_string(t) + ", y = " + std::to_string(y[0]) + " ...");
        const Mat j = analytic_jacobian(*sys, t, y);
        const Mat fd = finite_difference_jacobian(*sys, t, y);
        ASSERT_EQ(j.rows(), sys->dimension());
        ASSERT_EQ(j.cols(), sys->dimension());
        const double floor = 1e-6 * std::max(1.0, j.cwiseAbs().maxCoeff());
        for (Index r = 0; r < j.rows(); ++r) {
          for (Index col = 0; col < j.cols(); ++col) {
            EXPECT_LE(std::abs(j(r, col) - fd(r, col)), 1e-6 * std::abs(j(r, col)) + floor)
                << "entry (" << r << ", " << col << "): analytic " << j(r, col) << ", fd "
                << fd(r, col);
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, static_cast<int>(all_cases().size()));  // every model has a Jacobian
}

// J = [[0, I], [K, D]] with K and D the model's own blocks, and the sparsity pattern is the same
// at every state (implicit solvers analyse it once).
TEST(ModelsJacobian, MechanicalBlockStructureAndFixedPattern) {
  int checked = 0;
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    const MechanicalSystem* mech = sys->as_mechanical();
    if (mech == nullptr || !mech->has_force_jacobians()) continue;
    ++checked;
    const Index n = mech->dofs();
    SparseMat first;
    sys->jacobian(0.0, sys->initial_state(), first);
    for (const Vec& y : sample_states(*sys)) {
      SparseMat js;
      sys->jacobian(0.5, y, js);
      const Mat j(js);
      SparseMat ks, ds;
      mech->stiffness_block(0.5, y.head(n), y.tail(n), ks);
      mech->damping_block(0.5, y.head(n), y.tail(n), ds);
      EXPECT_TRUE(j.topLeftCorner(n, n).isZero(0.0));
      EXPECT_TRUE(j.topRightCorner(n, n).isIdentity(0.0));
      EXPECT_TRUE(j.bottomLeftCorner(n, n) == Mat(ks)) << j << "\nK =\n" << Mat(ks);
      EXPECT_TRUE(j.bottomRightCorner(n, n) == Mat(ds)) << j << "\nD =\n" << Mat(ds);
      // D = 0 exactly when the acceleration does not depend on v.
      EXPECT_EQ(Mat(ds).isZero(0.0), !mech->velocity_dependent());

      js.makeCompressed();
      first.makeCompressed();
      ASSERT_EQ(js.nonZeros(), first.nonZeros());
      for (Index k = 0; k <= js.outerSize(); ++k)
        EXPECT_EQ(js.outerIndexPtr()[k], first.outerIndexPtr()[k]);
      for (Index k = 0; k < js.nonZeros(); ++k)
        EXPECT_EQ(js.innerIndexPtr()[k], first.innerIndexPtr()[k]);
    }
  }
  EXPECT_GE(checked, 3);  // harmonic_oscillator, kepler, pendulum
}

// The sparsity pattern (used by column-grouped finite differences) holds every entry that is
// nonzero at any sampled state, not only those nonzero at the initial state, and asking for it
// is not an evaluation.
TEST(ModelsJacobian, PatternCoversEveryNonzero) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    ASSERT_TRUE(sys->has_jacobian_pattern());
    sys->reset_counters();
    const SparseMat pattern = sys->jacobian_pattern();
    EXPECT_EQ(sys->counters().f_evals, 0);
    EXPECT_EQ(sys->counters().jac_evals, 0);
    ASSERT_EQ(pattern.rows(), sys->dimension());
    ASSERT_EQ(pattern.cols(), sys->dimension());
    for (const Vec& y : sample_states(*sys)) {
      const Mat fd = finite_difference_jacobian(*sys, 0.7, y);
      const double floor = 1e-6 * std::max(1.0, fd.cwiseAbs().maxCoeff());
      for (Index r = 0; r < fd.rows(); ++r) {
        for (Index col = 0; col < fd.cols(); ++col) {
          if (std::abs(fd(r, col)) <= floor) continue;
          EXPECT_NE(pattern.coeff(r, col), 0.0)
              << "entry (" << r << ", " << col << ") = " << fd(r, col) << " not in the pattern";
        }
      }
    }
  }
}

// A model that says it is autonomous (Rosenbrock methods then drop ∂f/∂t) has f independent of
// t; Prothero–Robinson, with its φ(t), must not say so.
TEST(ModelsRhs, AutonomyFlagMatchesTimeDependence) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    EXPECT_EQ(sys->autonomous(), c.model != "prothero_robinson");
    for (const Vec& y : sample_states(*sys)) {
      const Vec f0 = rhs_at(*sys, 0.0, y), f1 = rhs_at(*sys, 1.7, y);
      if (sys->autonomous()) {
        EXPECT_TRUE(f0 == f1) << f0.transpose() << " vs " << f1.transpose();
      } else {
        EXPECT_GT(max_abs_diff(f0, f1), 1e-3);
      }
    }
  }
}

// rhs() of a mechanical system is [v; a(t, x, v)].
TEST(ModelsMechanical, RhsIsVelocityAndAcceleration) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    const MechanicalSystem* mech = sys->as_mechanical();
    if (mech == nullptr) continue;
    const Index n = mech->dofs();
    for (const Vec& y : sample_states(*sys)) {
      const Vec f = rhs_at(*sys, 0.2, y);
      Vec acc(n);
      mech->acceleration(0.2, y.head(n), y.tail(n), acc);
      EXPECT_TRUE(f.head(n) == y.tail(n)) << f.transpose();
      EXPECT_TRUE(f.tail(n) == acc) << f.transpose() << " vs " << acc.transpose();
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Invariants.

// Undamped oscillator and Kepler: each invariant is constant along the exact solution.
TEST(ModelsInvariants, ConstantAlongExactSolutionOfUndampedModels) {
  const std::vector<Case> cases = {
      {"harmonic_oscillator", {}},
      {"harmonic_oscillator", {"m=2", "k=3", "x0=0.7", "v0=-1.3"}},
      {"kepler", {"e=0"}},
      {"kepler", {"e=0.7"}},
      {"kepler", {"e=0.7", "gm=2", "a=1.5"}},
      {"kepler", {"e=0.9"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    const auto invariants = sys->invariants();
    ASSERT_FALSE(invariants.empty());
    EXPECT_EQ(invariants[0].name, "energy");
    const Vec y0 = sys->initial_state();
    for (const Invariant& inv : invariants) {
      SCOPED_TRACE(inv.name);
      const double i0 = inv.value(0.0, y0);
      ASSERT_NE(i0, 0.0);
      for (int s = 1; s <= 200; ++s) {
        const double t = 0.1 * s;
        EXPECT_NEAR(inv.value(t, exact_at(*sys, t)), i0, 1e-12 * std::abs(i0)) << "t = " << t;
      }
    }
  }
}

// At any state, dI/dt = ∇I·f: zero for conserved quantities (also the pendulum, which has no
// exact solution), -γv² for the oscillator's energy. ∇I by central differences, done here.
TEST(ModelsInvariants, RateAlongVectorFieldMatchesTheory) {
  int checked = 0;
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    double gamma = 0.0;
    const bool oscillator = c.model == "harmonic_oscillator";
    if (oscillator) {
      const Params p = Params::from_assignments(c.params);
      if (p.contains("gamma")) gamma = p.real("gamma");
    }
    for (const Invariant& inv : sys->invariants()) {
      SCOPED_TRACE(inv.name);
      ++checked;
      for (const Vec& y : sample_states(*sys)) {
        const double t = 0.3;
        const Index dim = sys->dimension();
        Vec grad(dim);
        for (Index i = 0; i < dim; ++i) {
          const double d = 1e-6 * std::max(1.0, std::abs(y[i]));
          Vec yp = y, ym = y;
          yp[i] += d;
          ym[i] -= d;
          grad[i] = (inv.value(t, yp) - inv.value(t, ym)) / (yp[i] - ym[i]);
        }
        const Vec f = rhs_at(*sys, t, y);
        const double rate = grad.dot(f);
        // E = ½mv² + ½kx² and m v' = -kx - γv give dE/dt = v(-kx - γv) + kxv = -γv².
        const double expected = oscillator ? -gamma * y[1] * y[1] : 0.0;
        EXPECT_NEAR(rate, expected, 1e-7 * grad.norm() * f.norm())
            << "y = " << y.transpose() << ", grad = " << grad.transpose();
      }
    }
  }
  EXPECT_GE(checked, 4);  // oscillator energy, Kepler energy and momentum, pendulum energy
}

// Damped oscillator: the energy decreases strictly along the exact solution.
TEST(ModelsInvariants, DampedOscillatorEnergyDecreases) {
  for (const Assignments& params : std::vector<Assignments>{{"gamma=0.5"},
                                                            {"gamma=0.5", "x0=0.7", "v0=-1.3"},
                                                            {"gamma=2"},
                                                            {"m=2", "k=8", "gamma=8", "v0=0.9"},
                                                            {"gamma=5", "x0=0.7", "v0=-1.3"}}) {
    const Case c{"harmonic_oscillator", params};
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    const auto inv = sys->invariants();
    ASSERT_FALSE(inv.empty());
    double previous = inv[0].value(0.0, sys->initial_state());
    for (int s = 1; s <= 400; ++s) {
      const double t = 0.025 * s;
      const double e = inv[0].value(t, exact_at(*sys, t));
      EXPECT_LT(e, previous) << "t = " << t;
      EXPECT_GT(e, 0.0) << "t = " << t;
      previous = e;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Evaluation counting at the system boundary.

TEST(ModelsCounting, EveryBoundaryCallCounts) {
  for (const std::string& name : kProblemModels) {
    SCOPED_TRACE(name);
    auto sys = make({name, {}});
    const Vec y = sys->initial_state();
    const Index n = sys->dimension();
    Vec f(n);
    finite_difference_jacobian(*sys, 0.0, y);  // before the reset, which must clear both counters
    if (sys->has_jacobian()) {
      SparseMat j;
      sys->jacobian(0.0, y, j);
    }
    sys->reset_counters();
    EXPECT_EQ(sys->counters().f_evals, 0);
    EXPECT_EQ(sys->counters().jac_evals, 0);

    sys->rhs(0.1, y, f);
    EXPECT_EQ(sys->counters().f_evals, 1);
    EXPECT_EQ(sys->counters().jac_evals, 0);
    sys->rhs(0.2, y, f);
    EXPECT_EQ(sys->counters().f_evals, 2);

    if (const MechanicalSystem* mech = sys->as_mechanical()) {
      const Index d = mech->dofs();
      Vec a(d);
      mech->acceleration(0.1, y.head(d), y.tail(d), a);
      EXPECT_EQ(sys->counters().f_evals, 3);
      EXPECT_EQ(sys->counters().jac_evals, 0);
    }
    const long f_before = sys->counters().f_evals;

    if (sys->has_jacobian()) {
      SparseMat j;
      sys->jacobian(0.1, y, j);
      EXPECT_EQ(sys->counters().jac_evals, 1);
      sys->jacobian(0.2, y, j);
      EXPECT_EQ(sys->counters().jac_evals, 2);
      EXPECT_EQ(sys->counters().f_evals, f_before);
    }
    const long j_before = sys->counters().jac_evals;

    finite_difference_jacobian(*sys, 0.1, y);
    EXPECT_EQ(sys->counters().f_evals, f_before + 2 * n);  // central differences
    EXPECT_EQ(sys->counters().jac_evals, j_before);
  }
}

// ---------------------------------------------------------------------------------------------
// 6. Bad parameters.

// The BadInput message from creating `model` with `params` ("" and a failure if none is thrown).
std::string bad_input_message(const std::string& model, const Assignments& params) {
  try {
    make({model, params});
  } catch (const BadInput& e) {
    return e.what();
  }
  ADD_FAILURE() << "no BadInput for " << describe({model, params});
  return "";
}

TEST(ModelsParams, BadValuesNameTheKey) {
  struct BadCase {
    std::string model;
    Assignments params;
    std::string key;
  };
  const std::vector<BadCase> cases = {
      {"kepler", {"e=1.2"}, "e"},
      {"kepler", {"e=1"}, "e"},
      {"kepler", {"e=-0.1"}, "e"},
      {"kepler", {"gm=0"}, "gm"},
      {"kepler", {"a=-1"}, "a"},
      {"harmonic_oscillator", {"m=-1"}, "m"},
      {"harmonic_oscillator", {"k=0"}, "k"},
      {"harmonic_oscillator", {"gamma=-0.1"}, "gamma"},
      {"harmonic_oscillator", {"k=abc"}, "k"},
      {"pendulum", {"length=0"}, "length"},
      {"pendulum", {"length=-2"}, "length"},
      {"prothero_robinson", {"phi=tan"}, "phi"},
      {"prothero_robinson", {"lambda=1e400"}, "lambda"},
      {"dahlquist", {"lambda_re=nan"}, "lambda_re"},
  };
  for (const BadCase& bc : cases) {
    SCOPED_TRACE(describe({bc.model, bc.params}));
    const std::string msg = bad_input_message(bc.model, bc.params);
    EXPECT_NE(msg.find("'" + bc.key + "'"), std::string::npos) << msg;
  }
  // The offending value is shown for values that do not parse or are not a choice.
  EXPECT_NE(bad_input_message("harmonic_oscillator", {"k=abc"}).find("abc"), std::string::npos);
  EXPECT_NE(bad_input_message("prothero_robinson", {"phi=tan"}).find("tan"), std::string::npos);
}

TEST(ModelsParams, BoundaryValuesAreAccepted) {
  EXPECT_NO_THROW(make({"kepler", {"e=0"}}));
  EXPECT_NO_THROW(make({"kepler", {"e=0.999"}}));
  EXPECT_NO_THROW(make({"harmonic_oscillator", {"gamma=0"}}));
  EXPECT_NO_THROW(make({"pendulum", {"length=0.01"}}));
}

TEST(ModelsRegistry, UnknownModelListsKnownNames) {
  try {
    model_registry().create("no_such_model", Params{});
    FAIL() << "no BadInput for an unknown model";
  } catch (const BadInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no_such_model"), std::string::npos) << msg;
    ASSERT_GE(model_registry().names().size(), kProblemModels.size());
    for (const auto& name : model_registry().names()) {
      EXPECT_NE(msg.find(name), std::string::npos) << name << " missing from: " << msg;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 7. stiffness().

TEST(ModelsStiffness, ClosedFormValues) {
  // Dahlquist: |λ| = |-0.5 + 3i| = √9.25.
  auto dahl = make({"dahlquist", {"lambda_re=-0.5", "lambda_im=3"}});
  EXPECT_NEAR(*dahl->stiffness(0.0, dahl->initial_state()), std::sqrt(9.25), 1e-14);
  // Underdamped oscillator: √(k/m) = √(8/2) = 2, independent of γ below critical.
  for (const char* gamma : {"gamma=0", "gamma=1", "gamma=7.9"}) {
    auto ho = make({"harmonic_oscillator", {"m=2", "k=8", gamma}});
    EXPECT_NEAR(*ho->stiffness(0.0, ho->initial_state()), 2.0, 1e-14) << gamma;
  }
  // Overdamped m = k = 1, γ = 5: roots -β ± √(β² - 1) with β = 2.5; the larger is β + √5.25.
  auto over = make({"harmonic_oscillator", {"gamma=5"}});
  EXPECT_NEAR(*over->stiffness(0.0, over->initial_state()), 2.5 + std::sqrt(5.25), 1e-14);
  // Kepler at pericentre r = a(1 - e): √(2GM/r³).
  for (const KeplerCase& kc : kKeplerCases) {
    auto kep = make(kepler_case(kc));
    const double r = kc.a * (1 - kc.e);
    EXPECT_NEAR(*kep->stiffness(0.0, kep->initial_state()), std::sqrt(2 * kc.gm / (r * r * r)),
                1e-12 * std::sqrt(2 * kc.gm / (r * r * r)))
        << describe(kepler_case(kc));
  }
  // Prothero–Robinson: |λ|.
  auto pr = make({"prothero_robinson", {"lambda=-20"}});
  EXPECT_NEAR(*pr->stiffness(0.0, pr->initial_state()), 20.0, 1e-14);
}

// For every model in this set the estimate is exact: the spectral radius of ∂f/∂y, computed
// here with Eigen's eigenvalue solver from the analytic Jacobian (itself checked against finite
// differences above; finite differences would lose half the digits at the critically damped
// oscillator's double eigenvalue).
TEST(ModelsStiffness, EqualsSpectralRadiusOfJacobian) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(describe(c));
    auto sys = make(c);
    for (const Vec& y : sample_states(*sys)) {
      const auto s = sys->stiffness(0.4, y);
      ASSERT_TRUE(s.has_value());
      const double rho = spectral_radius(analytic_jacobian(*sys, 0.4, y));
      EXPECT_NEAR(*s, rho, 1e-6 * rho) << "y = " << y.transpose();
    }
  }
}

}  // namespace
}  // namespace stiffbench
