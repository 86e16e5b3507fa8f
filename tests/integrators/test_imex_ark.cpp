// Additive (IMEX) Runge–Kutta methods of kind imex_ark (integrators/imex/imex_ark.hpp) and the
// coupling order conditions (core/theory/additive_conditions.hpp). Expected values come from theory
// (order conditions of bi-coloured trees, the count of distinct conditions, classical orders,
// evaluation counts derived in the header), from an independent source (ARKODE's tables) or from
// the exact solution of the test system below.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

// After <cstdio>: ARKODE's C headers use FILE without including it.
#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>

#include "core/driver.hpp"
#include "core/theory/additive_conditions.hpp"
#include "integrators/embedded_methods.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/imex/imex_ark.hpp"
#include "integrators/method_file.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;

// A split test system with an exact solution, non-autonomous in both parts:
//   Kaps' problem  y1' = -2 y1 + (y2² - y1)/ε,  y2' = y1 - y2 - y2²   (y1 = e^(-2t), y2 = e^(-t)),
//   and            y3' = (cos t - 1) y3                                 (y3 = e^(sin t - t)),
// split f_I = [(y2² - y1)/ε, 0, -y3 + sin 2t], f_E = [-2 y1, y1 - y2 - y2², cos(t) y3 - sin 2t]
// (parts = both), or with all of f in one part (implicit_only: f_E ≡ 0; explicit_only: f_I ≡ 0).
enum class Parts { both, implicit_only, explicit_only };

class SplitTestSystem final : public OdeSystem {
 public:
  SplitTestSystem(double eps, Parts parts, bool analytic_ji = true)
      : eps_(eps), parts_(parts), analytic_ji_(analytic_ji) {}
  std::string name() const override { return "split_test"; }
  Index dimension() const override { return 3; }
  Vec initial_state() const override { return Vec::Ones(3); }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    y << std::exp(-2 * t), std::exp(-t), std::exp(std::sin(t) - t);
  }
  bool has_imex_split() const override { return true; }
  bool has_implicit_part_jacobian() const override { return analytic_ji_; }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef f) const override {
    f << -2 * y[0] + (y[1] * y[1] - y[0]) / eps_, y[0] - y[1] - y[1] * y[1],
        (std::cos(t) - 1) * y[2];
  }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef f) const override {
    if (parts_ == Parts::implicit_only) return eval_rhs(t, y, f);
    if (parts_ == Parts::explicit_only) {
      f.setZero();
      return;
    }
    f << (y[1] * y[1] - y[0]) / eps_, 0.0, -y[2] + std::sin(2 * t);
  }
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef f) const override {
    if (parts_ == Parts::explicit_only) return eval_rhs(t, y, f);
    if (parts_ == Parts::implicit_only) {
      f.setZero();
      return;
    }
    f << -2 * y[0], y[0] - y[1] - y[1] * y[1], std::cos(t) * y[2] - std::sin(2 * t);
  }
  void eval_jacobian(double t, CVecRef y, SparseMat& j) const override {
    fill(j, {-2 - 1 / eps_, 2 * y[1] / eps_, 0, 1, -1 - 2 * y[1], 0, 0, 0, std::cos(t) - 1});
  }
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& j) const override {
    if (parts_ == Parts::implicit_only) return eval_jacobian(t, y, j);
    if (parts_ == Parts::explicit_only) return fill(j, {0, 0, 0, 0, 0, 0, 0, 0, 0});
    fill(j, {-1 / eps_, 2 * y[1] / eps_, 0, 0, 0, 0, 0, 0, -1});
  }

 private:
  // A dense 3×3 pattern, so that the pattern never changes.
  static void fill(SparseMat& j, std::initializer_list<double> v) {
    std::vector<Eigen::Triplet<double>> t;
    int k = 0;
    for (double x : v) {
      t.emplace_back(k / 3, k % 3, x);
      ++k;
    }
    j.resize(3, 3);
    j.setFromTriplets(t.begin(), t.end());
  }
  double eps_;
  Parts parts_;
  bool analytic_ji_;
};

const std::vector<std::string> kMethods = {"imex_euler", "ars232",     "ars443",
                                           "ark324l2sa", "ark436l2sa", "imex_ssp2_222"};

