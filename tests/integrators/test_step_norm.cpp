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

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "experiments/framework/catalog.hpp"
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

// The explicit Runge-Kutta methods run each combination pass inside the evaluation before it:
// on each range of dofs as the system finishes it (acceleration_in_ranges), or, on a system that
// offers an AccelerationChain, block by block in a wavefront over the stages (explicit_rk.cpp,
// chained_stages; two sweeps meeting at the middle block on two threads). Where the passes run
// does not change their per-entry arithmetic, and the chain's calls are the same pieces as the
// whole evaluation with every entry's terms in the same order on any schedule, so the states,
// the step norms and the evaluation counts must be bit for bit those of the same steps on the
// same network seen without either (WholeEvaluation: whole evaluations, every pass after them).
// The cloth n² with and without dashpots (stage velocities formed or not), at 1 and 2 threads;
// methods with a stage position formed in place (rk4, rk38), a final update of two and four
// terms, and Euler (the update right after the first evaluation). chained: whether the cloth
// offers its 32 partitions as a chain.
void expect_bits_of_whole_evaluations(int n, bool chained) {
  const int threads0 = omp_get_max_threads();
  for (const bool dashpots : {false, true}) {
    std::vector<std::string> params = {"n=" + std::to_string(n), "perturbation=0.01"};
    if (dashpots) params.push_back("dashpot=0.5");
    const auto sys = testing_support::model("cloth", params);
    const MechanicalSystem& mech = *sys->as_mechanical();
    ASSERT_EQ(mech.velocity_dependent(), dashpots);
    ASSERT_EQ(mech.acceleration_chain() != nullptr, chained);
    if (chained) {
      ASSERT_EQ(mech.acceleration_chain()->blocks(), 32);
    }
    const WholeEvaluation whole(mech);
    ASSERT_EQ(whole.acceleration_chain(), nullptr);
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
        const long f0 = sys->counters().f_evals;
        for (int k = 0; k < 4; ++k) {
          ASSERT_EQ(a->step(*sys, k * 2e-3, ya, 2e-3, sa), Status::ok);
          ASSERT_EQ(b->step(whole, k * 2e-3, yb, 2e-3, sb), Status::ok);
          EXPECT_TRUE(ya == yb) << "step " << k << ": max |diff| "
                                << (ya - yb).cwiseAbs().maxCoeff();
          EXPECT_EQ(*a->last_step_max_norm(), *b->last_step_max_norm());
          EXPECT_EQ(*a->last_step_max_norm(), ya.cwiseAbs().maxCoeff());
        }
        // whole's evaluations count on sys too: 2 × 4 steps × s, one a stage on each.
        EXPECT_EQ(sys->counters().f_evals - f0, 8L * a->info().stages);
        EXPECT_GT((ya - sys->initial_state()).cwiseAbs().maxCoeff(), 1e-6);
      }
    }
  }
  omp_set_num_threads(threads0);
}

// Cloth 48² (32 partitions of 1.5 rows, the parallel path; no chain: its bending springs, two
// rows long, join partitions that are not neighbours). A pass that ran on a range too early (before
// its accelerations were final) or wrote a position the evaluation still reads would change the
// bits.
TEST(StepNorm, PassesInsideTheEvaluationsGiveTheBitsOfPassesAfterThem) {
  expect_bits_of_whole_evaluations(48, false);
}

// Cloth 130² (32 partitions of about four rows, 50,700 coordinates: the chain on the two-thread
// schedule). A task run before its inputs were final (a link reading a neighbour's stage values
// before that neighbour's pass, a finish before the links into its block, an update before the
// last read of x or v there) or a pass overwriting what a later task reads would change the bits.
TEST(StepNorm, ChainedStagesGiveTheBitsOfWholeEvaluations) {
  expect_bits_of_whole_evaluations(130, true);
}

