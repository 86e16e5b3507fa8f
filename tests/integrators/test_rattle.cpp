// RATTLE (integrators/symplectic/rattle.hpp) on the constrained pendulum chain, checked against
// computations that share nothing with it: the chain's equations of motion in angle coordinates
// (no constraints at all) integrated by dopri5 at tight tolerance, and the single pendulum's
// exact solution through Jacobi elliptic functions (Boost.Math). Also: both constraints at every
// step, bounded energy error, symmetry, one acceleration per step, the network's constraint
// Jacobian against finite differences, the driver leaving RATTLE's state alone, and refusal of
// systems without constraints.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/special_functions/jacobi_elliptic.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/constraints.hpp"
#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "models/mass_spring/network.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// pendulum_chain's defaults (models/mass_spring/builders.hpp).
constexpr double kLength = 0.2, kGravity = 9.81, kAngle = 0.5;

// The n-link chain of equal bobs in the angles θ_i of the links from the downward vertical,
// bob k at L Σ_{i<=k} (sin θ_i, -cos θ_i). With c_ij = n - max(i, j) (0-based: the number of bobs
// at or below both links) the Lagrangian T = ½mL² Σ c_ij cos(θ_i - θ_j) θ_i'θ_j',
// V = -mgL Σ (n - i) cos θ_i gives
//   Σ_j c_ij cos(θ_i - θ_j) θ_j'' = -Σ_j c_ij sin(θ_i - θ_j) θ_j'² - (g/L)(n - i) sin θ_i,
// an ODE with no constraint: an independent route to the constrained chain's motion.
class AngleChain final : public OdeSystem {
 public:
  explicit AngleChain(int n) : n_(n) {}
  std::string name() const override { return "angle_chain"; }
  Index dimension() const override { return 2 * n_; }
  Vec initial_state() const override {
    Vec y = Vec::Zero(2 * n_);
    y.head(n_).setConstant(kAngle);
    return y;
  }

  // The Cartesian state [x; v] of the network (pinned point 0 first, 2D, interleaved).
  Vec cartesian(CVecRef y) const {
    const Index np = n_ + 1;
    Vec out = Vec::Zero(4 * np);
    double px = 0, py = 0, vx = 0, vy = 0;
    for (int k = 0; k < n_; ++k) {
      const double th = y[k], om = y[n_ + k];
      px += kLength * std::sin(th);
      py -= kLength * std::cos(th);
      vx += kLength * std::cos(th) * om;
      vy += kLength * std::sin(th) * om;
      out[2 * (k + 1)] = px;
      out[2 * (k + 1) + 1] = py;
      out[2 * np + 2 * (k + 1)] = vx;
      out[2 * np + 2 * (k + 1) + 1] = vy;
    }
    return out;
  }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override {
    Mat a(n_, n_);
    Vec b(n_);
    for (int i = 0; i < n_; ++i) {
      b[i] = -kGravity / kLength * (n_ - i) * std::sin(y[i]);
      for (int j = 0; j < n_; ++j) {
        const double c = n_ - std::max(i, j);
        a(i, j) = c * std::cos(y[i] - y[j]);
        b[i] -= c * std::sin(y[i] - y[j]) * y[n_ + j] * y[n_ + j];
      }
    }
    dydt.head(n_) = y.tail(n_);
    dydt.tail(n_) = a.ldlt().solve(b);  // the kinetic-energy matrix is SPD
  }

 private:
  int n_;
};

// The angle chain's Cartesian state at t by dopri5 at rtol = 1e-13, atol = 1e-15. Measured at
// t = 1 (n = 5): loosening to rtol = 1e-12 changes it by 6.3e-14, to 1e-11 by 6.4e-13, so it is
// accurate far below RATTLE's smallest error used here (9.3e-6).
Vec reference_chain(int n, double t, double rtol = 1e-13) {
  AngleChain sys(n);
  auto integ = integrator_registry().create("dopri5", Params{{"rtol", rtol}, {"atol", 1e-15}});
  AdaptiveOptions opt;
  opt.t_end = t;
  const RunResult r = run_adaptive(sys, *integ, opt);
  EXPECT_EQ(r.stats.status, Status::ok);
  return sys.cartesian(r.y);
}

RunResult run(const OdeSystem& sys, const std::string& method, double h, double t_end,
              const Observer& observer = {}, long outputs = 0) {
  auto integ = make(method);
  FixedStepOptions opt;
  opt.h = h;
  opt.t_end = t_end;
  opt.outputs = outputs;
  return run_fixed_step(sys, *integ, opt, observer);
}

std::unique_ptr<OdeSystem> chain(int n) {
  return model("pendulum_chain", {"n=" + std::to_string(n), "constrained=true"});
}

