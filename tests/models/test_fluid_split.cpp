// The additive split of fluid_2d (split=diffusion: f_E = P[-(u·∇)u + g], f_I = P[νLu + νb])
// and of prothero_robinson (f_E = φ'(t), f_I = λ(y - φ(t))): the parts add up to f,
// split=none leaves f bitwise unchanged, f_I on the Taylor–Green field is the 5-point stencil's
// eigenvalue times the field, the explicit part's spectrum estimate against dense eigenvalues,
// and an IMEX run stable far beyond the explicit diffusion limit with the Taylor–Green energy
// decay, where rk4 blows up.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/split_views.hpp"
#include "experiments/commands/list_describe.hpp"
#include "models/grid/fluid_2d.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

constexpr double kEps = 2.220446049250313e-16;  // machine epsilon (double)
const double kPi = std::numbers::pi;

const Fluid2d& fluid(const std::unique_ptr<OdeSystem>& sys) {
  return dynamic_cast<const Fluid2d&>(*sys);
}

// A divergence-free state away from the initial one: y0 + amp·sin(linspace), boundary faces
// zeroed, projected.
Vec perturbed_state(const Fluid2d& f, double amp) {
  Vec y = f.initial_state();
  y += amp * Vec::LinSpaced(f.dimension(), 0.0, 37.0).array().sin().matrix();
  y = y.cwiseProduct(f.free_faces());
  f.project_divergence_free(y);
  return y;
}

// f, f_E and f_I at y.
struct Parts {
  Vec f, fe, fi;
};
Parts parts(const OdeSystem& sys, const Vec& y) {
  Parts p{Vec(sys.dimension()), Vec(sys.dimension()), Vec(sys.dimension())};
  sys.rhs(0.0, y, p.f);
  sys.rhs_explicit_part(0.0, y, p.fe);
  sys.rhs_implicit_part(0.0, y, p.fi);
  return p;
}

// f_E + f_I = f up to rounding, on both scenes (gravity on, so every term is present: advection
// and g in f_E; νLu and the lid's νb in f_I). P is linear, and ΣDF = 0 for each part alone (the
// divergence telescopes to the fixed boundary faces, which D leaves out), so the pinned Poisson
// equation is consistent for each part and P F_E + P F_I = P(F_E + F_I) in exact arithmetic. In
// floating point the difference is the rounding of the sum F_E + F_I and of the two triangular
// solves: measured 1.1 to 4.3 eps (‖f_E‖∞ + ‖f_I‖∞) for n = 8 to 32; the bound 64 eps times that
// scale leaves a margin, and a missing or doubled term (the lid's νb; g = 2, which survives the
// projection on the periodic grid, where a uniform field is divergence-free, while the cavity
// projects it away as a hydrostatic pressure gradient) would exceed it by ten orders.
TEST(FluidSplit, PartsAddUpToTheRightHandSide) {
  for (const char* scene : {"scene=taylor_green", "scene=cavity"})
    for (const char* solver : {"solver=cholesky", "solver=cg"}) {
      SCOPED_TRACE(std::string(scene) + " " + solver);
      auto sys =
          model("fluid_2d", {scene, solver, "n=16", "re=10", "gravity=2", "split=diffusion"});
      ASSERT_TRUE(sys->has_imex_split());
      ASSERT_TRUE(sys->imex_split().has_value());
      EXPECT_EQ(sys->imex_split()->name, "diffusion");
      EXPECT_FALSE(sys->has_implicit_part_jacobian());  // νPL is dense: no analytic J_I
      const Vec y = perturbed_state(fluid(sys), 0.3);
      const Parts p = parts(*sys, y);
      const double scale = p.fe.cwiseAbs().maxCoeff() + p.fi.cwiseAbs().maxCoeff();
      EXPECT_GT(p.fe.cwiseAbs().maxCoeff(), 0.1);  // both parts are non-trivial here
      EXPECT_GT(p.fi.cwiseAbs().maxCoeff(), 1.0);
      // CG solves each projection to its relative tolerance 1e-12 only (of ‖DF‖ ≤ 2·scale/Δx
      // in the divergence, ~1e-12 scale in f after Dᵀ(DDᵀ)⁻¹).
      const double tol = std::string(solver) == "solver=cg" ? 1e-10 * scale : 64 * kEps * scale;
      EXPECT_LE(max_abs_diff(p.fe + p.fi, p.f), tol);
      // Each part is projected: divergence-free to the solver's accuracy.
      EXPECT_LT(fluid(sys).max_divergence(p.fe), 1e-9);
      EXPECT_LT(fluid(sys).max_divergence(p.fi), 1e-9);
    }
}