std::vector<const MethodDefinition*> imex_files() {
  std::vector<const MethodDefinition*> out;
  for (const MethodDefinition& m : built_in_methods())
    if (m.kind == MethodKind::imex_ark) out.push_back(&m);
  return out;
}

std::string file_text(const std::string& file) {
  for (const auto& [name, text] : embedded_method_files())
    if (name == file) return std::string(text);
  throw std::logic_error("no method file " + file);
}

// Max-norm error at t = 1 of N fixed steps.
double error_after(const std::string& method, const OdeSystem& sys, int n,
                   const std::vector<std::string>& params = {}) {
  auto integ = make(method, params);
  Vec y = sys.initial_state();
  integ->reset(sys, 0.0, y);
  SolveStats stats;
  const double h = 1.0 / n;
  for (int k = 0; k < n; ++k) {
    const Status st = integ->step(sys, k * h, y, h, stats);
    if (st != Status::ok) throw std::runtime_error(method + ": " + stats.message);
  }
  Vec exact(3);
  sys.exact(1.0, exact);
  return (y - exact).lpNorm<Eigen::Infinity>();
}

TEST(ImexArk, ShippedMethodsAreRegisteredAsImex) {
  ASSERT_EQ(imex_files().size(), kMethods.size());
  for (const std::string& name : kMethods) {
    SCOPED_TRACE(name);
    auto integ = make(name);
    EXPECT_EQ(integ->info().family, Family::imex);
    EXPECT_TRUE(integ->info().requires_.split);
    ASSERT_NE(integ->additive_tableau(), nullptr);
    EXPECT_EQ(integ->info().stages, integ->additive_tableau()->stages());
    EXPECT_FALSE(integ->linear_stability().has_value());
    EXPECT_TRUE(integ->explicit_part_stability().has_value());
  }
}

// The claimed order is the highest order whose conditions (both tables' own and the coupling
// ones, bi-coloured trees up to order 5) all hold; likewise the embedded order.
TEST(ImexArk, ClaimedOrdersAreTheHighestSatisfied) {
  for (const MethodDefinition* m : imex_files()) {
    SCOPED_TRACE(m->name);
    const AdditiveTableau& t = m->additive;
    EXPECT_EQ(additive_satisfied_order(t.explicit_table, t.implicit_table, t.explicit_table.b,
                                       t.implicit_table.b, 5),
              m->order);
    if (t.has_embedded()) {
      EXPECT_EQ(
          additive_satisfied_order(t.explicit_table, t.implicit_table, t.explicit_table.b_embedded,
                                   t.implicit_table.b_embedded, 5),
          t.embedded_order);
    }
  }
}

// With shared nodes a leaf below the root gives c whatever its colour, so the distinct conditions
// up to order 4 are 2 + 2 + 6 + 18 = 28 (order 3: root colour × {c², AE·c, AI·c}; order 4:
// 2 × (c³, c*(Aν·c) ×2, Aν·c² ×2, Aν·Aμ·c ×4)), 16 of them one table's own (1 + 1 + 2 + 4 per
// table) and 12 coupling conditions (2 of order 3, 10 of order 4). With different nodes
// (imex_ssp2_222) order 2 has 2 × 2 conditions bν·cμ.
TEST(AdditiveConditions, CountOfDistinctConditions) {
  const AdditiveTableau& t = built_in_method("ark436l2sa").additive;
  const auto c = additive_order_conditions(t.explicit_table, t.implicit_table, t.explicit_table.b,
                                           t.implicit_table.b, 4, "b");
  EXPECT_EQ(c.size(), 28u);
  EXPECT_EQ(std::count_if(c.begin(), c.end(), [](const auto& x) { return x.coupling; }), 12);
  const AdditiveTableau& s = built_in_method("imex_ssp2_222").additive;
  EXPECT_EQ(additive_order_conditions(s.explicit_table, s.implicit_table, s.explicit_table.b,
                                      s.implicit_table.b, 2, "b")
                .size(),
            6u);
}

