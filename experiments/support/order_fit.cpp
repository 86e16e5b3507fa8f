#include "experiments/support/order_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "experiments/output/output.hpp"

namespace stiffbench {

namespace {

// %g: the documented constants in sentences (10, 0.2, 0.01).
std::string g_short(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// One integrator's rows in ladder order, which of them can enter a fit (ran ok, above the
// floors, positive error) and the pairwise observed order between level b-1 and b.
struct FitLevels {
  std::vector<const FitPoint*> rs;
  std::vector<bool> usable;
  double pair_order(std::size_t b) const {
    return std::log(rs[b - 1]->error / rs[b]->error) / std::log(rs[b - 1]->h / rs[b]->h);
  }
  // The pairwise orders of consecutive usable levels b in [from, to), as "q q q".
  std::string pair_orders(std::size_t from, std::size_t to) const {
    std::string s;
    for (std::size_t b = std::max<std::size_t>(from, 1); b < to; ++b)
      if (usable[b] && usable[b - 1]) s += (s.empty() ? "" : " ") + format_fixed(pair_order(b), 2);
    return s;
  }
};

// The longest run of consecutive usable levels whose pairwise orders agree within
// kOrderAgreement; the finest of equally long runs. {first level, length}.
std::pair<std::size_t, std::size_t> asymptotic_window(const FitLevels& lv) {
  const std::size_t n = lv.rs.size();
  std::size_t best_a = 0, best_len = 0;
  for (std::size_t a = 0; a < n; ++a) {
    if (!lv.usable[a]) continue;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::size_t len = 1;
    for (std::size_t b = a + 1; b < n && lv.usable[b]; ++b) {
      const double q = lv.pair_order(b);
      lo = std::min(lo, q);
      hi = std::max(hi, q);
      if (!(hi - lo <= kOrderAgreement)) break;
      len = b - a + 1;
    }
    if (len >= best_len) {
      best_len = len;
      best_a = a;
    }
  }
  return {best_a, best_len};
}

// Least-squares slope of log error against log h over levels [a, a + len) (len >= 3) and its
// standard error sqrt(SSR / (m - 2) / Sxx).
std::pair<double, double> slope_and_se(const FitLevels& lv, std::size_t a, std::size_t len) {
  std::vector<double> x, y;
  for (std::size_t i = a; i < a + len; ++i) {
    x.push_back(std::log(lv.rs[i]->h));
    y.push_back(std::log(lv.rs[i]->error));
  }
  const double m = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i] / m;
    my += y[i] / m;
  }
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  const double slope = sxy / sxx;
  double ssr = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double res = y[i] - (my + slope * (x[i] - mx));
    ssr += res * res;
  }
  return {slope, std::sqrt(ssr / (m - 2) / sxx)};
}

// The last three pairwise orders up to level `last` (consecutive levels above the floors, two
// when only two exist), finest first.
std::vector<double> last_pair_orders(const FitLevels& lv, std::size_t last) {
  std::vector<double> q;
  for (std::size_t b = last; b >= 1 && q.size() < 3 && lv.usable[b] && lv.usable[b - 1]; --b)
    q.push_back(lv.pair_order(b));
  return q;
}

// Where the last three pairwise orders q1, q2, q3 (coarse to fine; `q` holds them finest first)
// are heading when their steps d1 = q2 - q1, d2 = q3 - q2 have one sign and shrink by a ratio
// r = d2/d1 ≤ 0.75: Aitken's extrapolation q3 + d2 r/(1 - r). Nothing otherwise (nearer r = 1
// the extrapolation is too sensitive to mean anything).
std::optional<double> order_limit(const std::vector<double>& q) {
  if (q.size() < 3) return std::nullopt;
  const double d2 = q[0] - q[1], d1 = q[1] - q[2];
  if (!(d1 * d2 > 0 && std::abs(d2) <= 0.75 * std::abs(d1))) return std::nullopt;
  const double r = d2 / d1;
  return q[0] + d2 * r / (1 - r);
}