// split=none (the default) has no split, and f is bitwise the same with split=none, with
// split=diffusion and without the parameter (the split adds code paths for the parts only; the
// full f is the unsplit code). The parts keep their own warm start of the CG pressure solve, so
// calling them between two calls of f does not change the second f either. (Checked against the
// binary before this change too: `solve ... --integrator rk4 --out` trajectories of both scenes
// and both solvers are byte-identical.)
TEST(FluidSplit, SplitNoneAndTheFullRightHandSideAreBitwiseUnchanged) {
  for (const char* scene : {"scene=taylor_green", "scene=cavity"})
    for (const char* solver : {"solver=cholesky", "solver=cg"}) {
      SCOPED_TRACE(std::string(scene) + " " + solver);
      const std::vector<std::string> base{scene, solver, "n=12", "gravity=1.5"};
      auto none = base, diffusion = base;
      none.push_back("split=none");
      diffusion.push_back("split=diffusion");
      auto plain = model("fluid_2d", base), sn = model("fluid_2d", none),
           sd = model("fluid_2d", diffusion);
      // The states from another object: a projection moves the CG warm start of its model.
      auto other = model("fluid_2d", base);
      const Vec y1 = perturbed_state(fluid(other), 0.2), y2 = perturbed_state(fluid(other), 0.5);
      EXPECT_FALSE(plain->has_imex_split());
      EXPECT_FALSE(plain->imex_split().has_value());
      EXPECT_FALSE(plain->explicit_part_spectrum(0.0, plain->initial_state()).has_value());
      EXPECT_FALSE(sn->has_imex_split());
      Vec a(y1.size()), b(y1.size()), c(y1.size());
      plain->rhs(0.0, y1, a);
      sn->rhs(0.0, y1, b);
      sd->rhs(0.0, y1, c);
      EXPECT_TRUE(a == b);
      EXPECT_TRUE(a == c);
      parts(*sd, y1);  // the parts' projections in between
      plain->rhs(0.0, y2, a);
      sd->rhs(0.0, y2, c);
      EXPECT_TRUE(a == c);
    }
}

// Taylor–Green, u_ij = sin(2π iΔx) cos(2π (j+½)Δx) (and v likewise), is an eigenfunction of the
// 5-point Laplacian: along x, sin(α + θ) + sin(α - θ) - 2 sin α = (2 cos θ - 2) sin α with
// θ = 2πΔx, and along y the same for the cosine, so
//   L u = 2 (2 cos θ - 2)/Δx² u = -(8/Δx²) sin²(πΔx) u = λ_h u   (→ -8π² as Δx → 0).
// The field is divergence-free, so P leaves νλ_h u as it is: f_I = νλ_h u. Rounding: the stencil
// adds five terms of size up to (4/Δx²)|u| that cancel to |λ_h u| ≈ 8π²|u|: a few ulps of
// 4ν n² max|u| (measured 5, 16 and 54 eps relative to max|f_I| for n = 8, 16, 32, growing like n²
// as that says); the bound is 20 eps · 4ν n² max|u|.
// The explicit part vanishes on this field, to rounding: the discrete advection term is a discrete
// gradient, as the PDE's is. With a = 2πx_i, b = 2πy_{j+½} at a u face and c = cos πΔx,
// K = sin(2πΔx)/(2Δx), the averages give v̄ = -c² cos a sin b and
//   u ∂u/∂x + v̄ ∂u/∂y = K sin 2a [(1 + c²)/2 + (1 - c²)/2 cos 2b],
// the v faces the same with x and y exchanged; both are the face differences Gq of the cell field
//   q = -[(1 + c²)(cos 2a' + cos 2b') + (1 - c²) cos 2a' cos 2b']/8   (a', b' at cell centres),
// since cos 2a'_{i} - cos 2a'_{i-1} = -2 sin 2a sin 2πΔx (c = 1 gives the PDE's -(cos 4πx +
// cos 4πy)/4). So P kills it: |f_E| is rounding (measured 2e-15 to 3e-14; bounded by 1e-12).
TEST(FluidSplit, TaylorGreenImplicitPartIsTheStencilEigenvalue) {
  for (int n : {8, 16, 32}) {
    SCOPED_TRACE(n);
    auto sys = model("fluid_2d", {"n=" + std::to_string(n), "re=10", "split=diffusion"});
    const Vec y = sys->initial_state();
    const Parts p = parts(*sys, y);
    const double dx = 1.0 / n, nu = 0.1;
    const double lambda_h = -8.0 * std::pow(std::sin(kPi * dx), 2) / (dx * dx);
    const Vec expected = nu * lambda_h * y;
    EXPECT_LE(max_abs_diff(p.fi, expected), 20 * kEps * 4 * nu * n * n * y.cwiseAbs().maxCoeff());
    EXPECT_GT(expected.cwiseAbs().maxCoeff(), 6.0);  // ν|λ_h| ≈ 0.8π² ≈ 7.9 times max|u| ≤ 1
    EXPECT_LE(p.fe.cwiseAbs().maxCoeff(), 1e-12);
  }
}

