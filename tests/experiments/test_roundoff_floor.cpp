// The round-off floor of the convergence and local-error studies: measured per method by
// reruns from rounding-level perturbations of y0 (--floor auto), the N·u·s model (--floor model),
// a given value (--floor VALUE), and the reasons the order fit gives when levels are removed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "stiffbench/stiffbench.hpp"

namespace stiffbench {
namespace {

// The chemical Akzo Nobel problem (IVP Test Set, F. Mazzia & C. Magherini, problem CHEMAKZO;
// originally a DAE of index 1 from Akzo Nobel Central Research), written as an ODE of 5
// components by eliminating the algebraic y6 = Ks·y1·y4:
//   y1' = -2 r1 + r2 - r3 - r4          r1 = k1 y1^4 sqrt(y2)
//   y2' = -r1/2 - r4 - r5/2 + Fin       r2 = k2 y3 y4
//   y3' = r1 - r2 + r3                  r3 = (k2/K) y1 y5
//   y4' = -r2 + r3 - 2 r4               r4 = k3 y1 y4^2
//   y5' = r2 - r3 + r5                  r5 = k4 y6^2 sqrt(y2),  Fin = klA (p/H - y2)
// with k1 = 18.7, k2 = 0.58, k3 = 0.09, k4 = 0.42, K = 34.4, klA = 3.3, Ks = 115.83, p = 0.9,
// H = 737, y(0) = (0.444, 0.00123, 0, 0.007, 0), t in [0, 180]. The Test Set's reference
// solution at t = 180 is the "exact" value here (only there: the studies ask for it at t_end).
class ChemAkzo final : public OdeSystem {
 public:
  static constexpr double k1 = 18.7, k2 = 0.58, k3 = 0.09, k4 = 0.42, K = 34.4, klA = 3.3,
                          Ks = 115.83, p = 0.9, H = 737.0, t_ref = 180.0;
  std::string name() const override { return "test_chemakzo"; }
  Index dimension() const override { return 5; }
  Vec initial_state() const override { return Vec{{0.444, 0.00123, 0.0, 0.007, 0.0}}; }
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    if (t != t_ref) throw std::logic_error("test_chemakzo: reference only at t = 180");
    // IVP Test Set, CHEMAKZO, reference solution at t = 180 (y1..y5; y6 = 0.4873531310307455e-2).
    y << 0.1150794920661702, 0.1203831471567715e-2, 0.1611562887407974, 0.3656156421249283e-3,
        0.1708010885264404e-1;
  }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    const double sq = std::sqrt(y[1]);
    const double y6 = Ks * y[0] * y[3];
    const double r1 = k1 * std::pow(y[0], 4) * sq, r2 = k2 * y[2] * y[3], r3 = k2 / K * y[0] * y[4],
                 r4 = k3 * y[0] * y[3] * y[3], r5 = k4 * y6 * y6 * sq;
    const double fin = klA * (p / H - y[1]);
    f[0] = -2 * r1 + r2 - r3 - r4;
    f[1] = -0.5 * r1 - r4 - 0.5 * r5 + fin;
    f[2] = r1 - r2 + r3;
    f[3] = -r2 + r3 - 2 * r4;
    f[4] = r2 - r3 + r5;
  }
  // J = C·∂r/∂y + ∂Fin/∂y e2ᵀ, C the stoichiometric coefficients of f above.
  void eval_jacobian(double, CVecRef y, SparseMat& jac) const override {
    const double sq = std::sqrt(y[1]);
    const double c5 = k4 * Ks * Ks;  // r5 = c5 y1² y4² sqrt(y2)
    Eigen::Matrix<double, 5, 5> dr = Eigen::Matrix<double, 5, 5>::Zero();  // dr(i, j) = ∂r_i/∂y_j
    dr(0, 0) = 4 * k1 * std::pow(y[0], 3) * sq;
    dr(0, 1) = k1 * std::pow(y[0], 4) / (2 * sq);
    dr(1, 2) = k2 * y[3];
    dr(1, 3) = k2 * y[2];
    dr(2, 0) = k2 / K * y[4];
    dr(2, 4) = k2 / K * y[0];
    dr(3, 0) = k3 * y[3] * y[3];
    dr(3, 3) = 2 * k3 * y[0] * y[3];
    dr(4, 0) = 2 * c5 * y[0] * y[3] * y[3] * sq;
    dr(4, 1) = c5 * y[0] * y[0] * y[3] * y[3] / (2 * sq);
    dr(4, 3) = 2 * c5 * y[0] * y[0] * y[3] * sq;
    Eigen::Matrix<double, 5, 5> c;
    c << -2, 1, -1, -1, 0,     //
        -0.5, 0, 0, -1, -0.5,  //
        1, -1, 1, 0, 0,        //
        0, -1, 1, -2, 0,       //
        0, 1, -1, 0, 1;
    Eigen::Matrix<double, 5, 5> j = c * dr;
    j(1, 1) -= klA;
    std::vector<Eigen::Triplet<double>> t;
    for (int r = 0; r < 5; ++r)
      for (int col = 0; col < 5; ++col) t.emplace_back(r, col, j(r, col));
    jac.resize(5, 5);
    jac.setFromTriplets(t.begin(), t.end());
  }
};

