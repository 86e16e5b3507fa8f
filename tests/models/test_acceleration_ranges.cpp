// MechanicalSystem::acceleration_in_ranges (core/ode_system.hpp): a(t, x, v), and done(b, e) on
// ranges of dofs that cover [0, dofs()) once each, each called once a[b, e) is final and the
// evaluation will not read x or v in [b, e) again. MassSpringNetwork calls done on each partition
// of points as it finishes it; with air drag (added after all partitions) and for other models
// the default calls it after the whole evaluation.
//
// The contract is checked here as a property, against an independent full evaluation
// (acceleration(), bit for bit): when done(b, e) runs, a[b, e) already holds acceleration()'s
// values; done then overwrites x[b, e) and v[b, e) with NaN, and the evaluation's a must still
// equal acceleration()'s bit for bit, which any later read of those entries would spoil (a NaN
// spreads through every force it enters). The ranges must tile [0, dofs()).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

struct Case {
  std::string model;
  std::vector<std::string> params;
  std::size_t min_ranges;  // at least this many ranges (32: the network's partitions)
};

TEST(AccelerationInRanges, EachRangeIsFinalWhenDoneRunsAndIsNotReadAgain) {
  // Cloth 48²: 2,304 points, at the parallel threshold's 2,048 and 32 partitions (≥ 64 · 32
  // points); with dashpots and point damping (a reads v), without them, split into parts, and
  // with drag (the default: one range, or 64 on threads from 50,000 dofs: cloth 130², 50,700).
  // A 6² cloth has one partition; the SPH tank is not a network (the default).
  const std::vector<Case> cases = {
      {"cloth", {"n=48", "perturbation=0.01", "dashpot=0.5", "damping=0.3"}, 32},
      {"cloth", {"n=48", "perturbation=0.01"}, 32},
      {"cloth", {"n=48", "perturbation=0.01", "dashpot=0.5", "split=stretch"}, 32},
      {"cloth", {"n=6", "perturbation=0.01", "dashpot=0.5"}, 1},
      {"cloth", {"n=20", "perturbation=0.01", "drag=1"}, 1},
      {"cloth", {"n=130", "perturbation=0.01", "drag=1"}, 64},
      {"sph_tank_2d", {"n=8", "width=0.1"}, 1}};
  const int threads0 = omp_get_max_threads();
  for (const Case& c : cases) {
    SCOPED_TRACE(c.model + " " + (c.params.empty() ? "" : c.params[0]) +
                 (c.params.size() > 2 ? " " + c.params[2] : ""));
    const auto sys = testing_support::model(c.model, c.params);
    const MechanicalSystem* m = sys->as_mechanical();
    ASSERT_NE(m, nullptr);
    const Index d = m->dofs();
    const Vec y0 = sys->initial_state();
    const Vec x = y0.head(d);
    Vec v(d);
    std::mt19937 gen(3);
    std::uniform_real_distribution<double> u(-0.1, 0.1);
    for (Index i = 0; i < d; ++i) v[i] = u(gen);
    for (const int threads : {1, 2}) {
      SCOPED_TRACE(threads);
      omp_set_num_threads(threads);
      Vec ref(d);
      m->acceleration(0.0, x, v, ref);
      ASSERT_TRUE(ref.allFinite());
      ASSERT_GT(ref.cwiseAbs().maxCoeff(), 0.0);
      Vec xs = x, vs = v, a = Vec::Constant(d, std::numeric_limits<double>::quiet_NaN());
      std::mutex mu;
      std::vector<std::pair<Index, Index>> ranges;
      bool final_when_done = true;
      const auto done = [&](Index b, Index e) {
        const std::lock_guard<std::mutex> lock(mu);
        ranges.emplace_back(b, e);
        for (Index i = b; i < e; ++i) {
          // Bit for bit (NaN never equals: a not yet written fails too).
          if (!(a[i] == ref[i] && std::signbit(a[i]) == std::signbit(ref[i])))
            final_when_done = false;
          xs[i] = std::numeric_limits<double>::quiet_NaN();
          vs[i] = std::numeric_limits<double>::quiet_NaN();
        }
      };
      const long f0 = sys->counters().f_evals;
      m->acceleration_in_ranges(0.0, xs, vs, a, done);
      EXPECT_EQ(sys->counters().f_evals, f0 + 1);  // one f evaluation
      EXPECT_TRUE(final_when_done);
      EXPECT_TRUE(a == ref) << "max |diff| " << (a - ref).cwiseAbs().maxCoeff();
      std::sort(ranges.begin(), ranges.end());
      EXPECT_GE(ranges.size(), c.min_ranges);
      Index next = 0;
      for (const auto& [b, e] : ranges) {
        EXPECT_EQ(b, next);
        EXPECT_GT(e, b);
        next = e;
      }
      EXPECT_EQ(next, d);
    }
  }
  omp_set_num_threads(threads0);
}

}  // namespace
}  // namespace stiffbench