// explicit_part_spectrum() against the dense eigenvalues of ∂f_E/∂y (central differences of f_E
// through the explicit part's view; f_E is quadratic, so they are exact to rounding) on 12 × 12
// grids: Taylor–Green at t = 0, a perturbed Taylor–Green field, and the cavity at Re = 100 after
// t = 1 (rk4 from rest). The eigenvalues lie near the imaginary axis (the transport part is
// skew-symmetric to leading order; the real parts come from the lower-order -(δu·∇)U and stay
// below 0.15 of the modulus), and the estimate max (|u| + |v̄|)/Δx bounds their modulus from above,
// within a factor 2 (measured ratios 1.32 and 1.69 for the two Taylor–Green states, 1.6 for the
// cavity; towards 1 on finer grids for the smooth field: 1.47, 1.32, 1.23 for n = 8, 12, 16).
TEST(FluidSplit, ExplicitPartSpectrumAgainstDenseEigenvalues) {
  struct Case {
    std::string label;
    std::vector<std::string> params;
    double amp;        // perturbation of the initial state
    double t_develop;  // rk4 run before the state is taken
  };
  const std::vector<Case> cases = {
      {"taylor_green", {"n=12", "split=diffusion"}, 0.0, 0.0},
      {"taylor_green perturbed", {"n=12", "split=diffusion"}, 0.3, 0.0},
      {"cavity", {"scene=cavity", "n=12", "split=diffusion"}, 0.0, 1.0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.label);
    auto sys = model("fluid_2d", c.params);
    Vec y = perturbed_state(fluid(sys), c.amp);
    if (c.t_develop > 0) {
      auto rk = make("rk4");
      FixedStepOptions o;
      o.t_end = c.t_develop;
      o.h = sys->suggested_step()->h;
      const RunResult r = run_fixed_step(*sys, *rk, o);
      ASSERT_EQ(r.stats.status, Status::ok);
      y = r.y;
    }
    const Mat je = finite_difference_jacobian(*explicit_part_view(*sys), 0.0, y);
    const Eigen::VectorXcd ev = Eigen::EigenSolver<Mat>(je, false).eigenvalues();
    const double rho = ev.cwiseAbs().maxCoeff();
    const auto est = sys->explicit_part_spectrum(0.0, y);
    ASSERT_TRUE(est.has_value());
    EXPECT_EQ(est->ray, SpectrumEstimate::Ray::imaginary);
    EXPECT_GT(rho, 1.0);
    EXPECT_GE(est->radius, rho);
    EXPECT_LE(est->radius, 2.0 * rho);
    EXPECT_LE(ev.real().cwiseAbs().maxCoeff(), 0.15 * rho);
  }
}

// describe names the split (and says split=none has none).
TEST(FluidSplit, DescribeNamesTheSplit) {
  std::ostringstream out;
  cmd_describe("fluid_2d", out);
  EXPECT_NE(out.str().find("splits (parameter split, default none)"), std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("diffusion: explicit f_E = advection and gravity"), std::string::npos);
  EXPECT_NE(out.str().find("none: no split"), std::string::npos);
  EXPECT_THROW(model("fluid_2d", {"split=advection"}), BadInput);
}