StudyObjects chemakzo() {
  return StudyObjects{[] { return std::make_unique<ChemAkzo>(); }, {}};
}

// y' = -y, y(0) = 1 to t = 40: y(40) = e^-40 = 4.2e-18, so every absolute error is far below the
// model N·u·max(1, ‖y0‖∞, ‖y_ref‖∞) = N·u (s = 1 from y0), while the rounding error of a run is
// about u·y(t) at each step, damped with the solution: of order 1e-33.
class FastDecay final : public OdeSystem {
 public:
  std::string name() const override { return "test_fast_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -y[0]; }
};

// Rows of one integrator with errors e_k at h_k = 0.1/2^k, at the round-off floor `floor` from
// `source` (the study's rule: error <= kFloorFactor × floor), in ladder order.
std::vector<ConvergenceRow> synthetic(const std::vector<double>& errors, double floor,
                                      const std::string& source, int order) {
  std::vector<ConvergenceRow> rows;
  for (std::size_t k = 0; k < errors.size(); ++k) {
    ConvergenceRow r;
    r.integrator = "m";
    r.order = order;
    r.h = 0.1 / std::pow(2.0, static_cast<double>(k));
    r.error = errors[k];
    r.roundoff_floor = floor;
    r.floor_used = floor;
    r.floor_source = source;
    r.at_floor = r.error <= kFloorFactor * floor;
    rows.push_back(r);
  }
  return rows;
}

// The perturbation: deterministic, opposite for the two signs, every nonzero component scaled by
// 1 ± 2^-30, zero components left exact.
TEST(RoundoffFloor, PerturbationIsDeterministicAndSymmetric) {
  const Vec y0{{1.0, 0.0, -3.5e-7, 0.444, 2.0e5}};
  const Vec up = perturbed_initial_state(y0, 1), again = perturbed_initial_state(y0, 1);
  const Vec down = perturbed_initial_state(y0, -1);
  EXPECT_EQ(up, again);
  EXPECT_EQ(up[1], 0.0);
  EXPECT_EQ(down[1], 0.0);
  for (Index i : {0, 2, 3, 4}) {
    const double rel_up = (up[i] - y0[i]) / y0[i], rel_down = (down[i] - y0[i]) / y0[i];
    EXPECT_NEAR(std::abs(rel_up), 0x1p-30, 1e-15) << i;  // the scaling, to its own rounding
    EXPECT_NEAR(rel_down, -rel_up, 1e-15) << i;
  }
}

// rk4 on the undamped oscillator (t_end = 10, |y| = 1) down to h = 0.1/2^11: the truncation error
// about t_end·h⁴/120 (the phase error of rk4's amplification factor against e^{ih}) is 4e-13 at
// h = 0.1/64 and 1.6e-18 at h = 0.1/1024, far below the rounding error of 10⁵ steps: the finest
// levels are the round-off plateau. Theory: (y₊ + y₋)/2 − y of three runs with independent
// rounding is about 1.2 σ (σ the rounding error of one), so the measured floor, twice it, is
// within a small factor of the plateau's errors (a factor 10 either way here).
TEST(RoundoffFloor, MeasuredFloorMatchesTheRoundoffPlateau) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 10;
  spec.h = 0.1;
  spec.levels = 12;
  const auto res = run_convergence(spec, nullptr);
  ASSERT_EQ(res.floors.size(), 1u);
  const auto& fl = res.floors[0];
  EXPECT_EQ(fl.source, "perturbed");
  EXPECT_DOUBLE_EQ(fl.h, res.rows.back().h);
  ASSERT_EQ(fl.spreads.size(), 3u);
  // The plateau: the levels whose truncation error (t_end h^4/120) is below 10% of their error.
  double plateau = 0;
  int plateau_rows = 0;
  for (const auto& r : res.rows) {
    EXPECT_EQ(r.floor_source, "perturbed");
    // The measured floor scaled to the row's steps by √(N/N_f).
    const double scaled =
        fl.value * std::sqrt(static_cast<double>(r.steps) / static_cast<double>(fl.steps));
    EXPECT_NEAR(r.floor_used, scaled, 1e-12 * scaled);
    if (spec.t_end * std::pow(r.h, 4) / 120 < 0.1 * r.error) {
      plateau = std::max(plateau, r.error);
      ++plateau_rows;
    }
  }
  ASSERT_GE(plateau_rows, 3);
  EXPECT_GT(fl.value, plateau / 10) << "plateau " << plateau;
  EXPECT_LT(fl.value, plateau * 10) << "plateau " << plateau;
  // The plateau rows are at the floor, the rows above 10x it fitted at order 4.
  EXPECT_TRUE(res.rows.back().at_floor);
  ASSERT_TRUE(res.fits[0].fitted.has_value()) << res.fits[0].reason;
  EXPECT_NEAR(*res.fits[0].fitted, 4.0, 0.1);
  EXPECT_EQ(res.fits[0].floor_source, "perturbed");
  // Reproducible: a second run measures the same floor bit for bit.
  EXPECT_EQ(run_convergence(spec, nullptr).floors[0].value, fl.value);
}