// Whether the last pairwise orders q (last_pair_orders) are still moving towards the expected
// slope: they each step towards it, by more than kOrderTolerance in all, and, when the steps
// shrink enough for order_limit, its extrapolated limit is within kOrderReductionSpread of it. A
// pre-asymptotic approach (e.g. backward Euler on a stiff cloth: 0.37 0.62 0.79 0.89, whose limit
// is 1.03) then is not read as a steady reduced order, while orders converging to another value (a
// true reduction) or wandering (noise) are.
bool orders_approach(const std::vector<double>& q, double expected) {
  if (q.size() < 2) return false;
  const double toward = expected - q[0];  // the direction still to go
  const double d2 = q[0] - q[1];
  const double d1 = q.size() == 3 ? q[1] - q[2] : d2;
  if (!(d1 * toward > 0 && d2 * toward > 0)) return false;
  if (std::abs(q.back() - q[0]) <= kOrderTolerance) return false;
  const auto limit = order_limit(q);
  return !limit || std::abs(*limit - expected) <= kOrderReductionSpread;
}

// How a reduced order behaves at the window's fine end, from its last pairwise orders q
// (last_pair_orders, finest first): steady when they agree within kOrderTolerance, else still
// falling or rising (from the coarsest of them to the finest); order_limit then tells where they
// level off.
std::string reduced_trend(const std::vector<double>& q) {
  if (q.size() < 2 ||
      *std::max_element(q.begin(), q.end()) - *std::min_element(q.begin(), q.end()) <=
          kOrderTolerance)
    return "a steady reduced order on this problem";
  return std::string("a reduced order on this problem, still ") +
         (q.front() < q.back() ? "falling" : "rising") + " at the window's fine end (" +
         format_fixed(q.back(), 2) + " to " + format_fixed(q.front(), 2) + ")";
}

// The round-off floor of a row in words: how it was found and its value.
std::string roundoff_words(const FitPoint& r) {
  if (r.floor_source == "perturbed")
    return "the round-off floor (measured by perturbed reruns: " + format_short(r.floor_used) + ")";
  if (r.floor_source == "given")
    return "the round-off floor (--floor " + format_short(r.floor_used) + ")";
  return "the round-off floor (the model N·u·s)";
}

// The finest usable level at or after `from` (`from` itself when none is finer).
std::size_t finest_usable(const FitLevels& lv, std::size_t from) {
  std::size_t last = from;
  for (std::size_t b = from; b < lv.rs.size(); ++b)
    if (lv.usable[b]) last = b;
  return last;
}

// Whether a level finer than `last` (the finest usable one) is at a floor: the floor, not the
// ladder's length, ends the usable levels, so finer steps cannot add usable ones.
bool floor_ends_ladder(const FitLevels& lv, std::size_t last) {
  for (std::size_t b = last + 1; b < lv.rs.size(); ++b)
    if (lv.rs[b]->at_floor) return true;
  return false;
}

// The pairwise orders through the round-off floor rows just finer than `last` (ok rows with a
// positive error, at most two pairs), as "q q" when each is within 0.3 of the expected slope: the
// floor marks levels whose errors still fall at the method's order. Empty otherwise.
std::string orders_through_floor(const FitLevels& lv, std::size_t last, double expected) {
  std::string s;
  int pairs = 0;
  for (std::size_t b = last + 1; b < lv.rs.size() && pairs < 2; ++b) {
    const auto& r = *lv.rs[b];
    const auto& p = *lv.rs[b - 1];
    if (!r.at_floor || r.status != Status::ok || !(r.error > 0) || !(p.error > 0) ||
        p.status != Status::ok)
      break;
    if (r.error > kFloorFactor * r.floor_used) break;  // at the reference's floor, not round-off
    const double q = lv.pair_order(b);
    if (!(std::abs(q - expected) <= 0.3)) return "";
    s += (s.empty() ? "" : " ") + format_fixed(q, 2);
    ++pairs;
  }
  return s;
}