// IMEX beyond the explicit diffusion limit. Taylor–Green on 32 × 32, Re = 10 (ν = 0.1): the
// explicit diffusion limit Δx²/(4ν) = 0.00244; h = 0.01 is 4.1 times it, 20 steps to T = 0.2.
// The stiffest diffusion mode (the checkerboard u = -v = (-1)^{i+j}, divergence-free, L eigenvalue
// -8/Δx²) has hν·8/Δx² = 8.2 there, beyond rk4's real-axis limit 2.785 (|R(-8.2)| ≈ 120): rk4
// blows up from rounding within the 20 steps.
// The IMEX runs: by the test above, f_E vanishes on the Taylor–Green field and f_I = νλ_h u is
// linear, so the semi-discrete solution is exactly u(t) = e^{νλ_h t} u0 (the advection of any
// multiple of the field is a discrete gradient too) and E_h(t) = E(0) e^{2νλ_h t}; an additive
// method reduces to its implicit table on it: E_num(T) = E(0) R_I(z)^{2N}, z = hνλ_h, R_I(z) =
// 1 + z bᵀ(I - zA)⁻¹1 of the implicit table, up to the Newton and GMRES tolerances (implicit
// stages matrix-free: 2048 unknowns > 200, no J_I; f_I is linear and Newton iterates to
// round-off: measured 8e-16 relative; bound 1e-10). Against the PDE's E(0) e^{-16π²νT}:
// E_h/E_PDE = e^{16νT(π² - sin²(πΔx)/Δx²)} = 1.0102 (the stencil's rate is 0.32% low at
// Δx = 1/32), and the time error R_I(z)^{40}/e^{40z} of these second- and third-order methods at
// hν|λ_h| = 0.079 is under 0.1% (computed below: ars232 -7.9e-4, ark324l2sa -3.8e-5), so
// E_num/E_PDE lies within 1.5% of 1 (measured 1.0094 and 1.0101).
TEST(FluidSplit, ImexStableBeyondTheExplicitDiffusionLimit) {
  const std::vector<std::string> params{"n=32", "re=10", "split=diffusion"};
  const double nu = 0.1, dx = 1.0 / 32, t_end = 0.2, h = 0.01;
  ASSERT_GT(h, 4.0 * dx * dx / (4 * nu));
  const double lambda_h = -8.0 * std::pow(std::sin(kPi * dx), 2) / (dx * dx);
  const double e0 = 0.25;  // ½∫(u² + v²) of the Taylor–Green field (tests/models/test_grid.cpp)
  const double e_pde = e0 * std::exp(-16 * kPi * kPi * nu * t_end);
  const double e_h = e0 * std::exp(2 * nu * lambda_h * t_end);
  EXPECT_NEAR(e_h / e_pde, 1.0102, 1e-4);
  FixedStepOptions opt;
  opt.t_end = t_end;
  opt.h = h;
  for (const char* name : {"ars232", "ark324l2sa"}) {
    SCOPED_TRACE(name);
    auto sys = model("fluid_2d", params);
    const Fluid2d& f = fluid(sys);
    auto integ = make(name);
    const RunResult r = run_fixed_step(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok);
    EXPECT_EQ(r.n_steps, 20);
    EXPECT_GT(r.stats.linear_iters, 0);  // matrix-free GMRES in the implicit stages
    EXPECT_EQ(r.stats.jac_evals, 0);
    const ButcherTableau& imp = integ->additive_tableau()->implicit_table;
    const double z = h * nu * lambda_h;
    const Index s = imp.stages();
    const Mat m = Mat::Identity(s, s) - z * imp.a;
    const double rz = 1.0 + z * imp.b.dot(m.lu().solve(Vec::Ones(s)));
    EXPECT_LE(std::abs(std::pow(rz, 40) / std::exp(40 * z) - 1.0), 1e-3);
    const double e = f.kinetic_energy(r.y);
    EXPECT_NEAR(e / (e0 * std::pow(rz, 40)), 1.0, 1e-10);
    EXPECT_NEAR(e / e_pde, 1.0, 0.015);
    EXPECT_LT(f.max_divergence(r.y), 1e-10);
  }
  auto sys = model("fluid_2d", params);
  auto rk4 = make("rk4");
  const RunResult r = run_fixed_step(*sys, *rk4, opt);
  EXPECT_EQ(r.stats.status, Status::unstable);
  EXPECT_LT(r.t, t_end);  // stopped early (measured: after 11 of the 20 steps)
}