// --floor model: every row is checked against N·u·s (s = 1 on the oscillator), as before the
// floor was measured: rows at most 10 N u are `floor`, the others not.
TEST(RoundoffFloor, ModelFloorReproducesTheBoundMarking) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 10;
  spec.h = 0.1;
  spec.levels = 10;
  spec.floor = "model";
  const auto res = run_convergence(spec, nullptr);
  int floor_rows = 0;
  for (const auto& r : res.rows) {
    const double bound = static_cast<double>(r.steps) * 0x1p-53;
    EXPECT_NEAR(r.floor_used, bound, 1e-12 * bound);
    EXPECT_EQ(r.floor_source, "model");
    EXPECT_EQ(r.at_floor, r.error <= 10 * bound) << r.h;
    floor_rows += r.at_floor ? 1 : 0;
  }
  EXPECT_GE(floor_rows, 3);
  EXPECT_EQ(res.floors[0].source, "model");
  EXPECT_EQ(res.floors[0].value, res.rows.back().roundoff_floor);
}

// --floor VALUE: that absolute error for every row (source given), whatever the model says.
TEST(RoundoffFloor, GivenFloorIsHonoured) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 10;
  spec.h = 0.1;
  spec.levels = 6;
  spec.floor = "1e-8";
  const auto res = run_convergence(spec, nullptr);
  int floor_rows = 0;
  for (const auto& r : res.rows) {
    EXPECT_EQ(r.floor_used, 1e-8);
    EXPECT_EQ(r.floor_source, "given");
    EXPECT_EQ(r.at_floor, r.error <= 1e-7) << r.h;
    floor_rows += r.at_floor ? 1 : 0;
  }
  // rk4's error, about t_end h^4/120, is below 1e-7 from h = 0.1/4 on (5.2e-7 at 0.05, 3.3e-8 at
  // 0.025): four of six levels, which leaves two and no fit.
  EXPECT_EQ(floor_rows, 4);
  EXPECT_EQ(res.fits[0].floor_source, "given");
  EXPECT_FALSE(res.fits[0].fitted.has_value());
}