// A hand computation: explicit Heun (c^E = 0, 1; b = 1/2, 1/2) with an implicit table of nodes
// c^I = 1/3, 1 and weights 3/4, 1/4 — each table is of order 2 on its own (bI·cI = 1/4 + 1/4 =
// 1/2), but the coupling condition bE·cI = (1/3 + 1)/2 = 2/3 misses 1/2 by 1/6.
TEST(ImexArkFile, CouplingConditionNamed) {
  const std::string text = R"(name = "bad_pair"
kind = "imex_ark"
order = 2
description = "test"
[explicit]
A = [[0, 0], [1, 0]]
b = ["1/2", "1/2"]
c = [0, 1]
[implicit]
A = [["1/3", 0], ["1/2", "1/2"]]
b = ["3/4", "1/4"]
c = ["1/3", 1]
)";
  try {
    parse_method_file(text, "bad_pair.toml");
    FAIL() << "accepted";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("coupling condition bE·cI = 1/2 (order 2) has residual "
                                         "0.166667"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("bad_pair.toml:3"), std::string::npos) << e.what();
  }
}

// A perturbed coefficient of a shipped file is refused with the condition it breaks: the last
// explicit weight of ark436l2sa 1/4 -> 1/4 + 1e-6 breaks Σ bE = 1 (residual 1e-6).
TEST(ImexArkFile, PerturbedShippedFileRefused) {
  std::string text = file_text("ark436l2sa.toml");
  const std::string row =
      R"(b = ["82889/524892", 0, "15625/83664", "69875/102672", "-2260/8211", "1/4"])";
  const auto at = text.find(row);
  ASSERT_NE(at, std::string::npos);
  text.replace(
      at, row.size(),
      R"(b = ["82889/524892", 0, "15625/83664", "69875/102672", "-2260/8211", "1/4 + 1e-6"])");
  try {
    parse_method_file(text, "ark.toml");
    FAIL() << "accepted";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("the explicit table alone: order 4 claimed but the "
                                         "condition of tree t (order 1) has residual 1e-06"),
              std::string::npos)
        << e.what();
  }
}

