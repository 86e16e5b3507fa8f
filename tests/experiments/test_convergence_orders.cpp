// Asymptotic orders and per-method ladders: the floor check of convergence and
// local-error rows, the order fit over the asymptotic window (NAME_orders.csv) and the
// per-method ladder's probe.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "stiffbench/stiffbench.hpp"

namespace stiffbench {
namespace {

std::filesystem::path fresh_dir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("sb_orders_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

std::string first_line(const std::filesystem::path& file) {
  std::ifstream f(file);
  std::string line;
  std::getline(f, line);
  return line;
}

// Rows of one integrator with errors e_k at h_k = 0.1/2^k and a stand-in round-off floor,
// flagged at the floor by the study's rule (error <= kFloorFactor × floor).
std::vector<ConvergenceRow> synthetic(const std::vector<double>& errors, double floor) {
  std::vector<ConvergenceRow> rows;
  for (std::size_t k = 0; k < errors.size(); ++k) {
    ConvergenceRow r;
    r.integrator = "m";
    r.order = 4;
    r.h = 0.1 / std::pow(2.0, static_cast<double>(k));
    r.error = errors[k];
    r.roundoff_floor = floor;
    r.floor_used = floor;
    r.floor_source = "model";
    r.at_floor = r.error <= kFloorFactor * floor;
    rows.push_back(r);
  }
  return rows;
}

// e_k = h_k^4 (1 + 0.02 (-1)^k) + 1e-13: pairwise orders alternate 4 ± 0.058 (within the 0.2
// agreement) until the additive 1e-13 takes over; with a floor of 1e-13 the rows k >= 7
// (h^4 < 1e-12) are floor rows. Theory: the window is k = 0..6 and the least-squares slope over
// it is p = 4 within its standard error (an independent computation of this fit in Python gives
// 3.9974 ± 0.0071).
TEST(OrderFit, WindowExcludesFloorRowsAndRecoversTheOrder) {
  std::vector<double> e;
  for (int k = 0; k < 10; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    e.push_back(std::pow(h, 4) * (1 + 0.02 * (k % 2 ? -1 : 1)) + 1e-13);
  }
  const auto rows = synthetic(e, 1e-13);
  for (int k = 7; k < 10; ++k) EXPECT_TRUE(rows[static_cast<std::size_t>(k)].at_floor) << k;
  EXPECT_FALSE(rows[6].at_floor);
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_EQ(f.levels_used, 7);
  EXPECT_DOUBLE_EQ(f.h_max, 0.1);
  EXPECT_DOUBLE_EQ(f.h_min, 0.1 / 64);
  ASSERT_TRUE(f.fitted_se.has_value());
  EXPECT_GT(*f.fitted_se, 0.0);
  EXPECT_LT(*f.fitted_se, 0.02);
  EXPECT_LE(std::abs(*f.fitted - 4.0), *f.fitted_se);
  EXPECT_TRUE(f.reason.empty()) << f.reason;
  // The local study expects order + 1 from the same slope: the fit is the slope itself.
  EXPECT_EQ(fit_order(rows, "m", true).expected_slope, 5);
}

// A pre-asymptotic first level (error 3 times the h^4 line: pairwise order 4 + log2 3 = 5.58)
// is left out: the window starts at h_1.
TEST(OrderFit, WindowLeavesOutAPreAsymptoticLevel) {
  std::vector<double> e;
  for (int k = 0; k < 6; ++k) e.push_back(std::pow(0.1 / std::pow(2.0, k), 4) * (k == 0 ? 3 : 1));
  const OrderFit f = fit_order(synthetic(e, 1e-16), "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_EQ(f.levels_used, 5);
  EXPECT_DOUBLE_EQ(f.h_max, 0.05);
  EXPECT_NEAR(*f.fitted, 4.0, 1e-9);  // exact h^4 over the window
}

// A method more accurate than its order on this problem (Lie splitting whose error term vanishes,
// declared order 1) with errors h²(1 + h): the pairwise orders are 2 + log2((1+h)/(1+h/2)),
// 2.07 at h = 0.1 falling to 2.00, so they approach 2, not the declared 1; the reason says the
// order is higher than the classical one (it used to call this "pre-asymptotic").
TEST(OrderFit, AHigherOrderThanClassicalIsNamed) {
  std::vector<double> e;
  for (int k = 0; k < 6; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    e.push_back(h * h * (1 + h));
  }
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 1;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 2.0, 0.05);
  EXPECT_EQ(f.reason.rfind("a higher order than the classical 1: " + format_fixed(*f.fitted, 2), 0),
            0u)
      << f.reason;
}

// A saturated error that becomes first order only as h falls below h0, e = h h0 / (h + h0), with
// h0 = 0.002 (the shape of backward Euler on a stiff cloth, whose large steps damp the motion
// away). Theory: the pairwise orders are 1 + log2((h/2 + h0)/(h + h0)), rising monotonically
// from 0.03 at h = 0.1 to 0.88 at h = 3.9e-4, i.e. towards 1. The fit window (the longest run
// agreeing within 0.2) is the nearly flat coarse end, far below 1; the reason must call this
// pre-asymptotic, not a steady order reduction.
TEST(OrderFit, AnApproachTowardsTheClassicalOrderIsNotAnOrderReduction) {
  const double h0 = 0.002;
  std::vector<double> e;
  for (int k = 0; k < 9; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    e.push_back(h * h0 / (h + h0));
  }
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 1;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_LT(*f.fitted, 1.0 - kOrderReductionSpread);  // the window alone would look reduced
  EXPECT_EQ(f.reason.rfind("pre-asymptotic: the pairwise orders are still moving towards 1", 0), 0u)
      << f.reason;
  EXPECT_EQ(f.reason.find("order reduction to"), std::string::npos) << f.reason;
}

// The contrast: e = h^0.5 (1 + 2h), a true reduced order 1/2 for a first-order method. Theory:
// pairwise orders 0.5 + log2((1 + 2h)/(1 + h)), 0.63 at h = 0.1 falling towards 0.5, away from
// 1; the reason names the order reduction to the fitted value.
TEST(OrderFit, OrdersSettlingBelowTheClassicalOneAreAnOrderReduction) {
  std::vector<double> e;
  for (int k = 0; k < 6; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    e.push_back(std::sqrt(h) * (1 + 2 * h));
  }
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 1;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 0.55, 0.06);
  EXPECT_EQ(f.reason.rfind("order reduction to " + format_fixed(*f.fitted, 2), 0), 0u) << f.reason;
  // The last three pairwise orders, 0.535 0.518 0.509, agree within 0.1: steady.
  EXPECT_NE(f.reason.find("a steady reduced order"), std::string::npos) << f.reason;
}

// Pairwise orders built to be 1.00, 0.92, 0.84 for a second-order method: the window (all three
// pairs, spread 0.16 <= 0.2) is far below 2 and no pair comes near it, so the verdict is an order
// reduction; its last three pairs differ by 0.16 > 0.1 and fall, so it is not "steady" (rodas4
// on Prothero–Robinson, lambda = -1e6, from h = 0.1/4 shows 1.50 1.31 1.18 of this shape).
TEST(OrderFit, AFallingReducedOrderIsNotCalledSteady) {
  std::vector<double> e = {1e-2};
  for (double q : {1.00, 0.92, 0.84}) e.push_back(e.back() / std::pow(2.0, q));
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 2;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 0.92, 0.01);
  EXPECT_EQ(f.reason.rfind("order reduction to 0.92 (classical 2): a reduced order on this "
                           "problem, still falling at the window's fine end (1.00 to 0.84)",
                           0),
            0u)
      << f.reason;
}

// e = h^0.5 exactly: every pairwise order is 1/2 (log2 of 2^0.5), so the reduction is steady.
TEST(OrderFit, EqualPairwiseOrdersBelowTheClassicalOneAreASteadyReduction) {
  std::vector<double> e;
  for (int k = 0; k < 6; ++k) e.push_back(std::sqrt(0.1 / std::pow(2.0, k)));
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 1;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 0.5, 1e-9);
  EXPECT_EQ(f.reason.rfind("order reduction to 0.50 (classical 1): a steady reduced order", 0), 0u)
      << f.reason;
}