TEST(RoundoffFloor, FloorOptionIsValidated) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  for (const char* bad : {"low", "0", "-1e-12", "nan", "inf", "1e-12x", ""}) {
    spec.floor = bad;
    try {
      spec.validate();
      ADD_FAILURE() << "accepted --floor '" << bad << "'";
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find("--floor"), std::string::npos) << e.what();
    }
  }
  for (const char* good : {"auto", "model", "1e-12", "3"}) {
    spec.floor = good;
    EXPECT_NO_THROW(spec.validate()) << good;
  }
  spec.floor = "2.5e-14";
  EXPECT_EQ(spec.given_floor(), 2.5e-14);
  EXPECT_EQ(spec.to_json()["floor"], "2.5e-14");
}

// A cheap problem where the model floor is far above the real rounding: rk4 on y' = -y to t = 40.
// Its errors (about 40 h^4/120 · e^-40 ≈ 1e-22 at h = 0.1) are all below 10 N u (4e-13 at
// h = 0.1), so --floor model marks every row and gives no fit; the measured floor keeps them
// and the fit is rk4's order 4 (theory: the error constant of rk4 on y' = -y is h^4/120 per unit
// time, relative to y).
TEST(RoundoffFloor, RowsBelowTheModelFloorAreKeptAndFitted) {
  ConvergenceSpec spec;
  spec.model = "test_fast_decay";
  spec.integrators = {"rk4"};
  spec.t_end = 40;
  spec.h = 0.1;
  spec.levels = 5;
  const StudyObjects decay{[] { return std::make_unique<FastDecay>(); }, {}};
  const auto res = run_convergence(inputs_of(spec, decay), spec, nullptr);
  ASSERT_EQ(res.rows.size(), 5u);
  for (const auto& r : res.rows) {
    EXPECT_LT(r.error, r.roundoff_floor) << r.h;  // below the model bound
    EXPECT_FALSE(r.at_floor) << r.h;
  }
  ASSERT_TRUE(res.fits[0].fitted.has_value()) << res.fits[0].reason;
  EXPECT_NEAR(*res.fits[0].fitted, 4.0, 0.1);
  spec.floor = "model";
  const auto old = run_convergence(inputs_of(spec, decay), spec, nullptr);
  for (const auto& r : old.rows) EXPECT_TRUE(r.at_floor) << r.h;
  EXPECT_FALSE(old.fits[0].fitted.has_value());
  // No level is usable: the reason names the model floor and the change that helps.
  EXPECT_NE(old.fits[0].reason.find("only 0 levels above the round-off floor (the model N·u·s)"),
            std::string::npos)
      << old.fits[0].reason;
}

// The local study measures its floor the same way (one step from perturbed y0s): rk4's local
// error on the oscillator, h = 0.1 … 0.1/2^7, is about h^5/120 (5e-16 at h = 0.1/128, 8e-8 at
// h = 0.1); the measured floor is at the rounding level of one step of a |y| = 1 solution, a few u.
TEST(RoundoffFloor, LocalStudyMeasuresItsFloor) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.h = 0.1;
  spec.levels = 8;
  const auto res = run_local_error(spec, nullptr);
  ASSERT_EQ(res.floors.size(), 1u);
  EXPECT_EQ(res.floors[0].source, "perturbed");
  EXPECT_GE(res.floors[0].value, 0.5 * 0x1p-53);
  EXPECT_LE(res.floors[0].value, 32 * 0x1p-53);
  ASSERT_TRUE(res.fits[0].fitted.has_value()) << res.fits[0].reason;
  EXPECT_NEAR(*res.fits[0].fitted, 5.0, 0.1);
}

