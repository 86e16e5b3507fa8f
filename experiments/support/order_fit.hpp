// The order fit of a step-size study (convergence, local-error): over the points of one
// integrator in ladder order (their floors applied), the asymptotic window is the longest run of
// consecutive levels that ran ok, are above both floors, and whose pairwise observed orders all
// lie within kOrderAgreement of each other (max − min); among equally long runs the finest. The
// fitted order is the least-squares slope of log(error) against log(h) over the window, with its
// standard error; with fewer than three levels there is no fit and the reason says what to change
// (experiments/studies/convergence.hpp states the rules of the reasons).
#pragma once

#include <optional>
#include <span>
#include <string>

#include "core/solve_stats.hpp"
#include "experiments/support/step_study.hpp"

namespace stiffbench {

constexpr double kOrderAgreement = 0.2;  // max − min of the pairwise orders in a fit window
constexpr double kOrderTolerance = 0.1;  // a fit further from the expected slope gets a reason
// A fit more than this below the classical order (its window's pairwise orders agreeing, as in
// every fit, and no coarser pair near the classical order) is reported as an order reduction to
// the fitted value: the reason names it.
constexpr double kOrderReductionSpread = 0.15;
// The per-method ladder aims its predicted finest error at this many times the larger floor (the
// fit's advice names it).
constexpr double kLadderFloorMargin = 100;

// One level of an integrator's ladder as the fit reads it.
struct FitPoint {
  double h = 0;      // the step actually taken
  double error = 0;  // NaN when the run failed
  Status status = Status::ok;
  bool at_floor = false;       // ok and within kFloorFactor of a floor
  double floor_used = 0;       // the round-off floor the level is checked against
  double reference_floor = 0;  // the reference's estimated accuracy (0: exact reference)
  std::string floor_source;    // how it was found: perturbed, model or given
};

// The order fit of one integrator (a row of NAME_orders.csv).
struct OrderFit {
  std::string integrator;
  int order = 0;  // the method's classical (claimed) order
  // The order its coefficients achieve (every order condition up to it holds; `analyze`), empty
  // for a method that is not coefficient-defined.
  std::optional<int> analysed_order;
  int expected_slope = 0;                   // order, or order + 1 for the local error
  std::optional<double> fitted, fitted_se;  // slope of log(error) against log(h) and its SE
  double h_min = 0, h_max = 0;              // the window's steps (0: no fit)
  int levels_used = 0;
  // The round-off floor of the integrator's rows and how it was found (perturbed, given; for
  // model the bound at its finest level).
  double floor_used = 0;
  std::string floor_source;
  // Why there is no fit, or why the fit is more than kOrderTolerance from the expected slope
  // (what the pairwise orders show); empty otherwise.
  std::string reason;
};

// The fit over the asymptotic window of the rows of `integrator` (in ladder order; their
// at_floor and status must be set). `local`: the expected slope is order + 1. `ladder`: the
// ladder that ran ("common" or "per-method"), so that the advice never names the one in use.
// The fit over the asymptotic window of one integrator's points (in ladder order) of classical
// order `order`. `local`: the expected slope is order + 1. `ladder`: the ladder that ran
// ("common" or "per-method"), so that the advice never names the one in use. The result's
// integrator is left empty.
OrderFit fit_order(std::span<const FitPoint> points, int order, bool local,
                   const std::string& ladder = "common");

// Least-squares slope of log(error) against log(h) over the last `n` points that ran ok with a
// positive error; empty when fewer than two.
std::optional<double> fitted_order(std::span<const FitPoint> points, int n = 3);

}  // namespace stiffbench
