// The velocity-form solves of the implicit methods on mechanical systems
// (integrators/solvers/velocity_form.hpp) against the first-order form they replace.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "core/driver.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/solvers/velocity_form.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

// One solve W k = r, W = I - cJ, in velocity form equals the dense LU solve of the first-order
// 2n system built from the model's assembled Jacobian (an independent computation), for a
// pinned cloth (fixed dofs eliminated) with a right-hand side that is non-zero at the fixed dofs
// too (the eliminated columns move to the right-hand side), with and without dashpots.
TEST(VelocityForm, SolveEqualsFirstOrderSystem) {
  for (const std::string dashpot : {"0", "0.3"}) {
    auto sys = model("cloth", {"n=4", "damping=0.2", "dashpot=" + dashpot});
    const MechanicalSystem& mech = *sys->as_mechanical();
    const Index n = mech.dofs();
    ASSERT_FALSE(mech.fixed_dofs().empty());
    EXPECT_EQ(mech.symmetric_force_jacobians(), dashpot == "0");
    // A state off the rest shape, moving.
    Vec y = sys->initial_state();
    for (Index i = 0; i < 2 * n; ++i) y[i] += 0.01 * std::sin(1.7 * static_cast<double>(i));
    for (Index f : mech.fixed_dofs()) y[n + f] = 0.0;
    SparseMat jac;
    sys->jacobian(0.0, y, jac);
    const double c = 0.05;
    const Mat w = Mat::Identity(2 * n, 2 * n) - c * Mat(jac);
    Vec r(2 * n);
    for (Index i = 0; i < 2 * n; ++i) r[i] = std::cos(0.37 * static_cast<double>(i) + 0.1);
    const Vec expected = w.partialPivLu().solve(r);
    for (const auto kind :
         {LinearSolverKind::automatic, LinearSolverKind::sparse_lu, LinearSolverKind::gmres}) {
      VelocityFormSolver vf;
      LinearSolverOptions opt;
      opt.kind = kind;
      opt.krylov_tol = 1e-14;
      vf.reset(mech, opt, 0.0, y);
      vf.update(0.0, y);
      ASSERT_TRUE(vf.factor(c)) << vf.error();
      Vec k = Vec::Zero(2 * n);
      ASSERT_TRUE(vf.solve(r, k).ok) << vf.error();
      EXPECT_LT(max_abs_diff(k, expected), 1e-11 * expected.cwiseAbs().maxCoeff())
          << "dashpot=" << dashpot << " " << to_string(vf.kind());
      // The symmetric case keeps a symmetric matrix with pins (what lets ldlt and cg run), and
      // Krylov products go through its 3×3 block-row copy.
      if (dashpot == "0") {
        EXPECT_EQ(vf.block_size(), 3);
        const Mat a(vf.matrix());
        EXPECT_LT((a - a.transpose()).cwiseAbs().maxCoeff(), 1e-12 * a.cwiseAbs().maxCoeff());
      }
    }
    // J u in velocity form equals the assembled first-order product.
    VelocityFormSolver vf;
    vf.reset(mech, {}, 0.0, y);
    vf.update(0.0, y);
    Vec ju(2 * n);
    vf.jacobian_times(r, ju);
    EXPECT_LT(max_abs_diff(ju, jac * r), 1e-12 * (jac * r).cwiseAbs().maxCoeff());
  }
}

// `auto` picks ldlt for small symmetric systems, cg for large ones, LU without symmetry.
TEST(VelocityForm, AutoSolverChoice) {
  EXPECT_EQ(velocity_form_auto_solver(kVelocityLdltMax, true), LinearSolverKind::ldlt);
  EXPECT_EQ(velocity_form_auto_solver(kVelocityLdltMax + 1, true), LinearSolverKind::cg);
  EXPECT_EQ(velocity_form_auto_solver(100, false), LinearSolverKind::dense_lu);
  EXPECT_EQ(velocity_form_auto_solver(5000, false), LinearSolverKind::sparse_lu);
  auto cloth = model("cloth", {"n=32"});  // 3,072 dofs, symmetric: cg
  auto be = make("backward_euler");
  be->reset(*cloth, 0.0, cloth->initial_state());
  const auto& core = dynamic_cast<const DirkIntegrator&>(*be).core();
  EXPECT_TRUE(core.velocity_form());
  EXPECT_EQ(core.linear_solver(), LinearSolverKind::cg);
}