TEST(ImexArkFile, ShapeAndNodeDefects) {
  const std::string head = "name = \"x\"\nkind = \"imex_ark\"\norder = 1\ndescription = \"d\"\n";
  const auto refused = [&](const std::string& body, const std::string& what) {
    try {
      parse_method_file(head + body, "x.toml");
      ADD_FAILURE() << "accepted: " << body;
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused(
      "[explicit]\nA = [[0, 1], [1, 0]]\nb = [1, 0]\n[implicit]\nA = [[0, 0], [0, 1]]\nb = [0, "
      "1]\n",
      "key 'explicit.A'");
  refused(
      "c = [0, 1]\n[explicit]\nA = [[0, 0], [1, 0]]\nb = [1, 0]\n[implicit]\nA = [[0, 0], "
      "[\"1/2\", \"1/4\"]]\nb = [0, 1]\n",
      "is not the row sum of the implicit table's A");
  refused("[explicit]\nA = [[0, 0], [1, 0]]\nb = [1, 0]\n[implicit]\nA = [[1]]\nb = [1]\n",
          "the explicit table has 2 stages");
  refused(
      "[explicit]\nA = [[0, 0], [1, 0]]\nb = [1, 0]\nd = 3\n[implicit]\nA = [[0, 0], [0, "
      "1]]\nb = [0, 1]\n",
      "unknown key 'explicit.d'");
}

// ark436l2sa and ark324l2sa: every coefficient agrees with ARKODE's tables (SUNDIALS 6.4:
// ARK436L2SA_ERK_6_3_4 / _DIRK_6_3_4, ARK324L2SA_ERK_4_2_3 / _DIRK_4_2_3) to rounding, and the
// implicit table of ark436l2sa is esdirk43's exactly.
TEST(ImexArk, TablesAgreeWithArkode) {
  struct Pair {
    std::string name;
    ARKODE_ERKTableID erk;
    ARKODE_DIRKTableID dirk;
  };
  for (const Pair& p :
       {Pair{"ark436l2sa", ARKODE_ARK436L2SA_ERK_6_3_4, ARKODE_ARK436L2SA_DIRK_6_3_4},
        Pair{"ark324l2sa", ARKODE_ARK324L2SA_ERK_4_2_3, ARKODE_ARK324L2SA_DIRK_4_2_3}}) {
    SCOPED_TRACE(p.name);
    const AdditiveTableau& t = built_in_method(p.name).additive;
    for (const auto& [ark, tab] :
         {std::pair{ARKodeButcherTable_LoadERK(p.erk), &t.explicit_table},
          std::pair{ARKodeButcherTable_LoadDIRK(p.dirk), &t.implicit_table}}) {
      ASSERT_NE(ark, nullptr);
      ASSERT_EQ(ark->stages, tab->stages());
      double worst = 0.0;
      for (int i = 0; i < ark->stages; ++i) {
        for (int j = 0; j < ark->stages; ++j)
          worst = std::max(worst, std::abs(ark->A[i][j] - tab->a(i, j)));
        worst = std::max(worst, std::abs(ark->b[i] - tab->b[i]));
        worst = std::max(worst, std::abs(ark->d[i] - tab->b_embedded[i]));
        worst = std::max(worst, std::abs(ark->c[i] - tab->c[i]));
      }
      ARKodeButcherTable_Free(ark);
      EXPECT_LE(worst, 2e-16);
    }
  }
  const ButcherTableau& esdirk = built_in_method("esdirk43").tableau;
  const ButcherTableau& imp = built_in_method("ark436l2sa").additive.implicit_table;
  EXPECT_EQ(esdirk.a, imp.a);
  EXPECT_EQ(esdirk.b, imp.b);
  EXPECT_EQ(esdirk.b_embedded, imp.b_embedded);
}

// Fixed-step convergence on the non-stiff test system (ε = 1): the observed order
// log2(e(h)/e(h/2)) at N = 20 -> 40 equals the classical order of the pair to 0.2.
TEST(ImexArk, ObservedOrderIsClassicalOrder) {
  const SplitTestSystem sys(1.0, Parts::both);
  for (const std::string& name : kMethods) {
    SCOPED_TRACE(name);
    const int order = make(name)->info().order;
    const double e1 = error_after(name, sys, 20), e2 = error_after(name, sys, 40);
    EXPECT_NEAR(std::log2(e1 / e2), order, 0.2) << e1 << " " << e2;
  }
}

// f_E ≡ 0: the additive method is its implicit table's DIRK; ark436l2sa against esdirk43 (same
// Newton, same tableau) on the stiff system (ε = 1e-3).
TEST(ImexArk, ImplicitPartAloneIsTheDirk) {
  const SplitTestSystem sys(1e-3, Parts::implicit_only);
  const double h = 0.05;
  auto imex = make("ark436l2sa");
  auto dirk = make("esdirk43");
  Vec a = sys.initial_state(), b = a;
  imex->reset(sys, 0, a);
  dirk->reset(sys, 0, b);
  SolveStats s1, s2;
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(imex->step(sys, k * h, a, h, s1), Status::ok) << s1.message;
    ASSERT_EQ(dirk->step(sys, k * h, b, h, s2), Status::ok) << s2.message;
  }
  EXPECT_LE((a - b).lpNorm<Eigen::Infinity>(), 1e-13 * b.lpNorm<Eigen::Infinity>());
}

// f_I ≡ 0: the explicit table alone (run by ExplicitRungeKutta).
TEST(ImexArk, ExplicitPartAloneIsTheExplicitTable) {
  const SplitTestSystem sys(1.0, Parts::explicit_only);
  const double h = 0.05;
  for (const std::string& name : kMethods) {
    SCOPED_TRACE(name);
    auto imex = make(name);
    ButcherTableau et = imex->additive_tableau()->explicit_table;
    et.b_embedded = Vec();
    et.embedded_order = 0;
    ExplicitRungeKutta erk(et, "explicit table");
    Vec a = sys.initial_state(), b = a;
    imex->reset(sys, 0, a);
    erk.reset(sys, 0, b);
    SolveStats s;
    for (int k = 0; k < 20; ++k) {
      ASSERT_EQ(imex->step(sys, k * h, a, h, s), Status::ok) << s.message;
      ASSERT_EQ(erk.step(sys, k * h, b, h, s), Status::ok);
    }
    EXPECT_LE((a - b).lpNorm<Eigen::Infinity>(), 1e-13);
  }
}

// Without J_I the implicit stages take finite-difference Jacobians of f_I (through the implicit
// part's view): same trajectory as with the analytic J_I up to the Newton tolerance (both iterate
// to round-off), on the stiff system (ε = 1e-4).
TEST(ImexArk, FiniteDifferenceJacobianOfTheImplicitPart) {
  const SplitTestSystem analytic(1e-4, Parts::both, true), fd(1e-4, Parts::both, false);
  const double h = 0.05;
  auto a_int = make("ark436l2sa"), f_int = make("ark436l2sa");
  Vec a = analytic.initial_state(), f = a;
  a_int->reset(analytic, 0, a);
  f_int->reset(fd, 0, f);
  SolveStats sa, sf;
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(a_int->step(analytic, k * h, a, h, sa), Status::ok) << sa.message;
    ASSERT_EQ(f_int->step(fd, k * h, f, h, sf), Status::ok) << sf.message;
  }
  EXPECT_LE((a - f).lpNorm<Eigen::Infinity>(), 1e-12);
}