const HolonomicConstraints& constraints_of(const OdeSystem& sys) {
  const HolonomicConstraints* c = sys.as_mechanical()->holonomic_constraints();
  if (!c) throw std::logic_error(sys.name() + " offers no constraints");
  return *c;
}

// The angle-chain reference agrees with the network at t = 0 (same initial state) and its
// dopri5 solution does not move when the tolerance is loosened by 100 (its accuracy).
TEST(Rattle, AngleChainReferenceIsConsistent) {
  auto sys = chain(5);
  EXPECT_LE(
      max_abs_diff(AngleChain(5).cartesian(AngleChain(5).initial_state()), sys->initial_state()),
      1e-15);
  EXPECT_LE(max_abs_diff(reference_chain(5, 1.0), reference_chain(5, 1.0, 1e-11)), 1e-10);
}

// Observed order 2 (within 0.2) on the 5-link constrained chain at t = 1 against the angle-chain
// reference, h = 4e-3 / 2^k. Errors are max-norm over positions and velocities; measured
// 5.95e-4, 1.49e-4, 3.72e-5, 9.30e-6 (orders 2.00). Velocity Verlet with the projection:
// 5.98e-3 and 3.00e-3 at h = 1e-3 and 5e-4.
TEST(Rattle, SecondOrderOnConstrainedChain) {
  auto sys = chain(5);
  const Vec ref = reference_chain(5, 1.0);
  std::vector<double> err;
  for (const double h : {4e-3, 2e-3, 1e-3, 5e-4}) {
    const RunResult r = run(*sys, "rattle", h, 1.0);
    ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
    err.push_back(max_abs_diff(r.y, ref));
  }
  for (std::size_t k = 1; k < err.size(); ++k)
    EXPECT_NEAR(std::log2(err[k - 1] / err[k]), 2.0, 0.2) << err[k - 1] << " " << err[k];
  // velocity_verlet with the model's end-of-step projection is first order against the same
  // reference (network.hpp): what RATTLE's constraint impulse in the first kick recovers.
  const double e1 = max_abs_diff(run(*sys, "velocity_verlet", 1e-3, 1.0).y, ref);
  const double e2 = max_abs_diff(run(*sys, "velocity_verlet", 5e-4, 1.0).y, ref);
  EXPECT_NEAR(std::log2(e1 / e2), 1.0, 0.2) << e1 << " " << e2;
  EXPECT_GT(e2, 10 * err.back());
}

// A single constrained pendulum (n = 1) against its exact solution: with k = sin(θ0/2) and
// ω = √(g/L), sin(θ/2) = k cd(ωt, k) (starting at rest at θ0), so
//   θ' = -2kω(1 - k²) sn/dn² / cos(θ/2).
TEST(Rattle, SinglePendulumMatchesEllipticSolution) {
  auto sys = chain(1);
  const double t = 2.0, k = std::sin(kAngle / 2), w = std::sqrt(kGravity / kLength);
  double cn = 0, dn = 0;
  const double sn = boost::math::jacobi_elliptic(k, w * t, &cn, &dn);
  const double theta = 2 * std::asin(k * cn / dn);
  const double omega = -2 * k * w * (1 - k * k) * sn / (dn * dn) / std::cos(theta / 2);
  Vec exact = Vec::Zero(8);
  exact << 0, 0, kLength * std::sin(theta), -kLength * std::cos(theta), 0, 0,
      kLength * std::cos(theta) * omega, kLength * std::sin(theta) * omega;
  std::vector<double> err;
  for (const double h : {2e-3, 1e-3, 5e-4}) {
    const RunResult r = run(*sys, "rattle", h, t);
    ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
    err.push_back(max_abs_diff(r.y, exact));
  }
  EXPECT_NEAR(std::log2(err[0] / err[1]), 2.0, 0.2) << err[0] << " " << err[1];
  EXPECT_NEAR(std::log2(err[1] / err[2]), 2.0, 0.2) << err[1] << " " << err[2];
  EXPECT_LT(err[2], 1e-5);  // measured 4.2e-5, 1.04e-5, 2.6e-6: converging to the exact motion
}