// The max-norm of an O(h²) component with a large constant and an O(h) one with a small
// constant, e = max(800 h², 0.25 h), for a first-order method (symplectic Euler on the cloth
// shows this). Theory: the pairwise orders are exactly 2 down to h = 3.9e-4, then log2(2.5) =
// 1.32 across the crossover h = 3.125e-4, then exactly 1. The window is the order-2 run, but the
// finest pair gives the classical order: the reason must say the window is pre-asymptotic, not
// that the method is more accurate than its order.
TEST(OrderFit, TheClassicalOrderAtTheFinestPairMakesTheWindowPreAsymptotic) {
  std::vector<double> e;
  for (int k = 0; k < 11; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    e.push_back(std::max(800 * h * h, 0.25 * h));
  }
  std::vector<ConvergenceRow> rows = synthetic(e, 1e-16);
  for (auto& r : rows) r.order = 1;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 2.0, 1e-9);
  EXPECT_EQ(f.levels_used, 9);
  EXPECT_EQ(f.reason.rfind("pre-asymptotic window: the finest pair above the floors", 0), 0u)
      << f.reason;
  EXPECT_NE(f.reason.find("gives 1.00, the classical order"), std::string::npos) << f.reason;
}

// Fewer than three levels above the floor: no fit, and the reason says what to change.
TEST(OrderFit, TooFewLevelsAboveTheFloorNamesTheFix) {
  const OrderFit f = fit_order(synthetic({1e-6, 6.25e-8, 1e-14, 2e-14, 1e-14}, 1e-14), "m", false);
  EXPECT_FALSE(f.fitted.has_value());
  EXPECT_EQ(f.levels_used, 0);
  EXPECT_NE(f.reason.find("only 2 levels above the round-off floor (the model N·u·s), 3 at it"),
            std::string::npos)
      << f.reason;
  EXPECT_NE(f.reason.find("larger --h"), std::string::npos) << f.reason;
  // Pairwise orders 1, 3, 1, 3 (errors falling by 2, 8, 2, 8): no three levels agree.
  const OrderFit g = fit_order(synthetic({1, 0.5, 0.0625, 0.03125, 0.00390625}, 1e-16), "m", false);
  EXPECT_FALSE(g.fitted.has_value());
  EXPECT_NE(g.reason.find("add --levels"), std::string::npos) << g.reason;
}