// A mechanical split: x'' = -k x + g, the spring implicit (a_I = -k x, K_I = -k, D_I = 0) and
// gravity explicit (a_E = g); exact x = g/k + (x0 - g/k) cos(ωt), v = -(x0 - g/k) ω sin(ωt),
// ω = √k, x0 = 1, v0 = 0.
class MechanicalSplit final : public MechanicalSystem {
 public:
  std::string name() const override { return "mechanical_split_test"; }
  Index dofs() const override { return 1; }
  Vec initial_state() const override { return Vec::Unit(2, 0); }
  bool velocity_dependent() const override { return false; }
  bool has_force_jacobians() const override { return true; }
  bool symmetric_force_jacobians() const override { return true; }
  bool has_imex_split() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    const double w = std::sqrt(k_), a = 1 - g_ / k_;
    y << g_ / k_ + a * std::cos(w * t), -a * w * std::sin(w * t);
  }
  void stiffness_block(double, CVecRef, CVecRef, SparseMat& k) const override { one(k, -k_); }
  void damping_block(double, CVecRef, CVecRef, SparseMat& d) const override { one(d, 0); }
  void implicit_force_jacobians(double, CVecRef, CVecRef, SparseMat& k,
                                SparseMat& d) const override {
    one(k, -k_);
    one(d, 0);
  }

 protected:
  void eval_acceleration(double, CVecRef x, CVecRef, VecRef a) const override {
    a[0] = -k_ * x[0] + g_;
  }
  void eval_acceleration_explicit_part(double, CVecRef, CVecRef, VecRef a) const override {
    a[0] = g_;
  }
  void eval_acceleration_implicit_part(double, CVecRef x, CVecRef, VecRef a) const override {
    a[0] = -k_ * x[0];
  }

 private:
  static void one(SparseMat& m, double v) {
    m.resize(1, 1);
    m.setZero();
    m.insert(0, 0) = v;
  }
  double k_ = 100.0, g_ = -9.81;
};

// On a mechanical model the implicit stages are solved in velocity form (the implicit part's
// view is a MechanicalSystem with K_I, D_I): the same trajectory as the first-order 2n system
// (system_form=first_order) to round-off, and ark436l2sa's order 4 against the exact solution
// (N = 40 -> 80 steps to t = 1, hω = 0.25 -> 0.125).
TEST(ImexArk, MechanicalModelsUseVelocityForm) {
  const MechanicalSplit sys;
  const auto run = [&](int n, const std::vector<std::string>& params, bool* velocity) {
    auto integ = make("ark436l2sa", params);
    Vec y = sys.initial_state();
    integ->reset(sys, 0, y);
    *velocity = dynamic_cast<const ImexArkIntegrator&>(*integ).core().velocity_form();
    SolveStats s;
    for (int k = 0; k < n; ++k)
      EXPECT_EQ(integ->step(sys, k * 1.0 / n, y, 1.0 / n, s), Status::ok) << s.message;
    return y;
  };
  bool velocity = false, first_order_velocity = true;
  const Vec a = run(40, {}, &velocity);
  const Vec b = run(40, {"system_form=first_order"}, &first_order_velocity);
  EXPECT_TRUE(velocity);
  EXPECT_FALSE(first_order_velocity);
  EXPECT_LE((a - b).lpNorm<Eigen::Infinity>(), 1e-12);
  Vec exact(2);
  sys.exact(1.0, exact);
  const double e1 = (a - exact).lpNorm<Eigen::Infinity>();
  const double e2 = (run(80, {}, &velocity) - exact).lpNorm<Eigen::Infinity>();
  EXPECT_NEAR(std::log2(e1 / e2), 4.0, 0.25) << e1 << " " << e2;
}

