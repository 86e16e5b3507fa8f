// `stiffbench audit` (experiments/studies/audit.hpp): the counting wrapper counts what is called on
// it, deliberately broken methods are each caught by the check that concerns their defect, built-in
// methods pass; and study rows carry the name a method was registered under (one tableau
// registered twice is two rows).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "cli/cli_main.hpp"
#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/studies/audit.hpp"
#include "experiments/studies/convergence.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/imex/imex_ark.hpp"
#include "integrators/implicit/rosenbrock.hpp"
#include "models/problems/kepler.hpp"
#include "tests/experiments/method_file_copy.hpp"

namespace stiffbench {
namespace {

const ButcherTableau& explicit_tableau(const std::string& name) {
  for (const auto& t : explicit_tableaux())
    if (t.name == name) return t;
  throw std::logic_error("no tableau " + name);
}

// An explicit Runge–Kutta method from a tableau that is NOT validated (a user's own stepper with
// a defect in its coefficients): fixed step, and adaptive when it has embedded weights (a plain
// controller on the embedded difference, at most 10,000 steps per call).
class UncheckedRk final : public Integrator {
 public:
  UncheckedRk(std::string name, ButcherTableau t, int claimed_order)
      : Integrator(MethodInfo{std::move(name),
                              Family::explicit_rk,
                              claimed_order,
                              static_cast<int>(t.b.size()),
                              {},
                              "test: unchecked tableau"}),
        t_(std::move(t)) {}
  const ButcherTableau* butcher_tableau() const override { return &t_; }
  bool supports_adaptive() const override { return t_.b_embedded.size() == t_.b.size(); }
  void reset(const OdeSystem& sys, double t0, CVecRef) override {
    k_.resize(sys.dimension(), t_.stages());
    t_now_ = t0;
    h_ = 0.01;
  }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) override {
    stages(sys, t, y, h);
    y += h * k_ * t_.b;
    return Status::ok;
  }
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override {
    const double tol = 1e-6;
    for (long n = 0; t_now_ < t_out; ++n) {
      if (n == 10000) {
        stats.message = "more than 10000 steps";
        return Status::solver_error;
      }
      const double h = std::min(h_, t_out - t_now_);
      stages(sys, t_now_, y, h);
      const double err = (h * k_ * (t_.b - t_.b_embedded)).cwiseAbs().maxCoeff();
      if (err <= tol) {
        y += h * k_ * t_.b;
        t_now_ += h;
        ++stats.steps;
      } else {
        ++stats.error_test_failures;
      }
      const double fac = err == 0 ? 5.0 : 0.9 * std::pow(tol / err, 1.0 / (t_.embedded_order + 1));
      h_ = h * std::clamp(fac, 0.2, 5.0);
    }
    return Status::ok;
  }

 private:
  void stages(const OdeSystem& sys, double t, CVecRef y, double h) {
    for (int i = 0; i < t_.stages(); ++i) {
      Vec yi = y;
      for (int j = 0; j < i; ++j) yi += h * t_.a(i, j) * k_.col(j);
      sys.rhs(t + t_.c[i] * h, yi, k_.col(i));
    }
  }
  ButcherTableau t_;
  Mat k_;
  double t_now_ = 0, h_ = 0.01;
};

// Euler that evaluates f twice per step but reports one evaluation (subtracts the other).
class UnderReportingEuler final : public Integrator {
 public:
  UnderReportingEuler()
      : Integrator(MethodInfo{"test_underreporting_euler",
                              Family::explicit_rk,
                              1,
                              1,
                              {},
                              "test: evaluates f twice, reports once"}) {}
  void reset(const OdeSystem& sys, double, CVecRef) override {
    f_.resize(sys.dimension());
    g_.resize(sys.dimension());
  }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override {
    sys.rhs(t, y, f_);
    sys.rhs(t, y, g_);   // a wasted evaluation...
    stats.f_evals -= 1;  // ...hidden from the counters
    y += h * f_;
    return Status::ok;
  }