// A solver defect is not a floor: errors h^4 plus a Newton-tolerance term N·1e-12 (N = 100·2^k
// steps, a loose stage solve) rise when h halves from h = 0.1/16 on. The round-off
// floor N·u is 10⁴ times smaller, so those rows stay ok; the fit over the levels where the
// pairwise orders agree (h = 0.1 to 0.1/8: 4.00, 4.00, 3.95) is 4, and its reason names the finer
// levels that leave it (pairwise orders 3.0, -0.08, -0.96).
TEST(OrderFit, ANewtonToleranceFloorIsNotHidden) {
  std::vector<ConvergenceRow> rows;
  for (int k = 0; k < 7; ++k) {
    const double h = 0.1 / std::pow(2.0, k);
    const double steps = 100 * std::pow(2.0, k);
    rows.push_back(synthetic({std::pow(h, 4) + steps * 1e-12}, steps * kUnitRoundoff)[0]);
    rows.back().h = h;
  }
  for (const auto& r : rows) EXPECT_FALSE(r.at_floor) << r.h;
  const OrderFit f = fit_order(rows, "m", false);
  ASSERT_TRUE(f.fitted.has_value());
  EXPECT_EQ(f.levels_used, 4);
  EXPECT_NEAR(*f.fitted, 4.0, 0.1);
  EXPECT_NE(f.reason.find("levels finer than the window"), std::string::npos) << f.reason;
  EXPECT_NE(f.reason.find("-0.96"), std::string::npos) << f.reason;
}

