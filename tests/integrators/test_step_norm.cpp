// Integrator::last_step_max_norm(): the kick/drift and explicit Runge-Kutta methods take ‖y‖∞ of
// the state they return while writing it (the fixed-step driver's blow-up check uses it instead
// of its own pass). Checked against ‖y‖∞ computed here from the returned state, on a cloth large
// enough for the OpenMP path of both (130²: 50,700 coordinates, 101,400 entries) and on a small
// one (serial path), and NaN when the state has a NaN entry.
//
// On a mechanical system the explicit Runge-Kutta methods run in their accelerations alone
// (integrators/explicit/explicit_rk.hpp: X_i = x + h (Σ_j a_ij) v + h² Σ_k (A²)_ik A_k, ...):
// the same stage values as the first-order form in exact arithmetic. The states must agree with
// those of the same methods run on the system's first-order face to within rounding: each
// combination sums at most s + 2 terms, so the two forms' values differ by at most
// 2 (s + 2) ε Σ|terms| (Higham 2002, §4.2) with Σ|terms| ≈ ‖y‖∞ (h |k| ≪ |y| here), and a change
// δx in a stage position changes the next ones by about (hω)² δx ≪ δx. 64 ε ‖y‖∞ a step covers
// s ≤ 4 with room; a wrong coefficient would show as h² |a| ≈ 1e-6 or more.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

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

// The system's first-order face only: as_mechanical() is null, so an integrator takes its general
// path and sees f = [v; a] through rhs(), the copy of v included.
class FirstOrderFace final : public OdeSystem {
 public:
  explicit FirstOrderFace(const OdeSystem& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  Index dimension() const override { return inner_.dimension(); }
  Vec initial_state() const override { return inner_.initial_state(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef f) const override { inner_.rhs(t, y, f); }

 private:
  const OdeSystem& inner_;
};

TEST(StepNorm, MechanicalPathMatchesTheFirstOrderPathToRounding) {
  // 8²: serial passes; 130²: 50,700 coordinates, the threaded passes of both paths. The damped
  // cloth with air drag is velocity-dependent, so the mechanical path also forms the stage
  // velocities, beside stage positions formed in place from the previous ones (rk4's X_3, rk38's
  // X_2 and X_3: header).
  for (const std::string n : {"8", "130", "8 damped"}) {
    const bool damped = n == "8 damped";
    const auto sys = damped ? testing_support::model(
                                  "cloth", {"n=8", "perturbation=0.01", "damping=0.3", "drag=1"})
                            : testing_support::model("cloth", {"n=" + n, "perturbation=0.01"});
    ASSERT_NE(sys->as_mechanical(), nullptr);
    ASSERT_EQ(sys->as_mechanical()->velocity_dependent(), damped);
    const FirstOrderFace plain(*sys);
    for (const std::string method : {"rk4", "rk38", "heun", "ssprk3", "kutta3", "euler"}) {
      auto a = testing_support::make(method);
      auto b = testing_support::make(method);
      Vec ya = sys->initial_state(), yb = ya;
      a->reset(*sys, 0.0, ya);
      b->reset(plain, 0.0, yb);
      SolveStats sa, sb;
      // The face's rhs() also counts on sys: a's evaluations are counted before b runs.
      const long f0 = sys->counters().f_evals;
      for (int k = 0; k < 4; ++k) ASSERT_EQ(a->step(*sys, k * 2e-3, ya, 2e-3, sa), Status::ok);
      const long fa = sys->counters().f_evals - f0, fb0 = plain.counters().f_evals;
      for (int k = 0; k < 4; ++k) ASSERT_EQ(b->step(plain, k * 2e-3, yb, 2e-3, sb), Status::ok);
      // One f evaluation a stage on both paths.
      EXPECT_EQ(fa, plain.counters().f_evals - fb0) << method;
      EXPECT_EQ(fa, 4L * a->info().stages) << method;
      const double bound =
          4 * 64 * std::numeric_limits<double>::epsilon() * yb.cwiseAbs().maxCoeff();
      EXPECT_LE((ya - yb).cwiseAbs().maxCoeff(), bound) << method << " n=" << n;
      // The steps moved the state well beyond that bound (the comparison is not vacuous).
      EXPECT_GT((ya - sys->initial_state()).cwiseAbs().maxCoeff(), 1e6 * bound) << method;
      EXPECT_NEAR(*a->last_step_max_norm(), *b->last_step_max_norm(), bound) << method;
    }
  }
}

// The same mechanical system with the default acceleration_in_ranges only (done after the whole
// evaluation, core/ode_system.cpp), where MassSpringNetwork calls done on each partition as it
// finishes it.
class WholeEvaluation final : public MechanicalSystem {
 public:
  explicit WholeEvaluation(const MechanicalSystem& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  Index dofs() const override { return inner_.dofs(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool velocity_dependent() const override { return inner_.velocity_dependent(); }

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override {
    inner_.acceleration(t, x, v, a);
  }

 private:
  const MechanicalSystem& inner_;
};

// The explicit Runge-Kutta methods run each combination pass inside the evaluation before it, on
// each range of dofs as the system finishes it (explicit_rk.cpp). When the passes run does not
// change their per-entry arithmetic, so the states and the step norms are bit for bit those of
// the same steps with every pass after the whole evaluation. A pass that ran on a range too early
// (before its accelerations were final) or wrote a position the evaluation still reads would
// change them. Cloth 48² (32 partitions, the parallel path) with and without dashpots (stage
// velocities formed or not), at 1 and 2 threads; methods with a stage position formed in place
// (rk4, rk38), a final update of two and four terms, and Euler (the update right after the
// first evaluation).
TEST(StepNorm, PassesInsideTheEvaluationsGiveTheBitsOfPassesAfterThem) {
  const int threads0 = omp_get_max_threads();
  for (const bool dashpots : {false, true}) {
    std::vector<std::string> params = {"n=48", "perturbation=0.01"};
    if (dashpots) params.push_back("dashpot=0.5");
    const auto sys = testing_support::model("cloth", params);
    ASSERT_EQ(sys->as_mechanical()->velocity_dependent(), dashpots);
    const WholeEvaluation whole(*sys->as_mechanical());
    for (const int threads : {1, 2}) {
      omp_set_num_threads(threads);
      for (const std::string method : {"rk4", "rk38", "heun", "ssprk3", "kutta3", "euler"}) {
        SCOPED_TRACE(method + (dashpots ? " dashpots" : "") + " threads " +
                     std::to_string(threads));
        auto a = testing_support::make(method);
        auto b = testing_support::make(method);
        Vec ya = sys->initial_state(), yb = ya;
        a->reset(*sys, 0.0, ya);
        b->reset(whole, 0.0, yb);
        SolveStats sa, sb;
        for (int k = 0; k < 4; ++k) {
          ASSERT_EQ(a->step(*sys, k * 2e-3, ya, 2e-3, sa), Status::ok);
          ASSERT_EQ(b->step(whole, k * 2e-3, yb, 2e-3, sb), Status::ok);
          EXPECT_TRUE(ya == yb) << "step " << k << ": max |diff| "
                                << (ya - yb).cwiseAbs().maxCoeff();
          EXPECT_EQ(*a->last_step_max_norm(), *b->last_step_max_norm());
          EXPECT_EQ(*a->last_step_max_norm(), ya.cwiseAbs().maxCoeff());
        }
        EXPECT_GT((ya - sys->initial_state()).cwiseAbs().maxCoeff(), 1e-6);
      }
    }
  }
  omp_set_num_threads(threads0);
}

}  // namespace
}  // namespace stiffbench