// What changes the result when the floor ends the ladder below its finest usable level `last`: a
// floor that marks levels whose errors still fall at the expected slope is named (the model
// bound: --floor auto measures it; a given one: lower it); otherwise a denser ladder, which keeps
// more levels above the floor over the same range of errors.
std::string floor_end_advice(const FitLevels& lv, std::size_t last, double expected) {
  const auto& r = *lv.rs[std::min(last + 1, lv.rs.size() - 1)];
  const std::string through = orders_through_floor(lv, last, expected);
  if (!through.empty()) {
    const std::string marks = " marks finer levels whose errors still fall at about order " +
                              std::to_string(static_cast<int>(expected)) + " (pairwise orders " +
                              through + ")";
    if (r.floor_source == "given")
      return "--floor " + format_short(r.floor_used) + marks + ": a smaller --floor keeps them";
    if (r.floor_source != "perturbed")
      return "the model N·u·s" + marks + ": --floor auto measures the floor instead of bounding it";
    return "the measured floor" + marks + ": a smaller --refine puts more levels above it";
  }
  return "the floor ends the ladder below them: a smaller --refine puts more levels above it";
}

// What gives more levels where the pairwise orders can settle: finer steps, unless the floor ends
// the ladder (floor_end_advice); a per-method ladder ends about kLadderFloorMargin times above the
// floors by design, whatever --levels says, so only a common ladder goes finer.
std::string finer_levels_advice(const FitLevels& lv, std::size_t last, double expected,
                                const std::string& ladder) {
  if (floor_ends_ladder(lv, last)) return floor_end_advice(lv, last, expected);
  if (ladder == "per-method")
    return "the per-method ladder ends about " + g_short(kLadderFloorMargin) +
           "x above the floors by design: --ladder common with a smaller --h goes down to " +
           g_short(kFloorFactor) + "x";
  return "add --levels or use a smaller --h";
}

// What the pairwise orders of a fit window [a, a + len) and around it show.
struct WindowOrders {
  double q_first = 0, q_last = 0;  // the window's first and last pairwise orders
  double w_lo = 0, w_hi = 0;       // their range over the window
  // A coarser pair near the expected slope (within 0.3): the method showed its order there
  // and something else sets the error in the window.
  bool coarser_near = false;
  std::vector<double> last_orders;  // the pairwise orders up to the window's finest level
  // The finest usable level of the integrator (not only of the window): orders still moving
  // towards the expected slope there make the whole approach pre-asymptotic too.
  std::size_t last_usable = 0;
  bool approaching = false;
  bool near_floors = false;  // that level is within kLadderFloorMargin of its floors
};

WindowOrders window_orders(const FitLevels& lv, std::size_t a, std::size_t len, double expected) {
  WindowOrders w;
  w.q_first = lv.pair_order(a + 1);
  w.q_last = lv.pair_order(a + len - 1);
  w.w_lo = w.w_hi = w.q_first;
  for (std::size_t b = 1; b <= a; ++b)
    if (lv.usable[b] && lv.usable[b - 1] && std::abs(lv.pair_order(b) - expected) <= 0.3)
      w.coarser_near = true;
  for (std::size_t b = a + 1; b < a + len; ++b) {
    w.w_lo = std::min(w.w_lo, lv.pair_order(b));
    w.w_hi = std::max(w.w_hi, lv.pair_order(b));
  }
  w.last_orders = last_pair_orders(lv, a + len - 1);
  w.last_usable = finest_usable(lv, a + len - 1);
  w.approaching = orders_approach(w.last_orders, expected) ||
                  orders_approach(last_pair_orders(lv, w.last_usable), expected);
  const auto& finest = *lv.rs[w.last_usable];
  w.near_floors =
      finest.error <= kLadderFloorMargin * std::max(finest.floor_used, finest.reference_floor);
  return w;
}

