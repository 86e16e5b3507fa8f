// Structure tests that order tests miss: evaluation counts, symplecticity, behaviour on damped
// systems, long-time energy behaviour, the Verlet family's documented equivalences.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <numbers>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// f evaluations = steps × stages for every explicit tableau (no FSAL tableau is registered).
TEST(EvaluationCount, ExplicitIsStepsTimesStages) {
  auto sys = model("kepler");
  for (const auto& t : explicit_tableaux()) {
    auto integ = make(t.name);
    FixedStepOptions opt;
    opt.t_end = 1.0;
    opt.h = 0.01;
    const RunResult r = run_fixed_step(*sys, *integ, opt);
    EXPECT_EQ(r.stats.f_evals, 100L * t.stages()) << t.name;
  }
}

// Symplectic methods: one acceleration per step; the Verlet family pays one extra evaluation
// in its first step (start-up or first-same-as-last).
TEST(EvaluationCount, SymplecticMethods) {
  auto sys = model("kepler");
  const std::map<std::string, long> expected = {{"symplectic_euler", 100},
                                                {"symplectic_euler_x", 100},
                                                {"velocity_verlet", 101},
                                                {"verlet", 101},
                                                {"leapfrog", 101}};
  for (const auto& [name, count] : expected) {
    auto integ = make(name);
    FixedStepOptions opt;
    opt.t_end = 1.0;
    opt.h = 0.01;
    EXPECT_EQ(run_fixed_step(*sys, *integ, opt).stats.f_evals, count) << name;
    EXPECT_EQ(integ->info().stages, 1) << name;
  }
}

// The one-step map of a method on the linear oscillator x'' = -k x - γ x' is a 2×2 matrix M;
// its columns are the images of (1, 0) and (0, 1).
Mat amplification_matrix(const std::string& method, double k, double gamma, double h) {
  auto sys =
      model("harmonic_oscillator", {"k=" + std::to_string(k), "gamma=" + std::to_string(gamma)});
  Mat m(2, 2);
  for (int j = 0; j < 2; ++j) {
    auto integ = make(method);
    Vec y = Vec::Zero(2);
    y[j] = 1.0;
    SolveStats stats;
    integ->reset(*sys, 0.0, y);
    integ->step(*sys, 0.0, y, h, stats);
    m.col(j) = y;
  }
  return m;
}

// Symplectic Euler (v first): v⁺ = (1 - hγ)v - hk x, x⁺ = x + h v⁺, so
// M = [[1 - h²k, h(1 - hγ)], [-hk, 1 - hγ]] and det M = 1 - hγ: area-preserving when γ = 0,
// contracting when damped. Explicit Euler has det M = 1 - hγ + h²k instead, which grows for
// small γ: a "symplectic" Euler that is really explicit Euler fails here.
TEST(SymplecticStructure, DampedOscillatorOneStepMatrix) {
  const double k = 1.0, gamma = 0.05, h = 0.1;
  const Mat m = amplification_matrix("symplectic_euler", k, gamma, h);
  EXPECT_NEAR(m(0, 0), 1 - h * h * k, 1e-15);
  EXPECT_NEAR(m(0, 1), h * (1 - h * gamma), 1e-15);
  EXPECT_NEAR(m(1, 0), -h * k, 1e-15);
  EXPECT_NEAR(m(1, 1), 1 - h * gamma, 1e-15);
  EXPECT_NEAR(m.determinant(), 1 - h * gamma, 1e-15);
  const Mat e = amplification_matrix("euler", k, gamma, h);
  EXPECT_NEAR(e.determinant(), 1 - h * gamma + h * h * k, 1e-15);
  // Position-first variant: M = [[1, h], [-hk, 1 - hγ - h²k]], det M = 1 - hγ too.
  EXPECT_NEAR(amplification_matrix("symplectic_euler_x", k, gamma, h).determinant(), 1 - h * gamma,
              1e-15);
}

// Every symplectic method preserves area on the undamped oscillator (det M = 1), and
// velocity Verlet has trace 2 - h²k (docs/reference-values.md: stable iff hω < 2).
TEST(SymplecticStructure, AreaPreservingOnUndampedOscillator) {
  for (const auto& name : {"symplectic_euler", "symplectic_euler_x", "velocity_verlet"}) {
    EXPECT_NEAR(amplification_matrix(name, 4.0, 0.0, 0.3).determinant(), 1.0, 1e-14) << name;
  }
  EXPECT_NEAR(amplification_matrix("velocity_verlet", 4.0, 0.0, 0.3).trace(), 2 - 0.09 * 4.0,
              1e-14);
  EXPECT_GT(amplification_matrix("rk4", 4.0, 0.0, 0.3).determinant(), 0.0);
  EXPECT_LT(amplification_matrix("rk4", 4.0, 0.0, 0.3).determinant(), 1.0);  // RK4 damps
}

