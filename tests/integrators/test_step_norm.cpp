// Integrator::last_step_max_norm(): the kick/drift and explicit Runge-Kutta methods take ‖y‖∞ of
// the state they return while writing it (the fixed-step driver's blow-up check uses it instead
// of its own pass). Checked against ‖y‖∞ computed here from the returned state, on a cloth large
// enough for the OpenMP path of both (130²: 50,700 coordinates, 101,400 entries) and on a small
// one (serial path), and NaN when the state has a NaN entry.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "experiments/catalog.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

TEST(StepNorm, EqualsMaxNormOfTheReturnedState) {
  for (const std::string n : {"8", "130"}) {
    const auto sys = testing_support::model("cloth", {"n=" + n, "perturbation=0.01"});
    for (const std::string method : {"symplectic_euler", "velocity_verlet", "rk4", "heun"}) {
      auto integ = testing_support::make(method);
      Vec y = sys->initial_state();
      integ->reset(*sys, 0.0, y);
      EXPECT_FALSE(integ->last_step_max_norm().has_value()) << method << " before a step";
      SolveStats stats;
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(integ->step(*sys, k * 1e-3, y, 1e-3, stats), Status::ok);
        const auto norm = integ->last_step_max_norm();
        ASSERT_TRUE(norm.has_value()) << method;
        // Exactly the max of |y_i| (max is exact, in any order).
        EXPECT_EQ(*norm, y.cwiseAbs().maxCoeff()) << method << " n=" << n;
      }
      // A NaN entry in the state makes the next step's norm NaN.
      y[y.size() - 1] = std::numeric_limits<double>::quiet_NaN();
      integ->step(*sys, 3e-3, y, 1e-3, stats);
      ASSERT_TRUE(integ->last_step_max_norm().has_value());
      EXPECT_TRUE(std::isnan(*integ->last_step_max_norm())) << method;
    }
  }
}

}  // namespace
}  // namespace stiffbench