// Why a fit over the window [a, a + len) is more than kOrderTolerance from the expected slope,
// read from the pairwise orders. A steady window (orders within 0.1): the method's order on this
// problem. The window's orders moving towards the expected slope: pre-asymptotic.
std::string off_fit_reason(const FitLevels& lv, std::size_t a, std::size_t len, double slope,
                           int expected_slope, const std::string& ladder) {
  const double expected = expected_slope;
  const std::string all = lv.pair_orders(1, lv.rs.size());
  const WindowOrders w = window_orders(lv, a, len, expected);
  const auto& [q_first, q_last, w_lo, w_hi, coarser_near, last_orders, last_usable, approaching,
               near_floors] = w;
  const auto limit = order_limit(last_orders);
  const std::string levelling =
      limit ? " (levelling off near " + format_fixed(*limit, 2) + ")" : std::string();
  std::string reason;
  // Pairwise orders still moving towards the classical order at the window's finest level
  // (orders_approach): pre-asymptotic, whatever the window's slope; not an order reduction.
  if (approaching)
    reason = "pre-asymptotic: the pairwise orders are still moving towards " +
             std::to_string(expected_slope) + " at the finest level above the floors (" + all +
             "), so " + format_fixed(slope, 2) + " is not the method's order on this problem: " +
             finer_levels_advice(lv, last_usable, expected, ladder);
  // Below the classical order by more than kOrderReductionSpread over a window whose pairwise
  // orders agree (within kOrderAgreement, as every fit window): the method's reduced order on
  // this problem.
  else if (slope < expected - kOrderReductionSpread && !coarser_near)
    reason = "order reduction to " + format_fixed(slope, 2) + " (classical " +
             std::to_string(expected_slope) + "): " + reduced_trend(last_orders) +
             ", as on stiff problems where the stage order or the lack of stiff accuracy sets "
             "it; pairwise orders " +
             all + levelling;
  else if (coarser_near)
    reason = "the error stops following h^" + std::to_string(expected_slope) +
             " below h = " + format_short(lv.rs[a]->h) +
             ": something other than the truncation error sets it there (a solver "
             "tolerance, order reduction or the reference); pairwise orders " +
             all;
  // Above the classical order by more than half an order down to the finest pair: more accurate
  // than the order promises (an error term vanishes on this problem), not a pre-asymptotic
  // approach from above (whose finest pairs come within half an order).
  else if (slope > expected + kOrderReductionSpread && q_last > expected + 0.5)
    reason = "a higher order than the classical " + std::to_string(expected_slope) + ": " +
             format_fixed(slope, 2) +
             " on this problem (a leading error term vanishes on it, e.g. a splitting whose "
             "parts commute on the solution's manifold, or a superconvergent point); pairwise "
             "orders " +
             all;
  // Above the classical order by less than half an order where the floors end the ladder: the
  // next error term still weighs there; the asymptotic order is not reached above the floors.
  else if (slope > expected && near_floors)
    reason = format_fixed(slope - expected, 2) + " above " + std::to_string(expected_slope) +
             " where the floors end the ladder (pairwise orders " + all +
             "): the next error term still weighs at these steps, so the asymptotic order is not "
             "reached above the floors";
  else if (w_hi - w_lo <= kOrderTolerance)
    reason = "a steady order of " + format_fixed(slope, 2) + ", not " +
             std::to_string(expected_slope) +
             ", on this problem (e.g. order reduction to the stage order on a stiff "
             "problem, or structure that changes the order); pairwise orders " +
             all;
  else if (std::abs(q_last - expected) < std::abs(q_first - expected))
    reason = "pre-asymptotic: the pairwise orders approach " + std::to_string(expected_slope) +
             " only slowly (" + all + ") down to the finest level above the floors";
  else
    reason = "fitted order differs from the classical one by " + format_fixed(slope - expected, 2) +
             "; pairwise orders " + all;
  // The finest usable level of the integrator (not only of the window) near the floors.
  if (!approaching && near_floors && !(slope > expected))
    reason += "; the floors (within " + g_short(kLadderFloorMargin) +
              "x of the finest level above them) stop the ladder before the orders settle";
  return reason;
}

