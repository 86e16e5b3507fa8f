// The ARKODE references on an additive split (integrators/reference/sundials.hpp): arkode_imex
// with a named ARK pair at a fixed step, compared with an independent ARK step written here from
// the same tables, and the Jacobian its Newton iteration uses.
#include <gtest/gtest.h>

#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "tests/integrators/split_test_system.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::KapsSplit;
using testing_support::LinearSplit;
using testing_support::make;

// The settings under which ARKODE's Newton iteration converges far below the comparison's 1e-9
// (docs/splits.md, arkode_imex at a fixed step).
const std::vector<std::string> kTight = {"rtol=1e-12", "atol=1e-14", "nonlin_conv_coef=1e-3",
                                         "max_nonlin_iters=20"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// One additive Runge–Kutta step on Kaps' split from ARKODE's coefficient arrays (not its
// stepper): stage i solves z = y + h Σ_{j<i} (aE_ij fE_j + aI_ij fI_j) + h aI_ii fI(z) by Newton
// with the exact 2x2 J_I to round-off; y += h Σ (bE_j fE_j + bI_j fI_j). Kaps is autonomous, so
// c does not enter.
Vec ark_step(ARKodeButcherTable e, ARKodeButcherTable im, double eps, const Vec& y, double h) {
  const int s = e->stages;
  std::vector<Vec> fe(s, Vec(2)), fi(s, Vec(2));
  for (int i = 0; i < s; ++i) {
    Vec psi = y;
    for (int j = 0; j < i; ++j) psi += h * (e->A[i][j] * fe[j] + im->A[i][j] * fi[j]);
    const double g = h * im->A[i][i];
    Vec z = psi;
    for (int it = 0; it < 50; ++it) {
      const Vec fiz{{(-z(0) + z(1) * z(1)) / eps, 0.0}};
      const Vec r = z - psi - g * fiz;
      // I - g J_I with J_I = [[-1/eps, 2 z1/eps], [0, 0]]: upper triangular.
      const double a = 1 + g / eps, b = -g * 2 * z(1) / eps;
      const double d1 = r(1), d0 = (r(0) - b * d1) / a;
      z(0) -= d0;
      z(1) -= d1;
      if (std::abs(d0) + std::abs(d1) < 1e-17) break;
    }
    fe[i] = Vec{{-2 * z(0), z(0) - z(1) - z(1) * z(1)}};
    fi[i] = Vec{{(-z(0) + z(1) * z(1)) / eps, 0.0}};
  }
  Vec out = y;
  for (int j = 0; j < s; ++j) out += h * (e->b[j] * fe[j] + im->b[j] * fi[j]);
  return out;
}

Vec hand_written_ark(ARKODE_ERKTableID eid, ARKODE_DIRKTableID iid, double eps, double t_end,
                     double h) {
  ARKodeButcherTable e = ARKodeButcherTable_LoadERK(eid);
  ARKodeButcherTable im = ARKodeButcherTable_LoadDIRK(iid);
  Vec y = Vec::Ones(2);
  const long n = std::lround(t_end / h);
  for (long k = 0; k < n; ++k) y = ark_step(e, im, eps, y, h);
  ARKodeButcherTable_Free(e);
  ARKodeButcherTable_Free(im);
  return y;
}

// Step for step: arkode_imex tables=ark436l2sa at a fixed step and the hand-written ARK step from
// the same tables agree to 1e-9 relative at t = 1 (eps = 1e-3: a stiff implicit part, so the
// Newton iteration matters), likewise ark324l2sa.
TEST(ArkodeImex, FixedStepAgreesWithAnIndependentArkStep) {
  struct Case {
    const char* tables;
    ARKODE_ERKTableID e;
    ARKODE_DIRKTableID i;
  };
  for (const Case c :
       {Case{"ark436l2sa", ARKODE_ARK436L2SA_ERK_6_3_4, ARKODE_ARK436L2SA_DIRK_6_3_4},
        Case{"ark324l2sa", ARKODE_ARK324L2SA_ERK_4_2_3, ARKODE_ARK324L2SA_DIRK_4_2_3}}) {
    KapsSplit sys(1e-3);
    auto integ = make("arkode_imex", with({std::string("tables=") + c.tables}, kTight));
    const RunResult r = run_fixed_step(sys, *integ, {1.0, 0.05});
    ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
    const Vec ref = hand_written_ark(c.e, c.i, 1e-3, 1.0, 0.05);
    EXPECT_LT(max_abs_diff(r.y, ref), 1e-9 * ref.cwiseAbs().maxCoeff()) << c.tables;
    // Each step is one ARKODE step of h: the explicit table's stage count of f_E calls per step
    // (ARKODE adds one f_E at the initial state: 121 and 81 measured).
    const long stages = std::string(c.tables) == "ark436l2sa" ? 6 : 4;
    EXPECT_GE(sys.counters().fe_evals, 20 * stages) << c.tables;
    EXPECT_LE(sys.counters().fe_evals, 20 * stages + 1) << c.tables;
  }
}

// Observed order 4 of ARK4(3)6L[2]SA at a fixed step on Kaps (eps = 0.5: smooth, no order
// reduction), errors against the exact solution over three halvings from h = 0.2.
TEST(ArkodeImex, FixedStepObservedOrderFour) {
  std::vector<double> err;
  for (double h = 0.2; h > 0.02; h /= 2) {
    KapsSplit sys(0.5);
    auto integ = make("arkode_imex", with({"tables=ark436l2sa"}, kTight));
    const RunResult r = run_fixed_step(sys, *integ, {1.0, h});
    ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
    Vec ye(2);
    sys.exact(1.0, ye);
    err.push_back(max_abs_diff(r.y, ye));
  }
  for (std::size_t k = 0; k + 1 < err.size(); ++k)
    EXPECT_NEAR(std::log2(err[k] / err[k + 1]), 4.0, 0.2) << err[k] << " -> " << err[k + 1];
}

// In split mode the Newton matrices come from J_I (implicit_part_jacobian), never from the full
// J: the test system counts the calls of each.
TEST(ArkodeImex, SplitModeNewtonUsesTheImplicitPartsJacobian) {
  KapsSplit sys(1e-3);
  auto integ = make("arkode_imex", {"linear_solver=dense"});
  const RunResult r = run_fixed_step(sys, *integ, {0.5, 0.05});
  ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
  EXPECT_EQ(sys.full_jacobian_calls(), 0);
  EXPECT_GT(sys.implicit_jacobian_calls(), 0);
  EXPECT_GT(sys.counters().fi_evals, 0);
  EXPECT_GT(sys.counters().fe_evals, 0);
  // arkode_dirk on the same model integrates the whole f: the full J.
  KapsSplit whole(1e-3);
  auto dirk = make("arkode_dirk", {"linear_solver=dense"});
  ASSERT_EQ(run_fixed_step(whole, *dirk, {0.5, 0.05}).stats.status, Status::ok);
  EXPECT_GT(whole.full_jacobian_calls(), 0);
  EXPECT_EQ(whole.implicit_jacobian_calls(), 0);
}

// arkode_mri: slow f_E by the MRI coupling table, fast f_I by the inner DIRK at h/20. On the
// linear split with non-commuting parts (lambda = 3; exact solution in split_test_system.hpp)
// the observed order over three halvings from h = 0.1 is the coupling table's: 3 for
// MRI-GARK-ERK33a and MIS-KW3 (Sandu 2019; Knoth & Wolke 1998), 4 for MRI-GARK-ERK45a; the
// inner SDIRK 5-3-4 (order 4, step h/20) and a converged Newton keep the fast error below it.
TEST(ArkodeMri, ObservedOrderIsTheCouplingTables) {
  for (const auto& [coupling, order] : {std::pair<std::string, double>{"mri_gark_erk33a", 3.0},
                                        {"mis_kw3", 3.0},
                                        {"mri_gark_erk45a", 4.0}}) {
    std::vector<double> err;
    for (double h = 0.1; h > 0.01; h /= 2) {
      LinearSplit sys(3.0);
      auto integ = make("arkode_mri", with({"coupling=" + coupling, "fast_steps=20"}, kTight));
      EXPECT_EQ(integ->info().order, static_cast<int>(order));
      const RunResult r = run_fixed_step(sys, *integ, {1.0, h});
      ASSERT_EQ(r.stats.status, Status::ok) << r.stats.message;
      Vec ye(2);
      sys.exact(1.0, ye);
      err.push_back(max_abs_diff(r.y, ye));
      // The slow part is evaluated only by the slow stages: f_E calls do not grow with the
      // fast steps (at most one per slow stage and step, plus ARKODE's initial one).
      EXPECT_LE(sys.counters().fe_evals, 5 * r.n_steps + 1) << coupling;
    }
    for (std::size_t k = 0; k + 1 < err.size(); ++k)
      EXPECT_NEAR(std::log2(err[k] / err[k + 1]), order, 0.25)
          << coupling << ": " << err[k] << " -> " << err[k + 1];
  }
}

TEST(ArkodeMri, RefusesModelsWithoutSplitAndAdaptiveRuns) {
  auto integ = make("arkode_mri");
  auto no_split = testing_support::model("dahlquist");
  EXPECT_THROW(run_fixed_step(*no_split, *integ, {0.1, 0.05}), BadInput);
  EXPECT_FALSE(integ->supports_adaptive());
  EXPECT_THROW(make("arkode_mri", {"coupling=nope"}), BadInput);
}

TEST(ArkodeImex, TablesParameterIsChecked) {
  EXPECT_THROW(make("arkode_imex", {"tables=named"}), BadInput);
  EXPECT_THROW(make("arkode_imex", {"explicit_table=ARKODE_ARK324L2SA_ERK_4_2_3"}), BadInput);
  EXPECT_EQ(make("arkode_imex", {"tables=ark324l2sa"})->info().order, 3);
  EXPECT_EQ(make("arkode_imex", {"tables=named", "explicit_table=ARKODE_ARK548L2SA_ERK_8_4_5",
                                 "implicit_table=ARKODE_ARK548L2SA_DIRK_8_4_5"})
                ->info()
                .order,
            5);
}

}  // namespace
}  // namespace stiffbench