// A real run: rk4 on the undamped oscillator (t_end = 10, N = 100·2^k steps), with the model
// floor (--floor model). Its global error is about t_end h^4/120 (the phase error of
// R(ih) = 1 - h^2/2 + h^4/24 - i(h - h^3/6) against e^{ih}): 6.5e-12 at h = 0.1/32, below the
// model floor 10·N·u = 3.6e-12 only from h = 0.1/64 on (4e-13 against 7.1e-12); the finest rows
// are at 1e-15..1e-14 with meaningless pairwise orders. Those rows get status floor and the fit
// over the levels above them is 4 ± 0.1.
TEST(OrderFit, Rk4OnTheOscillatorReachesTheRoundoffFloor) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 10;
  spec.h = 0.1;
  spec.levels = 10;
  spec.floor = "model";
  const auto res = run_convergence(spec, nullptr);
  ASSERT_EQ(res.rows.size(), 10u);
  int floor_rows = 0;
  for (const auto& r : res.rows) {
    // The round-off floor of a row: N u max(1, |y0|, |y_ref|) with |y| = 1 here.
    EXPECT_NEAR(r.roundoff_floor, static_cast<double>(r.steps) * 0x1p-53, 1e-3 * r.roundoff_floor);
    if (r.at_floor) {
      ++floor_rows;
      EXPECT_EQ(r.status_text(), "floor");
      EXPECT_LE(r.error, kFloorFactor * r.roundoff_floor);
      EXPECT_LE(r.h, 0.1 / 32);
    }
  }
  EXPECT_GE(floor_rows, 3);
  EXPECT_EQ(res.rows.back().status_text(), "floor");
  ASSERT_EQ(res.fits.size(), 1u);
  const OrderFit& f = res.fits[0];
  ASSERT_TRUE(f.fitted.has_value()) << f.reason;
  EXPECT_NEAR(*f.fitted, 4.0, 0.1);
  EXPECT_GE(f.levels_used, 4);
  EXPECT_GE(f.h_min, 0.1 / 32);
  // The CSV marks the floor rows in its status column.
  const Table t = convergence_table(res);
  EXPECT_EQ(t.rows.back()[11], "floor");
}

// The columns: convergence.csv and local_error.csv keep their contract columns and add the
// solver counters and the two floors; NAME_orders.csv has exactly its contract columns; the JSON
// records the reference check of a numerical reference, which the cache keeps under its own key.
// The orders table carries the order the coefficients achieve beside the claimed one: rk4 meets
// Kutta's eight conditions up to order 4 and fails the order-5 tall tree (bᵀA⁴1 = 0 ≠ 1/120),
// ros3p meets the Rosenbrock conditions to order 3 (Lang & Verwer 2001); bdf2 is a multistep
// method with no tableau, so its entry is empty.
TEST(OrderFit, OrdersTableShowsTheAnalysedOrder) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4", "ros3p", "bdf2"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 3;
  const auto res = run_convergence(spec, nullptr);
  ASSERT_EQ(res.fits.size(), 3u);
  EXPECT_EQ(res.fits[0].analysed_order, 4);
  EXPECT_EQ(res.fits[1].analysed_order, 3);
  EXPECT_FALSE(res.fits[2].analysed_order.has_value());
}