// The reasons: what removed the levels, and advice that would change the result.
TEST(RoundoffFloor, ReasonAdviceFitsTheLadderThatRan) {
  // Errors falling at order 4, then a plateau at 5e-15 that a measured floor of 1e-15 marks;
  // the pairwise orders into the plateau (about 30, then 0) are not the method's order.
  const std::vector<double> e = {1e-4, 6.25e-6, 5e-15, 5.5e-15, 4.5e-15};
  const OrderFit common = fit_order(synthetic(e, 1e-15, "perturbed", 4), "m", false, "common");
  EXPECT_FALSE(common.fitted.has_value());
  EXPECT_EQ(common.reason.rfind("only 2 levels above the round-off floor (measured by perturbed "
                                "reruns: 1.000e-15), 3 at it: use a larger --h or --ladder "
                                "per-method",
                                0),
            0u)
      << common.reason;
  const OrderFit own = fit_order(synthetic(e, 1e-15, "perturbed", 4), "m", false, "per-method");
  EXPECT_EQ(own.reason.find("--ladder per-method"), std::string::npos) << own.reason;
  EXPECT_NE(own.reason.find("smaller --refine"), std::string::npos) << own.reason;
}

// The model bound marks levels whose errors still fall at the method's order (pairwise orders
// exactly 4 through them: e = h^4 with a model floor of 1e-7): the reason says the model is the
// cause and --floor auto the remedy, not a larger --h.
TEST(RoundoffFloor, AModelFloorAboveFallingErrorsIsNamed) {
  std::vector<double> e;
  for (int k = 0; k < 6; ++k) e.push_back(std::pow(0.1 / std::pow(2.0, k), 4));
  const OrderFit f = fit_order(synthetic(e, 1e-7, "model", 4), "m", false, "per-method");
  EXPECT_FALSE(f.fitted.has_value());
  EXPECT_NE(f.reason.find("the model N·u·s marks finer levels whose errors still fall at about "
                          "order 4 (pairwise orders 4.00 4.00)"),
            std::string::npos)
      << f.reason;
  EXPECT_NE(f.reason.find("--floor auto"), std::string::npos) << f.reason;
  // A given floor: the advice is to lower it.
  const OrderFit g = fit_order(synthetic(e, 1e-7, "given", 4), "m", false, "common");
  EXPECT_NE(g.reason.find("a smaller --floor keeps them"), std::string::npos) << g.reason;
}

// Orders still approaching the classical one when the floor ends the ladder: pre-asymptotic, and
// no "add --levels" (finer levels are at the floor); errors built with pairwise orders 2.0 2.6
// 3.2 then a plateau at 1e-12 under a measured floor of 2e-13, for an order-4 method.
TEST(RoundoffFloor, PreAsymptoticUpToTheFloorDoesNotAdviseMoreLevels) {
  std::vector<double> e = {1e-3};
  for (double q : {2.0, 2.6, 3.2}) e.push_back(e.back() / std::pow(2.0, q));
  e.push_back(1e-12);
  e.push_back(1.2e-12);
  const OrderFit f = fit_order(synthetic(e, 2e-13, "perturbed", 4), "m", false, "common");
  EXPECT_FALSE(f.fitted.has_value());
  EXPECT_EQ(f.reason.rfind("pre-asymptotic: the pairwise orders above the floors are still "
                           "moving towards 4",
                           0),
            0u)
      << f.reason;
  EXPECT_EQ(f.reason.find("add --levels"), std::string::npos) << f.reason;
  EXPECT_NE(f.reason.find("smaller --refine"), std::string::npos) << f.reason;
  // The same orders without a floor below them: finer levels can settle them.
  e.resize(4);
  const OrderFit g = fit_order(synthetic(e, 1e-20, "perturbed", 4), "m", false, "common");
  EXPECT_NE(g.reason.find("add --levels"), std::string::npos) << g.reason;
}

