// The step map of IMEX pairs and operator splittings on a mechanical split (x' = v in f_I, the
// acceleration in f_E): Integrator::partitioned_stability() against the map the integrators
// themselves take, measured by running one step from the unit states on a one-dof oscillator,
// and the exact oscillator limits of the polynomial form against limits derived by hand.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>

#include "core/theory/linear_stability.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;

// x'' = a x + b x' with the whole acceleration explicit (a_E = a x + b v, a_I = 0), so
// f_I = [v; 0]: the test problem of partitioned_stability().
class ExplicitOscillator final : public MechanicalSystem {
 public:
  ExplicitOscillator(double a, double b) : a_(a), b_(b) {}
  std::string name() const override { return "explicit_oscillator_test"; }
  Index dofs() const override { return 1; }
  Vec initial_state() const override { return Vec::Unit(2, 0); }
  bool velocity_dependent() const override { return b_ != 0.0; }
  bool implicit_part_velocity_dependent() const override { return false; }
  bool has_force_jacobians() const override { return true; }
  bool symmetric_force_jacobians() const override { return true; }
  bool has_imex_split() const override { return true; }
  void stiffness_block(double, CVecRef, CVecRef, SparseMat& k) const override { one(k, a_); }
  void damping_block(double, CVecRef, CVecRef, SparseMat& d) const override { one(d, b_); }
  void implicit_force_jacobians(double, CVecRef, CVecRef, SparseMat& k,
                                SparseMat& d) const override {
    one(k, 0);
    one(d, 0);
  }

 protected:
  void eval_acceleration(double, CVecRef x, CVecRef v, VecRef acc) const override {
    acc[0] = a_ * x[0] + b_ * v[0];
  }
  void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef acc) const override {
    eval_acceleration(t, x, v, acc);
  }
  void eval_acceleration_implicit_part(double, CVecRef, CVecRef, VecRef acc) const override {
    acc[0] = 0.0;
  }

 private:
  static void one(SparseMat& m, double v) {
    m.resize(1, 1);
    m.setZero();
    m.insert(0, 0) = v;
  }
  double a_, b_;
};

// The eigenvalue of largest modulus (Im >= 0) of the step map the integrator takes at step h,
// from one step from (x, v) = (1, 0) and one from (0, 1) (the map in (x, u = h v) has the same
// eigenvalues as the map in (x, v)).
std::complex<double> measured_multiplier(const std::string& name,
                                         const std::vector<std::string>& params, double a, double b,
                                         double h) {
  const ExplicitOscillator sys(a, b);
  auto integ = make(name, params);
  std::array<double, 4> m{};  // [[m0, m1], [m2, m3]]
  for (int c = 0; c < 2; ++c) {
    Vec y(2);
    y << (c == 0 ? 1.0 : 0.0), (c == 1 ? 1.0 : 0.0);
    integ->reset(sys, 0.0, y);
    SolveStats s;
    EXPECT_EQ(integ->step(sys, 0.0, y, h, s), Status::ok) << name << ": " << s.message;
    m[static_cast<std::size_t>(c)] = y(0);
    m[static_cast<std::size_t>(2 + c)] = y(1);
  }
  return dominant_eigenvalue_2x2(m[0], m[1], m[2], m[3]);
}

struct Case {
  std::string name;
  std::vector<std::string> params;
};

// The formula's map is the integrator's map: the dominant eigenvalue agrees to the Newton
// tolerance (the implicit stages are linear here, so Newton converges in one iteration and the
// agreement is at round-off) on undamped and damped oscillators, stable and unstable steps.
TEST(PartitionedStability, FormulaIsTheIntegratorsMap) {
  const std::vector<Case> cases = {
      {"imex_euler", {}}, {"ars232", {}},        {"ars443", {}}, {"ark324l2sa", {}},
      {"ark436l2sa", {}}, {"imex_ssp2_222", {}}, {"lie", {}},    {"strang", {"explicit=kutta3"}}};
  for (const auto& c : cases) {
    const auto ls = make(c.name, c.params)->partitioned_stability();
    ASSERT_TRUE(ls.has_value()) << c.name;
    for (const double nu : {0.3, 1.0, 1.9, 2.5, 3.5})
      for (const double zeta : {0.0, 0.1}) {
        const double h = 0.01, omega = nu / h, a = -omega * omega, b = -2.0 * zeta * omega;
        const std::complex<double> want = ls->mechanical_multiplier(h * h * a, h * b);
        const std::complex<double> got = measured_multiplier(c.name, c.params, a, b, h);
        EXPECT_LE(std::abs(got - want), 1e-9 * std::max(1.0, std::abs(want)))
            << c.name << " nu = " << nu << " zeta = " << zeta << ": measured " << got
            << ", formula " << want;
        EXPECT_NEAR(ls->mechanical_amplification(h * h * a, h * b), std::abs(want), 1e-12);
      }
  }
}

// Exact limits on the undamped oscillator, derived by hand:
//  - imex_euler (forward Euler on v, backward Euler on x): v ← v − hω²x, x ← x + hv, i.e.
//    symplectic Euler, trace 2 − ν², det 1: stable iff ν <= 2;
//  - lie and strang: whatever the explicit sub-integrator, symplectic Euler and velocity Verlet
//    at b = 0 (operator_splitting.cpp): ν <= 2;
//  - ars232: the map's eigenvalues leave the unit circle at ν = 3.10754794806 (the first
//    crossing of the spectral radius of the same stage equations solved stage by stage in plain
//    Python, bisection to 1e-15; not the explicit table's imaginary limit √2);
//  - ark324l2sa: det D(ν²) = 1 + c ν⁴ + ... with c > 0 (growth ~0.026 ν⁴ per step), so it is
//    unstable arbitrarily close to 0: limit 0.
TEST(PartitionedStability, ExactOscillatorLimits) {
  const auto limit = [](const std::string& name) {
    const auto ls = make(name, {})->partitioned_stability();
    EXPECT_TRUE(ls.has_value()) << name;
    return oscillator_limit(*ls);
  };
  for (const std::string name : {"imex_euler", "lie", "strang"}) {
    const AxisLimit l = limit(name);
    EXPECT_TRUE(l.exact) << name;
    EXPECT_NEAR(l.limit, 2.0, 1e-12) << name;
  }
  const AxisLimit ars = limit("ars232");
  EXPECT_TRUE(ars.exact);
  EXPECT_NEAR(ars.limit, 3.10754794806, 1e-9);
  const AxisLimit ark = limit("ark324l2sa");
  EXPECT_TRUE(ark.exact);
  EXPECT_EQ(ark.limit, 0.0);
  EXPECT_FALSE(ark.unbounded);
  // The measured map grows at ν = 0.5 (a step that every explicit table with an imaginary-axis
  // limit above 0.5 would call stable).
  EXPECT_GT(std::abs(measured_multiplier("ark324l2sa", {}, -2500.0, 0.0, 0.01)), 1.0 + 1e-9);
}

}  // namespace
}  // namespace stiffbench
