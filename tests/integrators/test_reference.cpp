// The library references (SUNDIALS CVODE/ARKODE, GSL odeiv2) run through the testbed's own
// systems, drivers and statistics.
#include <gtest/gtest.h>

#include "integrators/reference/sundials.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "core/driver.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/convergence.hpp"
#include "experiments/studies/work_precision.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

std::vector<std::string> references() {
  std::vector<std::string> out;
  for (const auto& e : integrator_registry().entries())
    // arkode_mri needs a split and runs fixed-step only (tests/integrators/test_arkode_split.cpp).
    if (e.info.family == Family::reference && !e.info.requires_.split) out.push_back(e.info.name);
  return out;
}

class ReferenceTest : public ::testing::TestWithParam<std::string> {};

// Adaptive mode at rtol = 1e-8, atol = 1e-10: the global error of a well-behaved code stays
// within a modest multiple of the local tolerance; the required bound is 100×
// (atol + rtol·max|y|) on problems with exact solutions. The global error grows with the
// interval (gsl_rk2imp reaches 1.03e-6 on the oscillator at t = 5, measured), so the check
// is at t = 2: |λ|t ≈ 6 for the Dahlquist problem, a third of an oscillator period.
TEST_P(ReferenceTest, AdaptiveErrorWithin100TimesTolerance) {
  const double rtol = 1e-8, atol = 1e-10;
  for (const auto& [m, params] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"dahlquist", {"lambda_re=-1", "lambda_im=3"}}, {"harmonic_oscillator", {}}}) {
    auto sys = model(m, params);
    auto integ = make(GetParam(), {"rtol=1e-8", "atol=1e-10"});
    const RunResult r = run_adaptive(*sys, *integ, {2.0, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << m << ": " << r.stats.message;
    Vec ye(sys->dimension());
    sys->exact(2.0, ye);
    const double bound = 100 * (atol + rtol * std::max(1.0, ye.cwiseAbs().maxCoeff()));
    EXPECT_LT(max_abs_diff(r.y, ye), bound) << m;
    EXPECT_GT(r.stats.steps, 0) << m;
  }
}

INSTANTIATE_TEST_SUITE_P(All, ReferenceTest, ::testing::ValuesIn(references()),
                         [](const auto& param_info) { return param_info.param; });

// SUNDIALS counts its own f evaluations; the testbed counts them at the system boundary. With
// the library's difference-quotient Jacobian (NumLinRhsEvals) and the IMEX parts added, the
// two agree exactly.
TEST(ReferenceCounts, SundialsCountsAgreeWithTheBoundary) {
  struct Case {
    std::string integ, model;
    std::vector<std::string> params;
  };
  for (const Case& c :
       std::vector<Case>{{"cvode_bdf", "kepler", {}},
                         {"cvode_bdf", "kepler", {"jacobian=dq"}},
                         {"cvode_adams", "kepler", {"linear_solver=spgmr", "jacobian=dq"}},
                         {"cvode_bdf", "kepler", {"linear_solver=klu"}},
                         {"arkode_erk", "kepler", {}},
                         {"arkode_dirk", "kepler", {"jacobian=dq"}},
                         {"arkode_imex", "prothero_robinson", {"lambda=-100"}}}) {
    auto sys =
        model(c.model, c.model == "prothero_robinson" ? c.params : std::vector<std::string>{});
    auto integ =
        make(c.integ, c.model == "prothero_robinson" ? std::vector<std::string>{} : c.params);
    const RunResult r = run_adaptive(*sys, *integ, {2.0, 4});
    ASSERT_EQ(r.stats.status, Status::ok) << c.integ << ": " << r.stats.message;
    EXPECT_EQ(r.stats.library_f_evals, r.stats.f_evals) << c.integ << " " << c.params.size();
    EXPECT_FALSE(r.stats.library_report.empty());
  }
}

// Fixed-step mode: observed orders of the references whose order is fixed (ARKODE with a fixed
// step, GSL's bare Runge–Kutta steppers). ARKODE's Newton tolerance follows rtol, so implicit
// tables run at rtol = 1e-13. Step sizes keep the finest error above round-off. gsl_rk8pd is
// left out: between its pre-asymptotic range and round-off there is no pair of steps that
// resolves order 8 in double precision (measured on the oscillator: 8.70, 8.88, 8.59, then
// round-off at 4e-15; on e = 0.5 Kepler: 6.28, 7.56, then round-off).
TEST(ReferenceFixedStep, ObservedOrders) {
  struct Case {
    std::string name;
    int order;
    double h;
  };
  for (const Case& c : std::vector<Case>{{"arkode_erk", 5, 0.2},
                                         {"arkode_dirk", 4, 0.2},
                                         {"arkode_imex", 4, 0.2},
                                         {"gsl_rk4", 4, 0.2},
                                         {"gsl_rkf45", 5, 0.2},
                                         {"gsl_rkck", 5, 0.2},
                                         {"gsl_rk2imp", 2, 0.2},
                                         {"gsl_rk4imp", 4, 0.2}}) {
    ConvergenceSpec spec;
    spec.model = "harmonic_oscillator";
    spec.integrators = {c.name};
    spec.params = Params::from_assignments({"rtol=1e-13", "atol=1e-15"});
    spec.t_end = 10;
    spec.h = c.h;
    spec.levels = 4;
    const auto res = run_convergence(spec, nullptr);
    const auto p = last_observed_order(res.rows, c.name);
    ASSERT_TRUE(p.has_value()) << c.name;
    EXPECT_NEAR(*p, c.order, 0.2) << c.name;
    EXPECT_EQ(integrator_registry().at(c.name).info.order, c.order) << c.name;
  }
}

TEST(ReferenceFixedStep, AdaptiveOnlyMethodsAreRefusedInStepStudies) {
  for (const auto& name : {"cvode_bdf", "cvode_adams", "gsl_msbdf", "gsl_msadams", "gsl_bsimp"}) {
    ConvergenceSpec spec;
    spec.model = "harmonic_oscillator";
    spec.integrators = {name};
    spec.t_end = 1;
    spec.h = 0.1;
    spec.levels = 2;
    EXPECT_THROW(run_convergence(spec, nullptr), BadInput) << name;
  }
}

// The same CVODE run with dense, band, KLU (sparse) and SPGMR (matrix-free) linear solvers:
// the linear solver changes only how Newton's systems are solved, so at rtol = 1e-10 the
// solutions agree to ~1e-8 (the tolerance-driven step sequences differ slightly).
// On the mass-spring cloth when that model is registered, otherwise on HIRES.
// `velocity` (flexible GMRES preconditioned by the velocity-form solve) joins them on the cloth.
TEST(ReferenceLinearSolvers, CvodeDenseBandKluSpgmrAgreeOnCloth) {
  const bool cloth = model_registry().find("cloth") != nullptr;
  auto sys = cloth ? model("cloth", {"n=5"}) : model("hires");
  Vec ref;
  for (const auto& ls : {"dense", "band", "klu", "spgmr", "velocity"}) {
    auto integ =
        make("cvode_bdf", {"rtol=1e-10", "atol=1e-12", std::string("linear_solver=") + ls});
    const RunResult r = run_adaptive(*sys, *integ, {0.5, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << ls << ": " << r.stats.message;
    if (ref.size() == 0) {
      ref = r.y;
    } else {
      EXPECT_LT(max_abs_diff(r.y, ref), 1e-8) << ls;
    }
    if (std::string(ls) == "spgmr") {
      EXPECT_GT(r.stats.linear_iters, 0);
    }
  }
}

// linear_solver=auto: dense up to kSundialsAutoDenseMax (100) unknowns; above, velocity for
// mechanical models with force Jacobians, KLU for other analytic sparse Jacobians, SPGMR without
// one. A run on a model the velocity solver does not apply to is refused naming the parameter.
TEST(ReferenceLinearSolvers, AutoChoiceBySizeAndStructure) {
  const Index lim = kSundialsAutoDenseMax;
  EXPECT_EQ(lim, 100);
  EXPECT_EQ(sundials_auto_linear_solver(lim, true, true).solver, "dense");
  EXPECT_EQ(sundials_auto_linear_solver(lim, false, false).solver, "dense");
  EXPECT_EQ(sundials_auto_linear_solver(lim + 1, true, true).solver, "velocity");
  EXPECT_EQ(sundials_auto_linear_solver(lim + 1, true, false).solver, "klu");
  EXPECT_EQ(sundials_auto_linear_solver(lim + 1, false, false).solver, "spgmr");
  EXPECT_EQ(sundials_auto_linear_solver(24576, true, false).rule,
            "24576 unknowns > 100 and an analytic sparse Jacobian");
  auto hires = model("hires");
  auto integ = make("cvode_bdf", {"linear_solver=velocity"});
  EXPECT_THROW(run_adaptive(*hires, *integ, {1.0, 0}), BadInput);
}

// The resolved choice reaches the run and its report (the first line of the library
// statistics): HIRES (8 unknowns) dense; cloth n = 5 (150 unknowns, force Jacobians) velocity,
// or SPGMR when its Jacobian is switched off with jacobian=dq; the same for an ARKODE method.
TEST(ReferenceLinearSolvers, AutoChoiceIsReported) {
  struct Case {
    std::string integ, model;
    std::vector<std::string> model_params, params;
    std::string expect;
  };
  for (const Case& c : std::vector<Case>{
           {"cvode_bdf", "hires", {}, {}, "dense (linear_solver=auto: 8 unknowns <= 100)"},
           {"cvode_bdf",
            "cloth",
            {"n=5"},
            {},
            "velocity (linear_solver=auto: 150 unknowns > 100 and a mechanical model with force "
            "Jacobians)"},
           {"cvode_bdf",
            "cloth",
            {"n=5"},
            {"jacobian=dq"},
            "spgmr (linear_solver=auto: 150 unknowns > 100 and no analytic Jacobian)"},
           {"arkode_dirk",
            "cloth",
            {"n=5"},
            {"jacobian=dq"},
            "spgmr (linear_solver=auto: 150 unknowns > 100 and no analytic Jacobian)"},
           {"cvode_bdf", "cloth", {"n=5"}, {"linear_solver=klu"}, "klu (linear_solver=klu)"}}) {
    auto sys = model(c.model, c.model_params);
    auto integ = make(c.integ, c.params);
    const RunResult r = run_adaptive(*sys, *integ, {0.05, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << c.integ << " " << c.model << ": " << r.stats.message;
    const std::string first = r.stats.library_report.substr(0, r.stats.library_report.find('\n'));
    EXPECT_NE(first.find("Linear solver"), std::string::npos) << first;
    EXPECT_NE(first.find("= " + c.expect), std::string::npos) << first;
  }
}

// Library counter from CVODE's own statistics table ("Jac fn evals = N").
long library_counter(const std::string& report, const std::string& name) {
  const auto at = report.find(name);
  if (at == std::string::npos) return -1;
  return std::stol(report.substr(report.find('=', at) + 1));
}

// The matrix solvers on a MechanicalSystem fill J = [[0, I], [K, D]] from force_jacobians()
// into the pattern fixed at reset() (diagonal included) and count each call themselves, since
// force_jacobians() is not counted at the system boundary: the testbed's jac_evals must equal
// CVODE's own count of Jacobian calls exactly. KLU then agrees with dense on a 6 x 6 cloth to
// the accuracy of the tolerance (rtol = 1e-9 on positions of order 1; the step sequences
// differ, measured 1.2e-9 apart, bound 2e-8) while taking its Jacobian values only through
// the index maps; band does the same arithmetic as dense.
TEST(ReferenceLinearSolvers, MechanicalJacobianCountsAndKluMatchesDense) {
  auto sys = model("cloth", {"n=6"});
  Vec ref;
  for (const auto& ls : {"dense", "klu", "band"}) {
    auto integ = make("cvode_bdf", {"rtol=1e-9", "atol=1e-11", std::string("linear_solver=") + ls});
    const RunResult r = run_adaptive(*sys, *integ, {0.3, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << ls << ": " << r.stats.message;
    const long nje = library_counter(r.stats.library_report, "Jac fn evals");
    EXPECT_GT(nje, 0) << ls;
    EXPECT_EQ(r.stats.jac_evals, nje) << ls;
    if (ref.size() == 0)
      ref = r.y;
    else
      EXPECT_LT(max_abs_diff(r.y, ref), 2e-8) << ls;
  }
  // A first-order model goes through OdeSystem::jacobian(), counted at the boundary: the
  // same equality holds with the other route.
  auto hires = model("hires");
  auto integ = make("cvode_bdf", {"linear_solver=klu"});
  const RunResult r = run_adaptive(*hires, *integ, {321.8122, 0});
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_EQ(r.stats.jac_evals, library_counter(r.stats.library_report, "Jac fn evals"));
}

// Robertson's three concentrations sum to 1 for all time (the rates cancel in the sum); CVODE
// at rtol = 1e-8 keeps the sum to 1e-10 up to t = 1e11 (any linear multistep method preserves
// linear invariants up to the Newton and round-off errors).
// The number after "LABEL = " in a library's PrintAllStats table (SUN_OUTPUTFORMAT_TABLE), or -1.
long library_stat(const std::string& report, const std::string& label) {
  const std::string key = "\n" + label + " ";
  const auto at = ("\n" + report).find(key);
  if (at == std::string::npos) return -1;
  const auto eq = report.find('=', at);
  return eq == std::string::npos ? -1 : std::stol(report.substr(eq + 1));
}

// The SUNDIALS counters map into SolveStats: on HIRES (stiff) each solver counter
// equals the library's own figure as its PrintAllStats table prints it (read independently of
// the CVodeGet*/ARKStepGet* calls the mapping makes). By construction of a modified Newton
// iteration with a direct (dense) solver: at least one Newton iteration per step, one linear
// solve per Newton iteration, and at most one matrix set-up per Newton iteration (set-ups are
// skipped while the old matrix still converges), so 0 < linear_setups <= newton_iters; a dense
// solver makes no Krylov iterations.
TEST(ReferenceCounts, SundialsSolverCountersAreTheLibrarys) {
  for (const std::string name : {"cvode_bdf", "arkode_dirk"}) {
    auto sys = model("hires");
    auto integ = make(name, {"rtol=1e-6", "atol=1e-9"});
    const RunResult r = run_adaptive(*sys, *integ, {321.8122, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << name << ": " << r.stats.message;
    const SolveStats& s = r.stats;
    const std::string& lib = s.library_report;
    EXPECT_EQ(s.steps, library_stat(lib, "Steps")) << name;
    EXPECT_EQ(s.error_test_failures, library_stat(lib, "Error test fails")) << name;
    EXPECT_EQ(s.newton_iters, library_stat(lib, "NLS iters")) << name;
    EXPECT_EQ(s.newton_conv_failures, library_stat(lib, "NLS fails")) << name;
    EXPECT_EQ(s.linear_setups, library_stat(lib, "LS setups")) << name;
    EXPECT_EQ(s.linear_iters, library_stat(lib, "LS iters")) << name;
    EXPECT_GE(s.newton_iters, s.steps) << name;
    EXPECT_GT(s.linear_setups, 0) << name;
    EXPECT_LE(s.linear_setups, s.newton_iters) << name;
    EXPECT_EQ(s.lin_solves, s.newton_iters) << name;
    EXPECT_EQ(s.linear_iters, 0) << name;
    EXPECT_GT(s.error_test_failures, 0) << name;  // HIRES's transients reject some steps
  }
  // With GMRES the linear iterations are counted, one or more per Newton iteration.
  auto sys = model("hires");
  auto integ = make("cvode_bdf", {"rtol=1e-6", "atol=1e-9", "linear_solver=spgmr"});
  const RunResult r = run_adaptive(*sys, *integ, {321.8122, 0});
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_EQ(r.stats.linear_iters, library_stat(r.stats.library_report, "LS iters"));
  EXPECT_GE(r.stats.linear_iters, r.stats.newton_iters);
}

// An explicit method solves no equations: every solver counter is 0 (ARKODE's explicit mode and
// GSL's explicit pairs), while the pericentre passages of an eccentric Kepler orbit make the
// error test reject steps. GSL's rejected steps come from its evolve object (computed steps
// minus the accepted ones): rkf45 computes 6 stages per attempted step, the first from the
// previous step's end derivative, plus one f(t0, y0) at the start, so
// f_evals = 1 + 6·(accepted + rejected) exactly when the split is right.
TEST(ReferenceCounts, ExplicitReferencesSolveNothingAndCountRejections) {
  auto sys = model("kepler", {"e=0.9"});
  for (const std::string name : {"arkode_erk", "gsl_rkf45"}) {
    auto integ = make(name, {"rtol=1e-6", "atol=1e-9"});
    const RunResult r = run_adaptive(*sys, *integ, {20.0, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << name << ": " << r.stats.message;
    EXPECT_EQ(r.stats.newton_iters, 0) << name;
    EXPECT_EQ(r.stats.newton_conv_failures, 0) << name;
    EXPECT_EQ(r.stats.linear_setups, 0) << name;
    EXPECT_EQ(r.stats.linear_iters, 0) << name;
    EXPECT_EQ(r.stats.lin_solves, 0) << name;
    EXPECT_GT(r.stats.error_test_failures, 0) << name;
    if (name == "gsl_rkf45") {
      EXPECT_EQ(r.stats.f_evals, 1 + 6 * (r.stats.steps + r.stats.error_test_failures));
    }
  }
}

TEST(ReferenceStiff, RobertsonMassConservedByCvode) {
  auto sys = model("robertson");
  auto integ = make("cvode_bdf", {"rtol=1e-8", "atol=1e-14"});
  double worst = 0;
  const RunResult r = run_adaptive(*sys, *integ, {1e11, 22}, [&](double, CVecRef y) {
    worst = std::max(worst, std::abs(y.sum() - 1.0));
  });
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_LT(worst, 1e-10);
}

// A run the library cannot finish (10 internal steps to cover t = 100) ends with status
// solver_error and the library's own flag name; the next rows of the sweep still run.
TEST(ReferenceErrors, ImpossibleRunIsSolverErrorAndTheSweepGoesOn) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"cvode_bdf", "sdirk3"};
  spec.params = Params::from_assignments({"max_steps=10"});
  spec.t_end = 100;
  spec.h = 0.5;
  spec.levels = 2;
  spec.tol_levels = 2;
  spec.repeats = 1;
  const auto res = run_work_precision(spec, nullptr);
  ASSERT_EQ(res.rows.size(), 4u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(res.rows[i].stats.status, Status::solver_error);
    EXPECT_NE(res.rows[i].stats.message.find("CV_TOO_MUCH_WORK"), std::string::npos)
        << res.rows[i].stats.message;
  }
  for (int i = 2; i < 4; ++i) EXPECT_EQ(res.rows[i].stats.status, Status::ok);
}

class NanAfter final : public OdeSystem {
 public:
  std::string name() const override { return "nan_after"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef d) const override {
    d[0] = t > 0.5 ? std::numeric_limits<double>::quiet_NaN() : -y[0];
  }
};

// A right-hand side that turns non-finite is a library error, not an abort: GSL reports it
// (GSL_EBADFUNC) and CVODE gives up after its recoverable-error retries.
TEST(ReferenceErrors, NonFiniteRightHandSideIsReported) {
  NanAfter sys;
  for (const auto& name : {"gsl_rkf45", "gsl_msbdf", "cvode_bdf", "arkode_erk"}) {
    auto integ = make(name);
    const RunResult r = run_adaptive(sys, *integ, {1.0, 0});
    EXPECT_EQ(r.stats.status, Status::solver_error) << name;
    EXPECT_FALSE(r.stats.message.empty()) << name;
  }
}

// GSL keeps no count of its factorisations, linear solves or Newton iterations. The steppers
// that take a Jacobian do that work (GSL's sources: rk2imp, rk4imp and msbdf iterate a modified
// Newton method, bsimp solves linear systems without iterating), so their counters must read
// "not reported", never a 0 that a table or a linear_solves profile would take as free; the
// explicit steppers and msadams (functional iteration) make none and report a true 0. The check
// is a run each, so the values are what a study's CSV gets.
TEST(ReferenceCounters, GslWorkItDoesNotCountIsNotReportedNotZero) {
  auto sys = model("prothero_robinson", {"lambda=-1e4"});
  for (const std::string name :
       {"gsl_rk2imp", "gsl_rk4imp", "gsl_msbdf", "gsl_bsimp", "gsl_rkf45", "gsl_msadams"}) {
    auto integ = make(name);
    const RunResult r = run_adaptive(*sys, *integ, {1.0, 0});
    ASSERT_EQ(r.stats.status, Status::ok) << name;
    EXPECT_GT(r.stats.f_evals, 0) << name;
    const bool jacobian = name != "gsl_rkf45" && name != "gsl_msadams";
    const bool newton = jacobian && name != "gsl_bsimp";
    EXPECT_EQ(r.stats.lin_solves, jacobian ? SolveStats::kNotReported : 0) << name;
    EXPECT_EQ(r.stats.linear_setups, jacobian ? SolveStats::kNotReported : 0) << name;
    EXPECT_EQ(r.stats.newton_iters, newton ? SolveStats::kNotReported : 0) << name;
    EXPECT_EQ(r.stats.linear_iters, 0) << name;
    // In the CSVs an unreported count is an empty field.
    const auto names = SolveStats::field_names();
    const auto values = r.stats.field_values();
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == "lin_solves") {
        EXPECT_EQ(values[i].empty(), jacobian) << name;
      }
    }
  }
}

// Work-precision on an exact problem: every method's error falls as its work rises.
TEST(WorkPrecision, ErrorFallsAsWorkRisesOnProtheroRobinson) {
  WorkPrecisionSpec spec;
  spec.model = "prothero_robinson";
  spec.params = Params::from_assignments({"lambda=-1e4"});
  spec.integrators = {"cvode_bdf", "gsl_msbdf", "sdirk3", "bdf2"};
  spec.t_end = 2;
  spec.h = 0.02;
  spec.levels = 4;
  spec.tol_levels = 5;
  spec.repeats = 1;
  const auto res = run_work_precision(spec, nullptr);
  EXPECT_EQ(res.reference_description, "exact");
  for (std::size_t i = 1; i < res.rows.size(); ++i) {
    const auto& a = res.rows[i - 1];
    const auto& b = res.rows[i];
    ASSERT_EQ(b.stats.status, Status::ok) << b.integrator << " " << b.setting;
    if (a.integrator != b.integrator) continue;
    EXPECT_GT(b.stats.f_evals, a.stats.f_evals) << b.integrator << " " << b.setting;
    EXPECT_LT(b.error, a.error) << b.integrator << " " << b.setting;
  }
}

}  // namespace
}  // namespace stiffbench