// The Jacobian of the CHEMAKZO test system against central differences of f (an independent
// computation), at the initial state and at the reference state.
TEST(RoundoffFloor, ChemAkzoJacobianMatchesFiniteDifferences) {
  const ChemAkzo sys;
  Vec yref(5);
  sys.exact(180, yref);
  const std::vector<Vec> states = {sys.initial_state() + Vec::Constant(5, 1e-3), yref};
  for (const Vec& y : states) {
    SparseMat jac;
    sys.jacobian(0, y, jac);
    const Eigen::MatrixXd j(jac);
    for (Index c = 0; c < 5; ++c) {
      const double d = 1e-7 * std::max(1e-3, std::abs(y[c]));
      Vec yp = y, ym = y, fp(5), fm(5);
      yp[c] += d;
      ym[c] -= d;
      sys.rhs(0, yp, fp);
      sys.rhs(0, ym, fm);
      const Vec col = (fp - fm) / (2 * d);
      for (Index r = 0; r < 5; ++r)
        EXPECT_NEAR(j(r, c), col[r], 1e-6 * (1 + std::abs(col[r]))) << r << "," << c;
    }
  }
}

// CHEMAKZO to t = 180 (the IVP Test Set's reference there) on the common ladder h = 0.1 … 0.1/64
// (1,800 to 115,200 steps). The model floor 10·N·u (s = 1) is 2e-12 … 1.3e-10, above radau5's
// errors from h = 0.025 on (2.7e-13, then 8.6e-15, pairwise order 5.00); the measured floor (the
// rounding of a damped problem: the finest levels plateau at 2e-15 … 4e-15) keeps them, and the
// errors below 1e-14 that stop falling are `floor`. radau5 is fitted at its order 5 and sdirk3
// at 3 within 0.1 (Hairer & Wanner II: Radau IIA order 5, Alexander's SDIRK order 3); no row
// whose pairwise order is within 0.1 of the classical one is marked `floor`.
TEST(RoundoffFloor, ChemAkzoKeepsRowsBelowTheModelFloorAndFits) {
  ConvergenceSpec spec;
  spec.model = "test_chemakzo";
  spec.integrators = {"radau5", "sdirk3"};
  spec.t_end = 180;
  spec.h = 0.1;
  spec.levels = 7;
  const auto res = run_convergence(inputs_of(spec, chemakzo()), spec, nullptr);
  for (const auto& f : res.fits) {
    ASSERT_TRUE(f.fitted.has_value()) << f.integrator << ": " << f.reason;
    EXPECT_NEAR(*f.fitted, f.order, 0.1) << f.integrator << ": " << f.reason;
    EXPECT_EQ(f.floor_source, "perturbed");
  }
  int below_model = 0;
  for (const auto& r : res.rows) {
    if (r.at_floor && r.observed_order) {
      EXPECT_GT(std::abs(*r.observed_order - r.order), kOrderTolerance)
          << r.integrator << " h = " << r.h;
    }
    below_model += !r.at_floor && r.error <= kFloorFactor * r.roundoff_floor ? 1 : 0;
  }
  EXPECT_GE(below_model, 2);  // radau5 at h = 0.025 and 0.0125
  // Per-method ladders (radau5 from h = 0.119, its finest error 6e-16 just above its floor and
  // still at order 5): the same fit and rule.
  spec.ladder = "per-method";
  spec.levels = 6;
  spec.integrators = {"radau5"};
  const auto own = run_convergence(inputs_of(spec, chemakzo()), spec, nullptr);
  ASSERT_TRUE(own.fits[0].fitted.has_value()) << own.fits[0].reason;
  EXPECT_NEAR(*own.fits[0].fitted, 5.0, 0.1) << own.fits[0].reason;
  for (const auto& r : own.rows) {
    if (r.at_floor && r.observed_order) {
      EXPECT_GT(std::abs(*r.observed_order - r.order), kOrderTolerance) << "h = " << r.h;
    }
  }
  // --floor model: radau5 keeps only the two coarsest levels, no fit (the reported problem).
  spec.ladder = "common";
  spec.levels = 7;
  spec.floor = "model";
  spec.integrators = {"radau5"};
  const auto old = run_convergence(inputs_of(spec, chemakzo()), spec, nullptr);
  EXPECT_FALSE(old.fits[0].fitted.has_value());
  EXPECT_NE(old.fits[0].reason.find("only 2 levels above the round-off floor (the model N·u·s)"),
            std::string::npos)
      << old.fits[0].reason;
}

}  // namespace
}  // namespace stiffbench