// The fit over the window of `best_len` >= 3 consecutive agreeing levels from `best_a`, and the
// reason when it is off the expected slope or finer levels do not follow it.
void fit_over_window(const FitLevels& lv, std::size_t best_a, std::size_t best_len,
                     const std::string& ladder, OrderFit& fit) {
  const std::size_t n = lv.rs.size();
  const auto [slope, se] = slope_and_se(lv, best_a, best_len);
  fit.fitted = slope;
  fit.fitted_se = se;
  fit.h_max = lv.rs[best_a]->h;
  fit.h_min = lv.rs[best_a + best_len - 1]->h;
  fit.levels_used = static_cast<int>(best_len);
  // Levels finer than the window, above the floors, that do not agree with it: named even when
  // the fit is close to the expected slope (e.g. a solver tolerance that sets the error at fine
  // h must not disappear behind a clean fit over the coarse levels).
  const std::string finer = lv.pair_orders(best_a + best_len, n);
  if (!finer.empty())
    fit.reason = "levels finer than the window (h < " + format_short(fit.h_min) +
                 ") are above the floors but do not follow it (pairwise orders " + finer +
                 "): a solver tolerance, order reduction or the reference sets their error, "
                 "or they are still pre-asymptotic";
  if (std::abs(slope - fit.expected_slope) > kOrderTolerance) {
    // The finest pair above the floors within kOrderTolerance of the classical order, beyond
    // a window that is not: the window is the pre-asymptotic range (e.g. symplectic Euler on
    // the cloth: 2.16 2.04 2.01 2.00 1.99, then 1.00 where the first-order term takes over in
    // the max-norm), and the asymptotic order is the classical one. Otherwise the window's
    // reason, followed by the finer levels' note.
    double q_finest = std::numeric_limits<double>::quiet_NaN();
    std::size_t b_finest = 0;
    for (std::size_t b = best_a + best_len; b < n; ++b)
      if (lv.usable[b] && lv.usable[b - 1]) {
        q_finest = lv.pair_order(b);
        b_finest = b;
      }
    if (!finer.empty() && std::abs(q_finest - fit.expected_slope) <= kOrderTolerance)
      fit.reason = "pre-asymptotic window: the finest pair above the floors (h = " +
                   format_short(lv.rs[b_finest - 1]->h) + " to " +
                   format_short(lv.rs[b_finest]->h) + ") gives " + format_fixed(q_finest, 2) +
                   ", the classical order, after " + format_fixed(slope, 2) +
                   " over the window (pairwise orders " + lv.pair_orders(1, n) + "): " +
                   (floor_ends_ladder(lv, b_finest)
                        ? floor_end_advice(lv, b_finest, fit.expected_slope)
                        : "add levels below h = " + format_short(lv.rs[b_finest]->h) +
                              " to fit the asymptotic range");
    else
      fit.reason = off_fit_reason(lv, best_a, best_len, slope, fit.expected_slope, ladder) +
                   (finer.empty() ? "" : "; " + fit.reason);
  }
}

// No three consecutive usable levels agree: still approaching the order (pre-asymptotic) or
// wandering (unsettled); finer levels help unless the floor ends the ladder.
std::string unsettled_reason(const FitLevels& lv, int expected_slope, const std::string& ladder) {
  const std::size_t n = lv.rs.size();
  const double expected = expected_slope;
  std::size_t last = 0;
  for (std::size_t b = 0; b < n; ++b)
    if (lv.usable[b]) last = b;
  const std::string all = lv.pair_orders(1, n);
  const std::string agree = "no three consecutive levels agree within " + g_short(kOrderAgreement);
  if (orders_approach(last_pair_orders(lv, last), expected))
    return "pre-asymptotic: the pairwise orders above the floors are still moving "
           "towards " +
           std::to_string(expected_slope) + " (" + all + "; " + agree +
           "): " + finer_levels_advice(lv, last, expected, ladder);
  return "unsettled orders: the pairwise orders above the floors (" + all + ") " +
         "neither settle (" + agree + ") nor approach " + std::to_string(expected_slope) +
         " (noise, a solver tolerance or a change of regime at these steps): " +
         (floor_ends_ladder(lv, last) ? floor_end_advice(lv, last, expected)
                                      : "add --levels to see whether they settle at finer steps");
}

