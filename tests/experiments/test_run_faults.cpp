// Faults inside a run: a model that throws or returns NaN mid-run, and an integrator
// whose linear solver refuses its matrix, each end their own row with its own status and
// message, while the other rows of the study complete; the command line exits with 3 when a row
// ended with status error.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/convergence.hpp"

using namespace stiffbench;

namespace {

// y' = -y, y(0) = 1, exact e^{-t}. The fault fires on one chosen evaluation of the right-hand
// side, counted over the process, so exactly one run of a study meets it.
enum class Fault { none, throws, nan };
std::atomic<long> g_evals{0};
long g_fault_at = -1;
Fault g_fault = Fault::none;

class FaultyDecay final : public OdeSystem {
 public:
  std::string name() const override { return "faulty_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f[0] = -y[0];
    if (++g_evals != g_fault_at) return;
    if (g_fault == Fault::throws) throw std::runtime_error("model failure injected by the test");
    if (g_fault == Fault::nan) f[0] = std::numeric_limits<double>::quiet_NaN();
  }
};

ConvergenceResult study(Fault fault, long fault_at) {
  g_evals = 0;
  g_fault = fault;
  g_fault_at = fault_at;
  ConvergenceSpec spec;
  spec.integrators = {"rk4", "heun"};
  spec.t_end = 1.0;
  spec.h = 0.1;
  spec.levels = 3;
  spec.refine = 2;
  spec.reference = "exact";
  return run_convergence(
      inputs_of(spec, StudyObjects{[] { return std::make_unique<FaultyDecay>(); }, {}}), spec,
      nullptr);
}

// rk4 at h = 0.1 makes 10 steps x 4 evaluations; evaluation 30 falls in its first run.
TEST(RunFaults, ModelThrowingMidRunEndsOnlyItsRow) {
  const long before = fault_count();
  const ConvergenceResult r = study(Fault::throws, 30);
  ASSERT_EQ(r.rows.size(), 6u);  // 2 integrators x 3 levels: the study went on
  EXPECT_EQ(r.rows[0].stats.status, Status::error);
  EXPECT_NE(r.rows[0].stats.message.find("model failure injected"), std::string::npos)
      << r.rows[0].stats.message;
  for (std::size_t i = 1; i < r.rows.size(); ++i) {
    EXPECT_EQ(r.rows[i].stats.status, Status::ok) << i;
    EXPECT_LT(r.rows[i].error, 1e-2) << i;  // real results, not placeholders
  }
  EXPECT_EQ(fault_count(), before + 1);
}

TEST(RunFaults, ModelReturningNanMidRunIsUnstable) {
  const ConvergenceResult r = study(Fault::nan, 30);
  ASSERT_EQ(r.rows.size(), 6u);
  EXPECT_EQ(r.rows[0].stats.status, Status::unstable);
  EXPECT_FALSE(r.rows[0].stats.message.empty());
  for (std::size_t i = 1; i < r.rows.size(); ++i) EXPECT_EQ(r.rows[i].stats.status, Status::ok);
}

// LDLᵀ reads one triangle and refuses a non-symmetric iteration matrix (Dahlquist's with complex
// λ, J = [[re, -im], [im, re]], is not symmetric): that row ends with solver_error, rk4's row
// completes.
TEST(RunFaults, LinearSolverRefusingItsMatrixEndsOnlyItsRow) {
  ConvergenceSpec spec;
  spec.model = "dahlquist";
  spec.integrators = {"semi_implicit_euler", "rk4"};
  spec.params = Params{{"linear_solver", "ldlt"}, {"lambda_im", 2.0}};
  spec.t_end = 0.5;
  spec.h = 0.01;
  spec.levels = 2;
  spec.refine = 2;
  spec.reference = "exact";
  const ConvergenceResult r = run_convergence(spec, nullptr);
  ASSERT_EQ(r.rows.size(), 4u);
  for (const auto& row : r.rows) {
    if (row.integrator == "semi_implicit_euler") {
      EXPECT_EQ(row.stats.status, Status::solver_error);
      // The linear solver's own reason reaches the row's message.
      EXPECT_NE(row.stats.message.find("ldlt: the matrix is not symmetric"), std::string::npos)
          << row.stats.message;
    } else {
      EXPECT_EQ(row.stats.status, Status::ok);
    }
  }
}

// y' = -10 y, y(0) = 1, exact e^{-10 t}, with its non-negativity declared (the positivity criterion
// of core/ode_system.hpp: f = 0 at y = 0).
class NonNegativeDecay final : public OdeSystem {
 public:
  std::string name() const override { return "nonnegative_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-10.0 * t); }
  std::vector<Index> nonnegative_components() const override { return {0}; }
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -10.0 * y[0]; }
};

// Explicit Euler's factor per step is R(-10h) = 1 - 10h: at h = 0.15 it is -0.5, so after 3 steps
// y(0.45) = -0.125, outside the admissible set (not a blow-up: |R| < 1); at h = 0.075 and 0.0375
// it is 0.25 and 0.625, and rk4's R(-1.5) = 0.2734... > 0. Only the first row ends invalid_state;
// like unstable it is a numerical outcome, not a fault (no exit code 3), and the CSV says so.
TEST(RunFaults, StateOutsideTheAdmissibleSetEndsOnlyItsRow) {
  const long before = fault_count();
  ConvergenceSpec spec;
  spec.integrators = {"euler", "rk4"};
  spec.t_end = 0.45;
  spec.h = 0.15;
  spec.levels = 3;
  spec.refine = 2;
  spec.reference = "exact";
  const ConvergenceResult r = run_convergence(
      inputs_of(spec, StudyObjects{[] { return std::make_unique<NonNegativeDecay>(); }, {}}), spec,
      nullptr);
  ASSERT_EQ(r.rows.size(), 6u);
  EXPECT_EQ(r.rows[0].stats.status, Status::invalid_state);
  EXPECT_NE(r.rows[0].stats.message.find("y[0] = -0.125"), std::string::npos)
      << r.rows[0].stats.message;
  for (std::size_t i = 1; i < r.rows.size(); ++i)
    EXPECT_EQ(r.rows[i].stats.status, Status::ok) << i << ": " << r.rows[i].stats.message;
  EXPECT_EQ(fault_count(), before);
  const Table t = convergence_table(r);
  const auto col = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), "status") - t.columns.begin());
  ASSERT_LT(col, t.columns.size());
  EXPECT_EQ(t.rows[0][col], "invalid_state");
  EXPECT_EQ(t.rows[1][col], "ok");
}

}  // namespace
