// Geometric integrators: the order conditions of the velocity-Verlet compositions and their
// bounded energy error over long Kepler runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "integrators/symplectic/composition.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

double power_sum(const std::vector<double>& g, int p) {
  double s = 0.0;
  for (double x : g) s += std::pow(x, p);
  return s;
}

// Symmetric composition order conditions (Hairer, Lubich & Wanner, GNI §V.3.2): Σγ = 1 and
// Σγ³ = 0 for order 4, and in addition Σγ⁵ = 0 for order 6 (the remaining order-6 condition is
// checked by the observed order 6 in test_order.cpp). The published coefficients have 15
// digits, so the sums hold to ~1e-14.
TEST(Composition, OrderConditionsOfTheCoefficientTables) {
  for (const CompositionMethod& m : composition_methods()) {
    SCOPED_TRACE(m.name);
    const auto& c = m.kick_drift;
    ASSERT_EQ(c.kick.size(), c.drift.size());
    double sk = 0.0, sd = 0.0;
    for (std::size_t j = 0; j < c.kick.size(); ++j) {
      sk += c.kick[j];
      sd += c.drift[j];
    }
    EXPECT_NEAR(sk, 1.0, 1e-14);
    EXPECT_NEAR(sd, 1.0, 1e-14);
    // Symmetric: kicks palindromic, drifts palindromic apart from the trailing zero.
    const std::size_t s = c.kick.size();
    for (std::size_t j = 0; j < s; ++j) EXPECT_NEAR(c.kick[j], c.kick[s - 1 - j], 1e-15);
    for (std::size_t j = 0; j + 1 < s; ++j) EXPECT_NEAR(c.drift[j], c.drift[s - 2 - j], 1e-15);
    EXPECT_EQ(c.drift.back(), 0.0);
    if (m.gamma.empty()) continue;
    EXPECT_NEAR(power_sum(m.gamma, 1), 1.0, 1e-14);
    EXPECT_NEAR(power_sum(m.gamma, 3), 0.0, 1e-13);
    if (m.order >= 6) {
      EXPECT_NEAR(power_sum(m.gamma, 5), 0.0, 1e-13);
    }
  }
}

// Energy error over 1000 orbits of Kepler e = 0.5 at 100 steps per orbit: a symplectic method's
// energy error oscillates with bounded amplitude (backward error analysis, GNI §IX.8), so the
// largest |ΔH| over orbits 1..1000 stays close to that over orbits 1..100; a drift would make it
// ~10 times larger. Measured (h = T/100): yoshida4 1.6e-4, yoshida6 7.6e-7, blanes_moan
// 1.7e-8, the same over 100 and 1000 orbits.
TEST(Composition, EnergyErrorBoundedOverThousandKeplerOrbits) {
  const auto sys = model("kepler", {"e=0.5"});
  const double period = 2.0 * std::numbers::pi;
  const int per_orbit = 100;
  const double h = period / per_orbit;
  for (const std::string name : {"yoshida4", "yoshida6", "blanes_moan"}) {
    SCOPED_TRACE(name);
    auto integ = make(name);
    Vec y = sys->initial_state();
    const auto energy = sys->invariants().at(0).value;
    const double h0 = energy(0.0, y);
    integ->reset(*sys, 0.0, y);
    SolveStats stats;
    double t = 0.0, max100 = 0.0, max1000 = 0.0;
    for (int k = 1; k <= 1000 * per_orbit; ++k) {
      ASSERT_EQ(integ->step(*sys, t, y, h, stats), Status::ok);
      t += h;
      const double d = std::abs(energy(t, y) - h0);
      if (k <= 100 * per_orbit) max100 = std::max(max100, d);
      max1000 = std::max(max1000, d);
    }
    EXPECT_GT(max100, 1e-12);  // far above round-off, so the comparison measures the method
    EXPECT_LT(max1000, 1.5 * max100);
  }
}

}  // namespace
}  // namespace stiffbench