// After "only K levels above ": the round-off floor, how many rows are at it and what to change.
// The finest usable level (or the coarsest level when none is usable) and the first round-off floor
// row after it, whose floor the reason names.
std::string roundoff_reason(const FitLevels& lv, int n_usable, int n_roundoff, double expected,
                            const std::string& ladder) {
  std::size_t last = 0;
  for (std::size_t b = 0; b < lv.rs.size(); ++b)
    if (lv.usable[b]) last = b;
  const FitPoint* floor_row = nullptr;
  for (const auto* r : lv.rs)
    if (r->at_floor && r->error <= kFloorFactor * r->floor_used && !floor_row) floor_row = r;
  const std::string through = n_usable > 0 ? orders_through_floor(lv, last, expected) : "";
  std::string advice;
  if (!through.empty() && floor_row->floor_source != "perturbed")
    advice = floor_end_advice(lv, last, expected);
  else if (ladder == "per-method")
    advice =
        "use a larger --h (the probe's steps stay within [h/64, 16·h]) or a "
        "smaller --refine (the same levels over a shorter range of steps)";
  else
    advice = "use a larger --h or --ladder per-method";
  return roundoff_words(*floor_row) + ", " + std::to_string(n_roundoff) + " at it: " + advice;
}

}  // namespace

OrderFit fit_order(std::span<const FitPoint> points, int order, bool local,
                   const std::string& ladder) {
  OrderFit fit;
  FitLevels lv;
  for (const auto& r : points) lv.rs.push_back(&r);
  if (lv.rs.empty()) {
    fit.reason = "no rows";
    return fit;
  }
  fit.order = order;
  fit.expected_slope = fit.order + (local ? 1 : 0);
  const std::size_t n = lv.rs.size();
  lv.usable.assign(n, false);
  int n_usable = 0, n_roundoff = 0, n_reference = 0, n_failed = 0;
  std::string failed_status;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& r = *lv.rs[i];
    lv.usable[i] =
        r.status == Status::ok && !r.at_floor && std::isfinite(r.error) && r.error > 0 && r.h > 0;
    n_usable += lv.usable[i] ? 1 : 0;
    if (r.status != Status::ok) {
      ++n_failed;
      failed_status = to_string(r.status);
    } else if (r.at_floor) {
      ++(r.error <= kFloorFactor * r.floor_used ? n_roundoff : n_reference);
    }
  }
  const auto [best_a, best_len] = asymptotic_window(lv);
  if (best_len >= 3) {
    fit_over_window(lv, best_a, best_len, ladder, fit);
    return fit;
  }
  const std::string k = std::to_string(n_usable);
  const std::string level_word = n_usable == 1 ? " level" : " levels";
  const double expected = fit.expected_slope;
  if (n_usable >= 3) {
    fit.reason = unsettled_reason(lv, fit.expected_slope, ladder);
  } else if (n_roundoff > 0) {
    fit.reason = "only " + k + level_word + " above " +
                 roundoff_reason(lv, n_usable, n_roundoff, expected, ladder);
  } else if (n_reference > 0) {
    fit.reason = "only " + k + level_word +
                 " above the reference's accuracy: tighten --reference-rtol or use a more "
                 "accurate --reference";
  } else if (n_failed > 0) {
    fit.reason = "only " + k + level_word + " ran ok (the others ended " + failed_status +
                 "): use a smaller --h";
  } else {
    fit.reason = "only " + k + level_word + " with a positive error: add --levels";
  }
  return fit;
}

std::optional<double> fitted_order(std::span<const FitPoint> points, int n) {
  std::vector<double> lh, le;
  for (const auto& r : points)
    if (r.status == Status::ok && r.error > 0) {
      lh.push_back(std::log(r.h));
      le.push_back(std::log(r.error));
    }
  const std::size_t k = std::min(lh.size(), static_cast<std::size_t>(std::max(n, 0)));
  return least_squares_slope(std::vector<double>(lh.end() - k, lh.end()),
                             std::vector<double>(le.end() - k, le.end()));
}

}  // namespace stiffbench