// A user's own chain: a line of n unit masses joined by springs of a cubic force law
// f = k (d + d³) (d the extension) with dashpots, cut into blocks of uneven sizes (at least two
// points each, so no point has both of its springs in links). Its acceleration() is the chain's
// pieces in one order (every clear, every link, every finish), the chained steps run them in
// others, so the comparison checks the wavefront's order, the handshakes of its two sweeps and
// the pass ranges on a system the testbed does not know. A link that throws must stop the step
// with its exception on either schedule (not hang a sweep waiting for the other).
class SpringLine final : public MechanicalSystem, public AccelerationChain {
 public:
  explicit SpringLine(Index n) : n_(n) {
    for (Index b = 0; b < n;) {  // block sizes 2, 5, 9, 2, 5, 9, ... (scaled) up to n
      starts_.push_back(b);
      b = std::min(n, b + std::array<Index, 3>{2, 5, 9}[starts_.size() % 3] * (n / 2000 + 1));
    }
    starts_.push_back(n);
  }
  std::string name() const override { return "spring_line"; }
  Index dofs() const override { return n_; }
  Vec initial_state() const override {
    Vec y(2 * n_);
    for (Index i = 0; i < n_; ++i) {
      y[i] = static_cast<double>(i) + 0.1 * std::sin(0.37 * static_cast<double>(i));
      y[n_ + i] = 0.05 * std::cos(0.11 * static_cast<double>(i));
    }
    return y;
  }
  bool velocity_dependent() const override { return true; }
  const AccelerationChain* acceleration_chain() const override { return chained_ ? this : nullptr; }
  bool chained_ = true;
  Index throw_at_ = -1;  // link(q) throws BadInput for q == throw_at_

  Index blocks() const override { return static_cast<Index>(starts_.size()) - 1; }
  Index begin(Index q) const override { return starts_[static_cast<std::size_t>(q)]; }
  void clear(Index q, VecRef a) const override {
    a.segment(begin(q), begin(q + 1) - begin(q)).setZero();
  }
  void link(Index q, double, CVecRef x, CVecRef v, VecRef a) const override {
    if (q == throw_at_) throw BadInput("spring_line: link " + std::to_string(q));
    spring(begin(q + 1) - 1, x, v, a);
  }
  void finish(Index q, double, CVecRef x, CVecRef v, VecRef a) const override {
    for (Index i = begin(q); i + 1 < begin(q + 1); ++i) spring(i, x, v, a);
  }

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override {
    for (Index q = 0; q < blocks(); ++q) clear(q, a);
    for (Index q = 0; q + 1 < blocks(); ++q) link(q, t, x, v, a);
    for (Index q = 0; q < blocks(); ++q) finish(q, t, x, v, a);
  }

 private:
  // The spring between points i and i + 1 (rest length 1, k = 40, dashpot 0.3).
  static void spring(Index i, CVecRef x, CVecRef v, VecRef a) {
    const double d = x[i + 1] - x[i] - 1.0;
    const double f = 40.0 * (d + d * d * d) + 0.3 * (v[i + 1] - v[i]);
    a[i] += f;
    a[i + 1] -= f;
  }
  Index n_;
  std::vector<Index> starts_;
};

TEST(StepNorm, AUsersChainGivesTheBitsOfItsWholeEvaluation) {
  const int threads0 = omp_get_max_threads();
  SpringLine line(60000);  // 60,000 coordinates: the two-thread schedule
  ASSERT_GT(line.blocks(), 100);
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    for (const std::string method : {"rk4", "rk38", "heun", "euler"}) {
      SCOPED_TRACE(method + " threads " + std::to_string(threads));
      auto a = testing_support::make(method);
      auto b = testing_support::make(method);
      Vec ya = line.initial_state(), yb = ya;
      a->reset(line, 0.0, ya);
      b->reset(line, 0.0, yb);
      SolveStats sa, sb;
      for (int k = 0; k < 5; ++k) {
        line.chained_ = true;
        const long f0 = line.counters().f_evals;
        ASSERT_EQ(a->step(line, k * 1e-2, ya, 1e-2, sa), Status::ok);
        EXPECT_EQ(line.counters().f_evals - f0, a->info().stages);
        line.chained_ = false;
        ASSERT_EQ(b->step(line, k * 1e-2, yb, 1e-2, sb), Status::ok);
        EXPECT_TRUE(ya == yb) << "step " << k << ": max |diff| " << (ya - yb).cwiseAbs().maxCoeff();
        EXPECT_EQ(*a->last_step_max_norm(), *b->last_step_max_norm());
      }
      EXPECT_GT((ya - line.initial_state()).cwiseAbs().maxCoeff(), 1e-3);
      // A throwing link: in the first thread's blocks, at the split, in the second's.
      line.chained_ = true;
      for (const Index q : {Index{3}, line.blocks() / 2 - 1, line.blocks() - 2}) {
        line.throw_at_ = q;
        EXPECT_THROW(a->step(line, 0.0, ya, 1e-2, sa), BadInput) << "link " << q;
      }
      line.throw_at_ = -1;
    }
  }
  omp_set_num_threads(threads0);
}
}  // namespace
}  // namespace stiffbench