 private:
  Vec f_, g_;
};

// Symplectic Euler that evaluates the force on its own copy of the Kepler problem instead of the
// system it is given: the system boundary never sees those evaluations.
class CopyingEuler final : public Integrator {
 public:
  CopyingEuler()
      : Integrator(MethodInfo{"test_copying_euler", Family::symplectic, 1, 1,
                              Requirements{true, true}, "test: evaluates a copy of the system"}),
        copy_(0.5, 1.0, 1.0) {}
  void reset(const OdeSystem& sys, double, CVecRef) override { a_.resize(sys.dimension() / 2); }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override {
    const Index n = y.size() / 2;
    if (n != copy_.dofs()) {  // the copy is a Kepler problem: nothing else runs
      stats.message = "the copy is a Kepler problem";
      return Status::solver_error;
    }
    copy_.acceleration(t, y.head(n), y.tail(n), a_);
    y.tail(n) += h * a_;
    y.head(n) += h * y.tail(n);
    (void)sys;
    return Status::ok;
  }

 private:
  Kepler copy_;
  Vec a_;
};

const AuditRow* find_row(const AuditResult& r, const std::string& integ, const std::string& check,
                         const std::string& system = "") {
  for (const auto& row : r.rows)
    if (row.integrator == integ && row.check == check && (system.empty() || row.system == system))
      return &row;
  return nullptr;
}

std::string fails(const AuditResult& r) {
  std::ostringstream os;
  for (const auto& row : r.rows)
    if (row.status == "fail")
      os << row.integrator << " " << row.check << " " << row.system << ": " << row.claimed << " vs "
         << row.measured << " (" << row.reason << ")\n";
  return os.str();
}

std::filesystem::path scratch(const std::string& what) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("sb_audit_test_" + what + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

// The wrapper counts its own calls: 3 f (two rhs, one acceleration) and 2 Jacobians (one
// analytic, one force-Jacobian pair), and forwards them, so the wrapped Kepler's boundary
// counters see the 3 f and the 1 analytic Jacobian (force_jacobians is not counted by a system,
// by design).
TEST(AuditCountingWrapper, CountsItsOwnCallsAndForwardsTheHooks) {
  Params p;
  p.set("e", "0.5");
  const auto kepler = model_registry().create("kepler", p);
  CallCounts c;
  const auto w = make_counting_system(*kepler, c);
  ASSERT_NE(w->as_mechanical(), nullptr);
  EXPECT_EQ(w->dimension(), 4);
  EXPECT_TRUE(w->has_jacobian());
  EXPECT_TRUE(w->has_exact());
  EXPECT_TRUE(w->autonomous());
  EXPECT_EQ(w->initial_state(), kepler->initial_state());
  const Vec y = w->initial_state();
  Vec f(4), f_inner(4), a(2);
  w->rhs(0.0, y, f);
  w->rhs(0.1, y, f);
  kepler->reset_counters();
  w->as_mechanical()->acceleration(0.0, y.head(2), y.tail(2), a);
  kepler->rhs(0.0, y, f_inner);
  EXPECT_EQ(a, f_inner.tail(2));  // forwarded to the wrapped system
  SparseMat jac, k, d;
  w->jacobian(0.0, y, jac);
  w->as_mechanical()->force_jacobians(0.0, y.head(2), y.tail(2), k, d);
  EXPECT_EQ(c.f, 3);
  EXPECT_EQ(c.jac, 2);
  EXPECT_EQ(w->counters().f_evals, 3);       // the wrapper's own boundary
  EXPECT_EQ(kepler->counters().f_evals, 2);  // one forwarded acceleration + the direct rhs
  EXPECT_EQ(kepler->counters().jac_evals, 1);

  // A first-order system stays first-order.
  const auto dahlquist = model_registry().create("dahlquist", Params{});
  CallCounts c2;
  const auto w2 = make_counting_system(*dahlquist, c2);
  EXPECT_EQ(w2->as_mechanical(), nullptr);
  Vec g(2);
  w2->rhs(0.0, w2->initial_state(), g);
  EXPECT_EQ(c2.f, 1);
}

// Each broken method is caught by the check that concerns its defect (and only the defect's
// checks need to fail); the claims are false by construction:
//   heun with b̂ = (1.01, 0) claims embedded order 1: Σb̂ = 1.01, so the first condition fails by
//     0.01 and on y' = 1 the estimate is 0.01·h: the run needs ~1e4 steps instead of a few;
//   heun claiming order 3: its order-3 conditions fail (bᵀc² = 1/2 ≠ 1/3) and its local error is
//     O(h³), slope 3, not 4;
//   an Euler that evaluates f twice per step but subtracts one: 16 steps are 32 evaluations at
//     the wrapper, 16 reported, and 8 more steps cost 16, not 8 × 1 stage;
//   a symplectic Euler evaluating a copy of Kepler: the system sees 0 evaluations per step,
//   not 1.
TEST(Audit, CatchesEachBrokenMethodForItsReason) {
  ButcherTableau wrong_sum = explicit_tableau("heun");
  wrong_sum.name = "heun_bad_embedded";
  wrong_sum.b_embedded = Vec::Zero(2);
  wrong_sum.b_embedded << 1.01, 0.0;
  wrong_sum.embedded_order = 1;
  ButcherTableau over = explicit_tableau("heun");
  over.name = "heun_claims_3";
  over.order = 3;
  StudyTarget target;
  target.objects.integrators = {
      [wrong_sum] { return std::make_unique<UncheckedRk>("test_wrong_embedded", wrong_sum, 2); },
      [over] { return std::make_unique<UncheckedRk>("test_overclaimed", over, 3); },
      [] { return std::make_unique<UnderReportingEuler>(); },
      [] { return std::make_unique<CopyingEuler>(); }};
  const long failed_before = audit_failed_checks();
  const AuditResult r = audit_study(resolve_inputs(target), {}, scratch("broken"));
  EXPECT_GT(audit_failed_checks(), failed_before);  // the command would exit 3

  auto expect_fail = [&](const std::string& integ, const std::string& check,
                         const std::string& system = "") {
    const AuditRow* row = find_row(r, integ, check, system);
    ASSERT_NE(row, nullptr) << integ << " " << check;
    EXPECT_EQ(row->status, "fail") << integ << " " << check << ": " << row->reason;
  };
  auto expect_ok = [&](const std::string& integ, const std::string& check,
                       const std::string& system = "") {
    const AuditRow* row = find_row(r, integ, check, system);
    ASSERT_NE(row, nullptr) << integ << " " << check;
    EXPECT_EQ(row->status, "ok") << integ << " " << check << ": " << row->reason;
  };
  // Wrong embedded sum: the embedded row's order and the y' = 1 run; the solution is fine.
  expect_fail("test_wrong_embedded", "embedded_order");
  EXPECT_EQ(find_row(r, "test_wrong_embedded", "embedded_order")->measured, "0");
  expect_fail("test_wrong_embedded", "adaptive_constant");
  expect_ok("test_wrong_embedded", "tableau_order");
  expect_ok("test_wrong_embedded", "local_error_slope");
  // Overclaimed order: the tableau's conditions and the slope (3, not 4).
  expect_fail("test_overclaimed", "tableau_order");
  EXPECT_EQ(find_row(r, "test_overclaimed", "tableau_order")->measured, "2");
  expect_fail("test_overclaimed", "local_error_slope");
  const double slope = std::stod(find_row(r, "test_overclaimed", "local_error_slope")->measured);
  EXPECT_NEAR(slope, 3.0, 0.3);
  // Miscounting: reported against the wrapper, and the marginal cost per step.
  expect_fail("test_underreporting_euler", "f_evals_fixed", "scalar_linear");
  EXPECT_EQ(find_row(r, "test_underreporting_euler", "f_evals_fixed", "scalar_linear")->measured,
            "32");
  EXPECT_EQ(find_row(r, "test_underreporting_euler", "f_evals_fixed", "scalar_linear")->claimed,
            "16");
  expect_fail("test_underreporting_euler", "f_per_step", "scalar_linear");
  expect_ok("test_underreporting_euler", "local_error_slope");
  // Evaluating a copy: nothing passes the boundary, which the per-step count sees.
  expect_fail("test_copying_euler", "f_per_step", "kepler(e=0.5)");
  EXPECT_EQ(find_row(r, "test_copying_euler", "f_per_step", "kepler(e=0.5)")->measured, "0");
  // Not a mechanical system: skipped with the reason.
  const AuditRow* skipped = find_row(r, "test_copying_euler", "f_evals", "scalar_linear");
  ASSERT_NE(skipped, nullptr);
  EXPECT_EQ(skipped->status, "skip");
  EXPECT_NE(skipped->reason.find("mechanical"), std::string::npos) << skipped->reason;
}

// Methods that need an additive split (IMEX pairs, operator splitting) are audited on split
// systems, not skipped: the scalar system in halves, Kaps' problem and the cloth with
// split=springs for the counts; rotation_decay, whose parts do not commute, for the local error
// (on Kaps' problem from its initial state f_I vanishes along the solution and Lie and Strang
// looked exact, slopes 5); the monomials in halves for the adaptive exactness; the additive
// order conditions for the claims. Figures:
//   - lie and strang: local error O(h²) and O(h³) (splitting error; Hairer, Lubich & Wanner,
//     GNI §II.5), slopes 2 and 3. On the cloth each step restarts sdirk3 (restart(), not reset():
//     a reset evaluated one force Jacobian per step for its pattern that no counter saw; the
//     wrapper counted 32 calls against 16 reported, this check failed);
//   - ark324l2sa: order 3, embedded order 2 (Kennedy & Carpenter 2003);
//   - ars232's tables (order 2, Ascher, Ruuth & Spiteri 1997) under a claim of order 3: the
//     additive conditions stop at 2 and the local error's slope is 3, not 4.
TEST(Audit, SplitMethodsAreAuditedOnSplitSystems) {
  AdditiveTableau over = *integrator_registry().create("ars232", Params{})->additive_tableau();
  over.name = "test_imex_overclaimed";
  over.order = 3;
  StudyTarget target;
  target.integrators = {"lie", "strang", "ark324l2sa", "imex_ssp2_222"};
  target.objects.integrators = {[over] {
    return std::make_unique<ImexArkIntegrator>(over, "ars232 claiming order 3", ImplicitOptions{});
  }};
  const AuditResult r = audit_study(resolve_inputs(target), {}, scratch("split"));
  for (const auto& name : target.integrators)
    for (const auto& row : r.rows)
      if (row.integrator == name) {
        EXPECT_NE(row.status, "fail") << name << " " << row.check << ": " << row.reason;
      }
  const AuditRow* jac = find_row(r, "lie", "jac_evals_fixed", "cloth(n=8,split=springs)");
  ASSERT_NE(jac, nullptr);
  EXPECT_EQ(jac->status, "ok") << jac->reason;
  EXPECT_EQ(jac->measured, "16");
  EXPECT_NEAR(std::stod(find_row(r, "lie", "local_error_slope", "rotation_decay")->measured), 2.0,
              0.3);
  EXPECT_NEAR(std::stod(find_row(r, "strang", "local_error_slope", "rotation_decay")->measured),
              3.0, 0.3);
  EXPECT_EQ(find_row(r, "ark324l2sa", "tableau_order")->measured, "3");
  EXPECT_EQ(find_row(r, "ark324l2sa", "embedded_order")->measured, "2");
  EXPECT_EQ(find_row(r, "ark324l2sa", "adaptive_constant")->status, "ok");
  EXPECT_EQ(find_row(r, "ark324l2sa", "f_evals_adaptive", "kaps(eps=1e-3)")->status, "ok");

  const AuditRow* order = find_row(r, "test_imex_overclaimed", "tableau_order");
  ASSERT_NE(order, nullptr);
  EXPECT_EQ(order->status, "fail");
  EXPECT_EQ(order->measured, "2");
  const AuditRow* slope = find_row(r, "test_imex_overclaimed", "local_error_slope");
  ASSERT_NE(slope, nullptr);
  EXPECT_EQ(slope->status, "fail");
  EXPECT_NEAR(std::stod(slope->measured), 3.0, 0.3);
}

// Built-in methods of each kind pass every check that applies (the full list runs in CI:
// scripts/test.sh); the files are written.
TEST(Audit, BuiltInMethodsPass) {
  AuditSpec spec;
  spec.integrators = {"rk4", "dopri5", "rkf45", "velocity_verlet", "yoshida4", "rosenbrock2"};
  const auto dir = scratch("builtin");
  const AuditResult r = audit_study(inputs_of(spec), spec, dir);
  EXPECT_EQ(r.count("fail"), 0) << fails(r);
  for (const auto& name : spec.integrators) EXPECT_NE(find_row(r, name, "f_evals_fixed"), nullptr);
  EXPECT_EQ(find_row(r, "dopri5", "fsal")->measured, "yes");
  EXPECT_EQ(find_row(r, "rk4", "f_per_step", "kepler(e=0.5)")->measured, "4");
  EXPECT_EQ(find_row(r, "dopri5", "f_per_step", "cloth(n=8)")->measured, "6");
  // ROS2 claims W-order 2: by hand bᵀα1 = 1/2 and bᵀΓ1 = γ(b1 + b2) + b2·γ21 = γ − γ = 0 (the
  // order-2 W-conditions), and order 2 is its classical order, which bounds the W-order.
  EXPECT_EQ(find_row(r, "rosenbrock2", "tableau_order")->measured, "2");
  EXPECT_EQ(find_row(r, "rosenbrock2", "w_order")->status, "ok");
  EXPECT_EQ(find_row(r, "rosenbrock2", "w_order")->measured, "2");
  EXPECT_TRUE(std::filesystem::exists(dir / "audit.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "audit.md"));
  EXPECT_TRUE(std::filesystem::exists(dir / "audit.json"));
  std::filesystem::remove_all(dir);
}

// Rosenbrock methods get their order, embedded order and (when claimed) W-order checked by the
// conditions of core/theory/method_analysis.hpp (rosenbrock2's, claimed W-order 2, in
// BuiltInMethodsPass). ROS3P's tableau under a claim of W-order 3 fails: by hand bᵀα1 = (2/3)·0 +
// (1/3)·1 = 1/3, not 1/2, and bᵀΓ1 = (2/3)γ + (1/3)(1/2 − 2γ) = 1/6, not 0, so both order-2
// W-conditions fail (the reason names the first in w_trees()' order, W[t], by 1/6) and the
// W-order is 1 (Lang & Verwer's method has order 3 with the exact Jacobian only); its classical
// order 3 passes.
TEST(Audit, RosenbrockWOrderClaimIsChecked) {
  RosenbrockTableau w3 = ros3p_tableau();
  w3.name = "test_ros3p_w3";
  w3.w_order = 3;
  StudyTarget target;
  target.objects.integrators = {[w3] {
    return std::make_unique<Rosenbrock>(w3, "ros3p claiming W-order 3", ImplicitOptions{});
  }};
  const AuditResult r = audit_study(resolve_inputs(target), {}, scratch("rosenbrock"));
  const AuditRow* w = find_row(r, "test_ros3p_w3", "w_order");
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(w->status, "fail");
  EXPECT_EQ(w->measured, "1");
  EXPECT_NE(w->reason.find("W-condition of tree W[t] (order 2) fails by 0.167"), std::string::npos)
      << w->reason;
  EXPECT_EQ(find_row(r, "test_ros3p_w3", "tableau_order")->status, "ok");
  EXPECT_EQ(find_row(r, "test_ros3p_w3", "embedded_order")->measured, "2");
}

// A study's inputs from resolve_inputs: a method file (heun's coefficients under another name)
// and a variant of a built-in method; each row carries its label and both pass.
TEST(Audit, RunsFromResolvedInputsWithAMethodFileAndAVariant) {
  const std::string file = testing_support::renamed_method_file("heun", "test_audit_heun");
  StudyTarget target;
  target.integrators = {file, "bs3{rtol=1e-8}"};
  const AuditResult r = run_audit(resolve_inputs(target), AuditSpec{});
  std::set<std::string> labels;
  for (const auto& row : r.rows) labels.insert(row.integrator);
  EXPECT_EQ(labels, (std::set<std::string>{"test_audit_heun", "bs3{rtol=1e-8}"}));
  EXPECT_EQ(r.count("fail"), 0) << fails(r);
  EXPECT_EQ(find_row(r, "test_audit_heun", "tableau_order")->measured, "2");
  EXPECT_EQ(find_row(r, "bs3{rtol=1e-8}", "adaptive_constant")->status, "ok");
  std::filesystem::remove_all(std::filesystem::path(file).parent_path());
}

int cli(std::vector<std::string> args) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return cli_main(static_cast<int>(argv.size()), argv.data());
}

// The command's exit codes: 0 when every check holds, 3 when one fails (the files are written
// first), 2 for an unknown integrator. The failing method is heun registered with a claimed
// order of 3 (its tableau_order and local_error_slope checks fail, as above).
TEST(Audit, CommandExitsThreeOnAFailedCheck) {
  if (!integrator_registry().find("test_cli_overclaimed")) {
    ButcherTableau over = explicit_tableau("heun");
    over.order = 3;
    IntegratorRegistry::Entry e;
    e.info = MethodInfo{"test_cli_overclaimed", Family::explicit_rk, 3, 2, {}, "heun claiming 3"};
    e.make = [over](const Params&) {
      return std::make_unique<UncheckedRk>("test_cli_overclaimed", over, 3);
    };
    register_integrator(std::move(e));
  }
  const auto dir = scratch("cli");
  EXPECT_EQ(cli({"audit", "--integrators", "rk4", "--out", dir.string()}), 0);
  EXPECT_EQ(
      cli({"audit", "--integrators", "rk4,test_cli_overclaimed", "--out", dir.string(), "--force"}),
      3);
  const std::string csv = [&] {
    std::ifstream in(dir / "audit.csv");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }();
  EXPECT_NE(csv.find("test_cli_overclaimed,tableau_order,heun,3,2,fail"), std::string::npos) << csv;
  EXPECT_EQ(cli({"audit", "--integrators", "rk5", "--out", dir.string(), "--force"}), 2);
  std::filesystem::remove_all(dir);
}

TEST(Audit, RefusesUnknownAndRepeatedNames) {
  AuditSpec spec;
  spec.integrators = {"rk4", "rk4"};
  EXPECT_THROW(spec.validate(), BadInput);
  EXPECT_THROW(run_audit(spec), BadInput);
  spec.integrators = {"rk5"};
  EXPECT_THROW(run_audit(spec), BadInput);  // resolve_inputs names it
}

// Study rows carry the registered name: one tableau (rk4) registered twice under two names is two
// methods with their own rows, not one line with an order fitted across both.
TEST(RegisteredNames, OneTableauTwiceIsTwoRows) {
  for (const std::string name : {"test_rk4_first", "test_rk4_second"}) {
    IntegratorRegistry::Entry e;
    e.info = MethodInfo{name, Family::explicit_rk, 4, 4, {}, "rk4 registered under another name"};
    e.make = [](const Params&) {
      return std::make_unique<ExplicitRungeKutta>(explicit_tableau("rk4"), "rk4 again");
    };
    if (!integrator_registry().find(name)) register_integrator(std::move(e));
  }
  EXPECT_EQ(integrator_registry().create("test_rk4_first", Params{})->info().name,
            "test_rk4_first");
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"test_rk4_first", "test_rk4_second"};
  spec.h = 0.1;
  spec.levels = 3;
  const ConvergenceResult r = run_local_error(spec, nullptr);
  std::set<std::string> names;
  for (const auto& row : r.rows) names.insert(row.integrator);
  EXPECT_EQ(names, (std::set<std::string>{"test_rk4_first", "test_rk4_second"}));
  EXPECT_EQ(r.rows.size(), 6u);  // 3 levels each
}

}  // namespace
}  // namespace stiffbench