// Over 1000 steps of the damped oscillator the amplitude of symplectic Euler decays like
// |eigenvalue|^N = (1 - hγ)^{N/2}, while explicit Euler grows like (1 - hγ + h²)^{N/2}.
TEST(SymplecticStructure, DampedOscillatorLongRunDecaysAtTheRightRate) {
  const double h = 0.1, gamma = 0.05;
  auto sys = model("harmonic_oscillator", {"gamma=0.05"});
  FixedStepOptions opt;
  opt.t_end = 100.0;
  opt.h = h;
  auto se = make("symplectic_euler");
  auto eu = make("euler");
  const double n_steps = 1000;
  const double se_norm = run_fixed_step(*sys, *se, opt).y.norm();
  const double eu_norm = run_fixed_step(*sys, *eu, opt).y.norm();
  const double se_rate = std::pow(1 - h * gamma, n_steps / 2);          // ≈ 0.082
  const double eu_rate = std::pow(1 - h * gamma + h * h, n_steps / 2);  // ≈ 12.1
  // The eigenvectors are not orthogonal, so the norm matches the rate within a bounded factor.
  EXPECT_GT(se_norm, se_rate / 2);
  EXPECT_LT(se_norm, se_rate * 2);
  EXPECT_GT(eu_norm, eu_rate / 2);
  EXPECT_LT(eu_norm, eu_rate * 2);
}

struct EnergyTrace {
  double max_dev_first = 0;  // max |E - E0|/|E0| over the first 100 orbits
  double max_dev_last = 0;   // ... over the last 100 orbits
  Status status = Status::ok;
};

EnergyTrace kepler_energy(const std::string& method, double h, int orbits) {
  auto sys = model("kepler", {"e=0.5"});
  const auto energy = sys->invariants().front();
  const double e0 = energy.value(0, sys->initial_state());
  const double period = 2 * std::numbers::pi;
  auto integ = make(method);
  FixedStepOptions opt;
  opt.t_end = orbits * period;
  opt.h = h;
  opt.outputs = orbits * 20L;
  EnergyTrace tr;
  const RunResult r = run_fixed_step(*sys, *integ, opt, [&](double t, CVecRef y) {
    const double dev = std::abs((energy.value(t, y) - e0) / e0);
    if (t <= 100 * period) tr.max_dev_first = std::max(tr.max_dev_first, dev);
    if (t >= (orbits - 100) * period) tr.max_dev_last = std::max(tr.max_dev_last, dev);
  });
  tr.status = r.stats.status;
  return tr;
}

// Symplectic methods keep a modified energy exactly, so the energy error oscillates without a
// secular trend (Hairer–Lubich–Wanner, GNI §IX.8): over 1000 orbits of the e = 0.5 orbit the
// deviation in the last 100 orbits is no larger than in the first 100 (up to a small factor).
// Explicit Euler has no such invariant and its energy error grows with time.
TEST(SymplecticStructure, KeplerEnergyBoundedOver1000Orbits) {
  const double h = 0.005;
  for (const auto& name :
       {"symplectic_euler", "symplectic_euler_x", "velocity_verlet", "verlet", "leapfrog"}) {
    const EnergyTrace tr = kepler_energy(name, h, 1000);
    ASSERT_EQ(tr.status, Status::ok) << name;
    EXPECT_LT(tr.max_dev_last, 1.5 * tr.max_dev_first) << name;
    EXPECT_LT(tr.max_dev_last, 0.05) << name;
  }
  // Explicit Euler gains energy every orbit until the body escapes (E → 0, deviation → 1).
  const EnergyTrace eu = kepler_energy("euler", h, 1000);
  EXPECT_GT(eu.max_dev_last, 0.5);
  EXPECT_GT(eu.max_dev_last, eu.max_dev_first);
}

// Documented in verlet.hpp: two-step Verlet, leapfrog and velocity Verlet produce the same
// trajectory in exact arithmetic; in floating point they agree to round-off.
TEST(VerletFamily, SameTrajectoryAsVelocityVerlet) {
  auto sys = model("pendulum", {"theta0=2.5"});
  FixedStepOptions opt;
  opt.t_end = 20.0;
  opt.h = 0.02;
  auto vv = make("velocity_verlet");
  const Vec ref = run_fixed_step(*sys, *vv, opt).y;
  for (const auto& name : {"verlet", "leapfrog"}) {
    auto integ = make(name);
    EXPECT_LT(max_abs_diff(run_fixed_step(*sys, *integ, opt).y, ref), 1e-10) << name;
  }
}

// Leapfrog and the Verlet family refuse damped (velocity-dependent) systems; every symplectic
// method refuses a first-order model. The message names both sides.
TEST(SymplecticStructure, RefusesWhatItCannotIntegrate) {
  auto damped = model("harmonic_oscillator", {"gamma=0.1"});
  auto dahl = model("dahlquist");
  FixedStepOptions opt;
  for (const auto& name : {"velocity_verlet", "verlet", "leapfrog"}) {
    auto integ = make(name);
    try {
      run_fixed_step(*damped, *integ, opt);
      ADD_FAILURE() << name << " accepted a damped system";
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos);
      EXPECT_NE(std::string(e.what()).find("velocity"), std::string::npos);
    }
  }
  for (const auto& name :
       {"symplectic_euler", "symplectic_euler_x", "velocity_verlet", "verlet", "leapfrog"}) {
    auto integ = make(name);
    try {
      run_fixed_step(*dahl, *integ, opt);
      ADD_FAILURE() << name << " accepted a first-order system";
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find("dahlquist"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find("mechanical"), std::string::npos);
    }
  }
  // Symplectic Euler is defined for damped systems (v⁺ = v + h a(t, x, v)).
  auto se = make("symplectic_euler");
  EXPECT_EQ(run_fixed_step(*damped, *se, opt).stats.status, Status::ok);
}

}  // namespace
}  // namespace stiffbench