// ---------------------------------------------------------------------------------------------
// prothero_robinson: f_E = φ'(t), f_I = λ(y - φ(t)), J_I = λ.

// f = λ(y - φ) + φ' is computed as the same two terms added once, and IEEE addition commutes, so
// f_E + f_I equals f bit for bit. J_I = λ against central differences of f_I (linear in y: exact
// up to the rounding of λ(y ± δ - φ), about eps|λ|·|y|/δ ≈ 4e-11 |λ| relative with δ ≈ 6e-6).
// ∂f_E/∂y = 0, so J - J_I = 0 and the explicit part's spectrum is exactly 0.
TEST(ProtheroRobinsonSplit, PartsJacobianAndName) {
  for (const char* phi : {"phi=sin", "phi=cos", "phi=exp"}) {
    SCOPED_TRACE(phi);
    auto sys = model("prothero_robinson", {"lambda=-1e6", phi, "y0_offset=0.3"});
    ASSERT_TRUE(sys->has_imex_split());
    ASSERT_TRUE(sys->imex_split().has_value());
    EXPECT_EQ(sys->imex_split()->name, "stiff");
    ASSERT_TRUE(sys->has_implicit_part_jacobian());
    for (double t : {0.3, 0.7, 2.0}) {  // not 0: φ' = -sin 0 would make f_E zero
      const Vec y{{0.4 - t}};
      Vec f(1), fe(1), fi(1);
      sys->rhs(t, y, f);
      sys->rhs_explicit_part(t, y, fe);
      sys->rhs_implicit_part(t, y, fi);
      EXPECT_EQ(fe[0] + fi[0], f[0]);
      EXPECT_NE(fe[0], 0.0);
      EXPECT_NE(fi[0], 0.0);
      SparseMat ji, j;
      sys->reset_counters();
      sys->implicit_part_jacobian(t, y, ji);
      EXPECT_EQ(sys->counters().jac_evals, 1);
      sys->jacobian(t, y, j);
      EXPECT_EQ(Mat(ji)(0, 0), -1e6);
      EXPECT_EQ(Mat(j)(0, 0) - Mat(ji)(0, 0), 0.0);
      const Mat fd = finite_difference_jacobian(*implicit_part_view(*sys), t, y);
      EXPECT_NEAR(fd(0, 0), -1e6, 1e-6 * 1e6);
      const auto spec = sys->explicit_part_spectrum(t, y);
      ASSERT_TRUE(spec.has_value());
      EXPECT_EQ(spec->radius, 0.0);
    }
  }
  std::ostringstream out;
  cmd_describe("prothero_robinson", out);
  EXPECT_NE(out.str().find("splits: stiff"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("implicit f_I = λ(y - φ(t))"), std::string::npos) << out.str();
}

// With J_I the IMEX methods' implicit stages use it (jacobian=auto: analytic): ars232 on
// λ = -1e6 at h = 0.01 (h|λ| = 1e4) follows φ = sin t. ARS(2,3,2) is stiffly accurate, so the
// stiff component is damped at every step: for h|λ| ≫ 1 the error y_n - φ(t_n) is the stages'
// defect divided by λ,
// O(h|φ''|/|λ|) = 1e-8 times a constant of the method (measured 5.9e-8); bound 1e-6.
TEST(ProtheroRobinsonSplit, ImexRunUsesTheImplicitPartJacobian) {
  auto sys = model("prothero_robinson", {"lambda=-1e6"});
  auto integ = make("ars232");
  FixedStepOptions opt;
  opt.t_end = 1.0;
  opt.h = 0.01;
  const RunResult r = run_fixed_step(*sys, *integ, opt);
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_GT(r.stats.jac_evals, 0);
  EXPECT_NEAR(r.y[0], std::sin(1.0), 1e-6);
}

}  // namespace
}  // namespace stiffbench