// |g(x)| <= 1e-12 and |G(x) v| <= 1e-12 after every step (the solver stops at 1e-14 max(1, |x|)
// and 1e-14 max(1, |v|); |x| <= 1 and |v| ~ 2 here), over 2000 steps of the 5-link chain.
// Measured: max|g| = 8.0e-15, max|G v| = 3.3e-16.
TEST(Rattle, ConstraintsHoldAtEveryStep) {
  auto sys = chain(5);
  const HolonomicConstraints& c = constraints_of(*sys);
  const Index n = sys->as_mechanical()->dofs();
  ASSERT_EQ(c.constraint_count(), 5);
  Vec g(5);
  SparseMat jac;
  double worst_g = 0, worst_gv = 0;
  long calls = 0;
  const RunResult r = run(
      *sys, "rattle", 1e-3, 2.0,
      [&](double, CVecRef y) {
        c.constraint_values(y.head(n), g);
        c.constraint_jacobian(y.head(n), jac);
        worst_g = std::max(worst_g, g.cwiseAbs().maxCoeff());
        worst_gv = std::max(worst_gv, (jac * y.tail(n)).cwiseAbs().maxCoeff());
        ++calls;
      },
      2000);
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_EQ(calls, 2001);
  EXPECT_LE(worst_g, 1e-12);
  EXPECT_LE(worst_gv, 1e-12);
  EXPECT_GT(max_abs_diff(r.y, sys->initial_state()), 0.1);  // it swung
}

// Symplectic and symmetric: the energy error oscillates at O(h²) without drift. Over 20,000 steps
// (t = 40, h = 2e-3) the largest |E - E0| in the last quarter is no larger than in the first
// (a drift would grow it). Measured per quarter: 1.37e-5, 1.52e-5, 1.33e-5, 1.39e-5 (E0 = -5.17).
// Velocity Verlet with the end-of-step projection dissipates energy steadily (network.hpp):
// 0.11, 0.20, 0.27, 0.33.
TEST(Rattle, EnergyErrorBoundedWithoutDrift) {
  auto sys = chain(5);
  const auto energy = sys->invariants().front().value;
  const double e0 = energy(0, sys->initial_state());
  auto quarters = [&](const std::string& method) {
    std::vector<double> worst(4, 0.0);
    const double t_end = 40.0;
    const RunResult r = run(
        *sys, method, 2e-3, t_end,
        [&](double t, CVecRef y) {
          const auto q = std::min<std::size_t>(3, static_cast<std::size_t>(4 * t / t_end));
          worst[q] = std::max(worst[q], std::abs(energy(t, y) - e0));
        },
        20000);
    EXPECT_EQ(r.stats.status, Status::ok);
    return worst;
  };
  const auto rattle = quarters("rattle");
  EXPECT_LE(rattle[3], 1.2 * rattle[0]);
  EXPECT_LE(*std::max_element(rattle.begin(), rattle.end()), 3e-5);
  const auto verlet = quarters("velocity_verlet");
  EXPECT_GT(verlet[3], 2 * verlet[0]);
  EXPECT_GT(verlet[3], 1000 * rattle[3]);
}

// Symmetric method: a step of +h followed by a step of -h returns to the start (up to the
// constraint solves' tolerance), from a generic state on the manifold. Measured: 2.8e-14.
TEST(Rattle, StepBackwardUndoesStep) {
  auto sys = chain(5);
  Vec y = run(*sys, "rattle", 1e-3, 0.3).y;
  const Vec start = y;
  auto integ = make("rattle");
  SolveStats stats;
  integ->reset(*sys, 0.3, y);
  ASSERT_EQ(integ->step(*sys, 0.3, y, 0.01, stats), Status::ok);
  EXPECT_GT(max_abs_diff(y, start), 1e-3);
  ASSERT_EQ(integ->step(*sys, 0.31, y, -0.01, stats), Status::ok);
  EXPECT_LE(max_abs_diff(y, start), 1e-12);
}

// One acceleration evaluation per step after the first (a(x_{n+1}) is reused), and the driver
// does not project after RATTLE's steps: its result equals stepping by hand bit for bit.
TEST(Rattle, OneEvaluationPerStepAndNoProjection) {
  auto sys = chain(3);
  const RunResult r = run(*sys, "rattle", 1e-3, 0.5);
  EXPECT_EQ(r.n_steps, 500);
  EXPECT_EQ(r.stats.f_evals, 501);
  // At least one Newton update per step (measured 979 over 500 steps: two each, quadratic).
  EXPECT_GE(r.stats.newton_iters, 500);
  EXPECT_LE(r.stats.newton_iters, 1500);
  Vec y = sys->initial_state();
  auto integ = make("rattle");
  SolveStats stats;
  integ->reset(*sys, 0.0, y);
  for (long k = 0; k < 500; ++k) ASSERT_EQ(integ->step(*sys, k * 1e-3, y, 1e-3, stats), Status::ok);
  EXPECT_TRUE(y == r.y);
}