// One fixed step: ark436l2sa evaluates f_E at each of its 6 stages (bE_6 = 1/4 ≠ 0, no FSAL
// reuse) and f_I once at its explicit first stage plus once per Newton iteration; ars443 skips
// its last explicit stage (bE_5 = 0) and its first implicit one (column 1 of A_I and bI_1 zero).
TEST(ImexArk, EvaluationCountsOfOneStep) {
  const SplitTestSystem sys(1e-3, Parts::both);
  for (const auto& [name, fe, fi_explicit] :
       {std::tuple{"ark436l2sa", 6L, 1L}, std::tuple{"ars443", 4L, 0L}}) {
    SCOPED_TRACE(name);
    auto integ = make(name);
    Vec y = sys.initial_state();
    integ->reset(sys, 0, y);
    sys.reset_counters();
    SolveStats s;
    ASSERT_EQ(integ->step(sys, 0, y, 0.01, s), Status::ok);
    EXPECT_EQ(sys.counters().fe_evals, fe);
    EXPECT_EQ(sys.counters().fi_evals, fi_explicit + s.newton_iters);
    EXPECT_EQ(sys.counters().f_evals, sys.counters().fe_evals + sys.counters().fi_evals);
  }
}

// Adaptive ark436l2sa on the stiff test system (ε = 1e-4): the error at t = 1 is within a few
// times rtol (global error of a locally controlled run), and tightening rtol by 100 lowers it.
TEST(ImexArk, AdaptiveReachesTolerance) {
  const SplitTestSystem sys(1e-4, Parts::both);
  Vec exact(3);
  sys.exact(1.0, exact);
  double previous = 0;
  for (const auto& [rtol, text] : {std::pair{1e-5, "rtol=1e-5"}, std::pair{1e-7, "rtol=1e-7"}}) {
    SCOPED_TRACE(rtol);
    auto integ = make("ark436l2sa", {text, "atol=1e-12"});
    ASSERT_TRUE(integ->supports_adaptive());
    Vec y = sys.initial_state();
    integ->reset(sys, 0, y);
    SolveStats s;
    ASSERT_EQ(integ->advance_to(sys, 1.0, y, s), Status::ok) << s.message;
    const double err = (y - exact).lpNorm<Eigen::Infinity>();
    EXPECT_LE(err, 10 * rtol);
    EXPECT_GT(s.steps, 3);
    if (previous > 0) {
      EXPECT_LT(err, previous / 10);
    }
    previous = err;
  }
}

// The embedded estimate of the IMEX pairs is raw by default (error_filter=off), since the
// (I - hγJ_I)^-1 filter hides the error the explicit table leaves in stiff components. Theory
// (imex_ark.hpp): with a stiffly accurate implicit table y_{n+1} - z_s = h Σ (bE_i - aE_si) kE_i,
// which no implicit solve damps, and the filter divides the estimate of it by about h γ |λ|.
// Prothero–Robinson y' = λ(y - sin t) + cos t (f_E = cos t, f_I = λ(y - sin t), λ = -1e6, exact
// y = sin t): ark324l2sa's error at t = 1 must follow rtol raw (within 10 rtol, as for any
// locally controlled run; atol = 1e-12, so rtol sets the weights), while the filtered estimate
// leaves it above 100 rtol at 1e-6 (6.5e-3 measured with atol 1e-10: the tolerance sets
// nothing). One interval: no output time caps a step.
TEST(ImexArk, RawEstimateControlsTheErrorOfTheExplicitTableInStiffComponents) {
  const auto sys = testing_support::model("prothero_robinson", {"lambda=-1e6"});
  auto run = [&](const std::string& rtol, const std::string& filter) {
    std::vector<std::string> params = {"rtol=" + rtol, "atol=1e-12"};
    if (!filter.empty()) params.push_back("error_filter=" + filter);
    auto integ = make("ark324l2sa", params);
    Vec y = sys->initial_state();
    integ->reset(*sys, 0, y);
    SolveStats s;
    EXPECT_EQ(integ->advance_to(*sys, 1.0, y, s), Status::ok) << s.message;
    return std::abs(y[0] - std::sin(1.0));
  };
  for (const std::string rtol : {"1e-4", "1e-6", "1e-8"}) {
    SCOPED_TRACE(rtol);
    const double err = run(rtol, "");  // the default
    EXPECT_EQ(err, run(rtol, "off"));
    EXPECT_LE(err, 10 * std::stod(rtol));
  }
  EXPECT_GT(run("1e-6", "on"), 100 * 1e-6);
}

}  // namespace
}  // namespace stiffbench