// Every implicit method gives the same trajectory in velocity form (auto: ldlt here; and cg) as
// in the first-order form with sparse LU: the elimination is exact, so the runs differ only by
// Newton's tolerance (1e-12 per step, 20 steps) and round-off. Pinned, damped cloth; and the
// same with dashpots (non-symmetric: LU in both forms).
TEST(VelocityForm, TrajectoriesEqualFirstOrderForm) {
  const std::vector<std::string> methods = {
      "backward_euler", "implicit_midpoint",   "trapezoidal", "sdirk2", "sdirk3",
      "bdf2",           "semi_implicit_euler", "rosenbrock2", "ros3p",  "rodas4"};
  for (const std::string dashpot : {"0", "0.5"}) {
    auto sys = model("cloth", {"n=5", "damping=0.1", "dashpot=" + dashpot});
    FixedStepOptions opt;
    opt.t_end = 0.2;
    opt.h = 0.01;
    for (const auto& name : methods) {
      auto first = make(name, {"system_form=first_order", "linear_solver=sparse_lu"});
      const RunResult ref = run_fixed_step(*sys, *first, opt);
      ASSERT_EQ(ref.stats.status, Status::ok) << name << ": " << ref.stats.message;
      std::vector<std::vector<std::string>> variants = {{}};
      if (dashpot == "0") variants.push_back({"linear_solver=cg", "krylov_tol=1e-14"});
      for (auto params : variants) {
        params.push_back("system_form=velocity");
        auto vel = make(name, params);
        const RunResult r = run_fixed_step(*sys, *vel, opt);
        ASSERT_EQ(r.stats.status, Status::ok) << name << ": " << r.stats.message;
        EXPECT_LT(max_abs_diff(r.y, ref.y), 1e-9)
            << name << " dashpot=" << dashpot << (params.size() > 1 ? " cg" : " auto");
        // Same work: one Jacobian per step (modified Newton) or per step (linearly implicit).
        EXPECT_EQ(r.stats.jac_evals, ref.stats.jac_evals) << name;
      }
    }
  }
}

// CG with the incomplete-Cholesky preconditioner solves the same system as LDLᵀ, in fewer
// iterations than with Jacobi (IC(0) of an SPD matrix is a closer approximation of it).
TEST(VelocityForm, IncompleteCholeskyPreconditioner) {
  auto sys = model("cloth", {"n=12"});
  FixedStepOptions opt;
  opt.t_end = 0.1;
  opt.h = 0.01;
  const RunResult ref = run_fixed_step(*sys, *make("baraff_witkin", {"linear_solver=ldlt"}), opt);
  const RunResult ic = run_fixed_step(
      *sys,
      *make("baraff_witkin", {"linear_solver=cg", "preconditioner=ichol", "krylov_tol=1e-12"}),
      opt);
  const RunResult jac =
      run_fixed_step(*sys, *make("baraff_witkin", {"linear_solver=cg", "krylov_tol=1e-12"}), opt);
  ASSERT_EQ(ic.stats.status, Status::ok) << ic.stats.message;
  ASSERT_EQ(jac.stats.status, Status::ok) << jac.stats.message;
  EXPECT_LT(max_abs_diff(ic.y, ref.y), 1e-10);
  EXPECT_LT(ic.stats.linear_iters, jac.stats.linear_iters);
  EXPECT_THROW(make("baraff_witkin", {"linear_solver=gmres", "preconditioner=ichol"}), BadInput);
}

// Baraff–Witkin is linearly implicit Euler in velocity form: the same step on an autonomous
// model (cloth), to round-off and the Krylov tolerance.
TEST(VelocityForm, BaraffWitkinIsLinearlyImplicitEuler) {
  auto sys = model("cloth", {"n=6", "damping=0.1"});
  FixedStepOptions opt;
  opt.t_end = 0.1;
  opt.h = 0.01;
  auto bw = make("baraff_witkin", {"linear_solver=ldlt"});
  auto sie = make("semi_implicit_euler", {"system_form=first_order", "linear_solver=sparse_lu"});
  const RunResult a = run_fixed_step(*sys, *bw, opt);
  const RunResult b = run_fixed_step(*sys, *sie, opt);
  ASSERT_EQ(a.stats.status, Status::ok);
  ASSERT_EQ(b.stats.status, Status::ok);
  EXPECT_LT(max_abs_diff(a.y, b.y), 1e-12);
}

// A compressed cloth (prestretch 0.5: every spring at half its rest length) makes K indefinite
// (the across-spring term k(1 - L/l) < 0) and M - h²MK indefinite at a large step. An explicit
// cg then reports solver_error with the reason; `auto` (cg above 2000 dofs: 26² points = 2,028)
// switches the run to LDLᵀ and gives LDLᵀ's result.
TEST(VelocityForm, IndefiniteMatrixFallsBackOrReports) {
  auto sys = model("cloth", {"n=26", "pin=none", "prestretch=0.5"});
  FixedStepOptions opt;
  opt.t_end = 0.2;
  opt.h = 0.1;
  auto cg = make("baraff_witkin", {"linear_solver=cg"});
  const RunResult r = run_fixed_step(*sys, *cg, opt);
  EXPECT_EQ(r.stats.status, Status::solver_error);
  EXPECT_NE(r.stats.message.find("not positive definite"), std::string::npos) << r.stats.message;
  auto ldlt = make("baraff_witkin", {"linear_solver=ldlt"});
  const RunResult ref = run_fixed_step(*sys, *ldlt, opt);
  ASSERT_EQ(ref.stats.status, Status::ok) << ref.stats.message;
  auto automatic = make("baraff_witkin");
  const RunResult a = run_fixed_step(*sys, *automatic, opt);
  ASSERT_EQ(a.stats.status, Status::ok) << a.stats.message;
  EXPECT_LT(max_abs_diff(a.y, ref.y), 1e-10);
}

}  // namespace
}  // namespace stiffbench