TEST(OrderFit, OutputColumnsAndReferenceCheck) {
  const auto dir = fresh_dir("cols");
  ConvergenceSpec spec;
  spec.model = "pendulum";
  spec.reference = "rk4";
  spec.integrators = {"heun", "rk4"};
  spec.t_end = 2;
  spec.h = 0.1;
  spec.levels = 4;
  std::ostringstream err;
  const auto res = convergence_study(spec, dir.string(), false, nullptr, err);
  const std::string counters =
      ",newton_iters,newton_conv_failures,error_test_failures,"
      "linear_setups,linear_iters,fe_evals,fi_evals,roundoff_floor,reference_floor,floor_used,"
      "floor_source";
  EXPECT_EQ(first_line(dir / "convergence.csv"),
            "model,integrator,order,h,steps,error,observed_order,f_evals,jac_evals,lin_solves,"
            "wall_s,status" +
                counters);
  EXPECT_EQ(first_line(dir / "convergence_orders.csv"),
            "integrator,order,analysed_order,fitted_order,fitted_order_se,h_min,h_max,levels_used,"
            "reason,floor_used,floor_source");
  std::ifstream js(dir / "convergence.json");
  const auto meta = nlohmann::json::parse(js);
  ASSERT_TRUE(meta.contains("reference_accuracy")) << meta.dump(2);
  // The reference is rk4 at (finest h)/16 = 0.1/8/16, its check at half that step: their
  // difference is about 15/16 of the first one's error, C h^4 with C of order 1e-2..1 here.
  const double acc = meta["reference_accuracy"].get<double>();
  EXPECT_GT(acc, 0.0);
  EXPECT_LT(acc, 1e-8);
  EXPECT_EQ(meta["ladder"], "common");
  EXPECT_EQ(res.rows.front().reference_floor, acc);
  // Two cache files (the reference and its check); a second run reuses both.
  int cached = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "reference"))
    cached += e.path().extension() == ".csv" ? 1 : 0;
  EXPECT_EQ(cached, 2);
  spec.cache_dir = dir.string();
  const auto again = run_convergence(spec, nullptr);
  EXPECT_TRUE(again.reference_from_cache);
  EXPECT_EQ(again.reference_accuracy, res.reference_accuracy);

  const auto ldir = fresh_dir("lcols");
  ConvergenceSpec lspec;
  lspec.model = "harmonic_oscillator";
  lspec.integrators = {"heun"};
  lspec.h = 0.1;
  lspec.levels = 3;
  convergence_study(lspec, ldir.string(), true, nullptr, err);
  EXPECT_EQ(first_line(ldir / "local_error.csv"),
            "model,integrator,order,h,local_error,observed_order,status,f_evals,jac_evals,"
            "lin_solves" +
                counters);
  EXPECT_EQ(first_line(ldir / "local_error_orders.csv"),
            "integrator,order,analysed_order,fitted_order,fitted_order_se,h_min,h_max,levels_used,"
            "reason,floor_used,floor_source");
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(ldir);
}

// Per-method ladders on the oscillator (s = 1): each method's coarsest error is at most about
// 1e-2 (the probe's target, within its factor 3), no row reaches a floor, and the fitted order
// is the classical one within 0.1. A high-order method's ladder moves towards the floor: its
// finest error is above kLadderFloorMargin/3 × its measured round-off floor (the probe aims at
// 100 × floor within a factor 3, from a measurement that grows in proportion to the steps, at
// least the √N growth of floor_used) and within a factor 30 of kLadderFloorMargin × the model
// floor (which is above the measured one).
TEST(OrderFit, PerMethodLadderKeepsErrorsInTheDocumentedRange) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"euler", "rk4", "gauss6"};
  spec.t_end = 10;
  spec.h = 0.1;
  spec.levels = 5;
  spec.ladder = "per-method";
  const auto res = run_convergence(spec, nullptr);
  ASSERT_EQ(res.rows.size(), 15u);
  ASSERT_EQ(res.ladders.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& first = res.rows[5 * i];
    const auto& last = res.rows[5 * i + 4];
    // h0 is the ladder's first step (the driver takes N = round(T/h) steps).
    EXPECT_EQ(first.steps, std::lround(spec.t_end / res.ladders[i].h0));
    EXPECT_LE(first.error, 3e-2) << first.integrator;
    EXPECT_GT(last.error, kLadderFloorMargin / 3 * last.floor_used) << last.integrator;
    for (std::size_t k = 0; k < 5; ++k) EXPECT_FALSE(res.rows[5 * i + k].at_floor);
    ASSERT_TRUE(res.fits[i].fitted.has_value()) << res.fits[i].reason;
    EXPECT_NEAR(*res.fits[i].fitted, res.fits[i].order, 0.1) << res.fits[i].integrator;
    EXPECT_LE(res.ladders[i].probes.size(), static_cast<std::size_t>(kProbeRuns));
  }
  const auto& g = res.rows[14];
  EXPECT_EQ(g.integrator, "gauss6");
  EXPECT_LT(g.error, 30 * kLadderFloorMargin * g.roundoff_floor);
}

TEST(OrderFit, LadderChoiceIsValidated) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.ladder = "own";
  EXPECT_THROW(spec.validate(), BadInput);
}

}  // namespace
}  // namespace stiffbench