// The network's G = ∂g/∂x against central differences of g (step 1e-6: truncation ~1e-12,
// rounding ~1e-10), at a generic state, with a pinned end included in the pattern.
TEST(Rattle, NetworkConstraintJacobianMatchesFiniteDifferences) {
  auto sys = chain(4);
  const HolonomicConstraints& c = constraints_of(*sys);
  const Index n = sys->as_mechanical()->dofs();
  Vec x = run(*sys, "rattle", 1e-3, 0.4).y.head(n);
  x += 0.01 * Vec::LinSpaced(n, -1.0, 1.0);  // off the manifold too
  SparseMat jac;
  c.constraint_jacobian(x, jac);
  ASSERT_EQ(jac.rows(), 4);
  ASSERT_EQ(jac.cols(), n);
  EXPECT_EQ(jac.nonZeros(), 4 * 4);  // two 2D end points per link
  Vec gp(4), gm(4);
  const double d = 1e-6;
  for (Index j = 0; j < n; ++j) {
    Vec xp = x, xm = x;
    xp[j] += d;
    xm[j] -= d;
    c.constraint_values(xp, gp);
    c.constraint_values(xm, gm);
    const Vec fd = (gp - gm) / (2 * d);
    for (Index i = 0; i < 4; ++i) EXPECT_NEAR(jac.coeff(i, j), fd[i], 1e-8) << i << " " << j;
  }
  // Values written in place keep the pattern (no reallocation).
  const double* values = jac.valuePtr();
  c.constraint_jacobian(x * 1.01, jac);
  EXPECT_EQ(jac.valuePtr(), values);
}

// A step that cannot satisfy the constraint is reported, never returned silently wrong: a single
// Newton iteration (newton_max_iter=1) leaves max|g| above the 1e-14 tolerance at h = 0.02 (the
// quadratic convergence needs two or three, see OneEvaluationPerStepAndNoProjection), and a
// duplicated constraint makes G M⁻¹ Gᵀ singular. Bad parameters are BadInput.
TEST(Rattle, ReportsFailedConstraintSolves) {
  auto sys = chain(5);
  auto integ = make("rattle", {"newton_max_iter=1"});
  FixedStepOptions opt;
  opt.h = 0.02;
  opt.t_end = 0.2;
  const RunResult r = run_fixed_step(*sys, *integ, opt);
  EXPECT_EQ(r.stats.status, Status::newton_failed);
  EXPECT_NE(r.stats.message.find("did not converge in 1 Newton"), std::string::npos)
      << r.stats.message;
  EXPECT_EQ(r.stats.newton_conv_failures, 1);

  std::vector<MassPoint> pts(3);
  pts[0].pinned = true;
  pts[1].x = {0.2, 0.0, 0.0};
  pts[2].x = {0.4, 0.0, 0.0};
  NetworkOptions net;
  net.gravity = {0.0, -9.81, 0.0};
  const MassSpringNetwork dup("duplicated", 2, pts, {}, net,
                              {{0, 1, 0.2}, {1, 2, 0.2}, {2, 1, 0.2}});
  const RunResult d = run(dup, "rattle", 1e-3, 0.01);
  EXPECT_NE(d.stats.status, Status::ok);
  EXPECT_NE(d.stats.message.find("dependent constraints"), std::string::npos) << d.stats.message;

  EXPECT_THROW(make("rattle", {"constraint_tol=0"}), BadInput);
  EXPECT_THROW(make("rattle", {"newton_max_iter=0"}), BadInput);
}

// RATTLE needs constraints offered through holonomic_constraints() and velocity-independent
// forces: refused with BadInput otherwise, before any step.
TEST(Rattle, RefusesSystemsWithoutConstraints) {
  // Mechanical and undamped but unconstrained (the spring pendulum chain, Kepler), and a
  // first-order system: each refused, the first two for want of constraints.
  for (const auto& [name, params] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"pendulum_chain", {}}, {"kepler", {}}, {"van_der_pol", {}}}) {
    auto sys = model(name, params);
    try {
      run(*sys, "rattle", 1e-3, 0.1);
      ADD_FAILURE() << name << " accepted";
    } catch (const BadInput& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("integrator 'rattle'"), std::string::npos) << msg;
      if (sys->as_mechanical()) {
        EXPECT_NE(msg.find("needs holonomic constraints"), std::string::npos) << msg;
      }
    }
  }
  // Constrained but damped: the velocity Verlet kick needs a(x) alone.
  std::vector<MassPoint> pts(3);
  pts[0].pinned = true;
  pts[1].x = {0.0, -0.2, 0.0};
  pts[2].x = {0.0, -0.4, 0.0};
  NetworkOptions opt;
  opt.point_damping = 0.1;
  const MassSpringNetwork damped("damped", 2, pts, {}, opt, {{0, 1, 0.2}, {1, 2, 0.2}});
  EXPECT_THROW(run(damped, "rattle", 1e-3, 0.1), BadInput);
}

}  // namespace
}  // namespace stiffbench
