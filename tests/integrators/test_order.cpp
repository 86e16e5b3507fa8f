// Observed orders of every registered integrator, through the same experiment code the
// `convergence` and `local-error` commands use.
#include <gtest/gtest.h>

#include "experiments/framework/catalog.hpp"
#include "experiments/studies/convergence.hpp"

namespace stiffbench {
namespace {

// The hand-written methods; the library references have their own order tests
// (test_reference.cpp) with the tolerances their Newton solvers need. Methods that need
// holonomic constraints (rattle) cannot run on these unconstrained problems: their order is
// tested on the constrained pendulum chain (test_rattle.cpp). Methods that need a spring
// network (xpbd, projective_dynamics) cannot run on the oscillator and Kepler problems here,
// which have no springs: their order 1 is checked on the spring chain's exact normal-mode
// solution in test_graphics_solvers.cpp. Methods that need an additive split (the imex family)
// cannot run on these unsplit problems: their orders are checked on a split test system with an
// exact solution in test_imex_ark.cpp.
std::vector<std::string> all_integrators() {
  std::vector<std::string> out;
  for (const auto& e : integrator_registry().entries())
    // stable_fluids runs only on fluid_2d (tests/models/test_grid.cpp); lie and strang need a
    // split (tests/integrators/test_operator_splitting.cpp).
    if (e.info.family != Family::reference && !e.info.requires_.constraints &&
        !e.info.requires_.spring_network && !e.info.requires_.grid_fluid && !e.info.requires_.split)
      out.push_back(e.info.name);
  return out;
}

class OrderTest : public ::testing::TestWithParam<std::string> {
 protected:
  int order() const { return integrator_registry().at(GetParam()).info.order; }
};

// Global error at t = 10 on the undamped oscillator (exact solution cos t), h = 0.1 / 2^k,
// k = 0..5. The last pair (h = 0.00625 → 0.003125) is in the asymptotic range for every method
// and far above round-off (smallest error, rk4's, is ~1e-10). Fifth-order methods (dopri5,
// cash_karp) would reach round-off there (dopri5: 7e-13 at h = 0.0125), so they take
// h = 0.4 / 2^k, k = 0..4 (last pair 0.05 → 0.025, errors 8e-10 and 2e-11).
TEST_P(OrderTest, GlobalOrderOnHarmonicOscillator) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {GetParam()};
  spec.t_end = 10;
  spec.h = order() >= 5 ? 0.4 : 0.1;
  spec.levels = order() >= 5 ? 5 : 6;
  // gauss6 (order 6, the diagonal Padé error constant 3!²/(6!·7!) ≈ 1e-5) would reach round-off
  // from h = 0.025 (3e-14); it takes h = 0.8 / 2^k (last pair 0.1 → 0.05, errors 8e-11, 1.3e-12).
  if (GetParam() == "gauss6") spec.h = 0.8;
  // blanes_moan's error constant is tiny (errors 3e-12 at h = 0.0125, 1.4e-14 at 0.003125: the
  // round-off floor, where the observed order is 3.8 and moves with the last bits of its
  // coefficients): it takes h = 0.4 / 2^k, k = 0..4 (last pair 0.05 → 0.025, errors 7.7e-10 and
  // 4.8e-11, observed order 4.0007).
  if (GetParam() == "blanes_moan") {
    spec.h = 0.4;
    spec.levels = 5;
  }
  const auto res = run_convergence(spec, nullptr);
  const auto p = last_observed_order(res.rows, GetParam());
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(*p, order(), 0.2);
}

// Local error of one step from (x, v) = (1, 0): the leading term is C h^{p+1}, so the slope
// is order + 1. Step sizes 0.4 / 2^k, k = 0..4 (smallest rk4 error ~1e-10).
TEST_P(OrderTest, LocalErrorSlopeOnHarmonicOscillator) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {GetParam()};
  spec.h = 0.4;
  spec.levels = 5;
  // gauss6's one-step error (≈ 1e-5 h^7) is at round-off at h = 0.025 (1e-16): h = 0.8 / 2^k
  // (last pair 0.1 → 0.05, errors 1e-12, 8e-15, slope 6.98).
  if (GetParam() == "gauss6") spec.h = 0.8;
  const auto res = run_local_error(spec, nullptr);
  const auto p = last_observed_order(res.rows, GetParam());
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(*p, order() + 1, 0.2);
}

// The oscillator is linear, so it checks only the linear order conditions. The eccentric
// Kepler orbit (e = 0.5, exact solution through Kepler's equation) exercises the nonlinear
// ones. t_end = 5 is deliberately not a period: after exactly one period of this reversible
// orbit the first-order symplectic Euler errors cancel and it shows order 2. Fifth-order
// methods start at h = 0.04 (dopri5: errors 3e-10 and 9e-12 in the last pair; from h = 0.01
// they would end at round-off, 9e-14).
TEST_P(OrderTest, GlobalOrderOnEccentricKepler) {
  ConvergenceSpec spec;
  spec.model = "kepler";
  spec.params = Params::from_assignments({"e=0.5"});
  spec.integrators = {GetParam()};
  spec.t_end = 5;
  // blanes_moan is fourth order with an error constant ~3000 times yoshida4's (measured: 2e-10
  // at h = 0.01, against 2.3e-6), so from h = 0.01 it would end at round-off (5e-14 at
  // h = 0.00125); it starts at h = 0.04 like the fifth-order methods (errors 2e-10, 1.3e-11).
  spec.h = order() >= 5 || GetParam() == "blanes_moan" ? 0.04 : 0.01;
  // gauss6 from h = 0.04 ends at 2.6e-14 (h = 0.005); from h = 0.16 the last pair is h = 0.04 →
  // 0.02 with errors 7.4e-9 and 1.2e-10 (order 6.00).
  if (GetParam() == "gauss6") spec.h = 0.16;
  spec.levels = 4;
  const auto res = run_convergence(spec, nullptr);
  const auto p = last_observed_order(res.rows, GetParam());
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(*p, order(), 0.2);
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, OrderTest, ::testing::ValuesIn(all_integrators()),
                         [](const auto& param_info) { return param_info.param; });

// observed_order is empty on each integrator's first row and computed from consecutive rows
// of the same integrator only.
TEST(ConvergenceRows, ObservedOrderOnlyBetweenRowsOfOneIntegrator) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"euler", "rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 3;
  const auto res = run_convergence(spec, nullptr);
  ASSERT_EQ(res.rows.size(), 6u);
  EXPECT_FALSE(res.rows[0].observed_order.has_value());
  EXPECT_FALSE(res.rows[3].observed_order.has_value());
  const auto& a = res.rows[1];
  const auto& b = res.rows[2];
  EXPECT_DOUBLE_EQ(*b.observed_order, std::log(a.error / b.error) / std::log(a.h / b.h));
  EXPECT_EQ(res.reference_description, "exact");
}

// A reference run replaces the exact solution when asked: rk4 at (finest h)/16 is accurate
// to ~1e-11 here, far below euler's errors, so the orders agree with the exact reference.
TEST(ConvergenceRows, ReferenceMethodAgreesWithExact) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"euler", "heun"};
  spec.t_end = 2;
  spec.h = 0.1;
  spec.levels = 3;
  const auto exact = run_convergence(spec, nullptr);
  spec.reference = "rk4";
  const auto ref = run_convergence(spec, nullptr);
  ASSERT_EQ(exact.rows.size(), ref.rows.size());
  for (std::size_t i = 0; i < exact.rows.size(); ++i)
    EXPECT_NEAR(ref.rows[i].error, exact.rows[i].error, 1e-9 + 1e-6 * exact.rows[i].error);
  EXPECT_NE(ref.reference_description.find("rk4"), std::string::npos);
}

TEST(ConvergenceRows, NoExactSolutionNeedsReference) {
  ConvergenceSpec spec;
  spec.model = "pendulum";
  spec.integrators = {"euler"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  EXPECT_THROW(run_convergence(spec, nullptr), BadInput);
  spec.reference = "exact";
  EXPECT_THROW(run_convergence(spec, nullptr), BadInput);
}

}  // namespace
}  // namespace stiffbench
