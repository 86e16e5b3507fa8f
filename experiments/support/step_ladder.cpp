#include "experiments/support/step_ladder.hpp"

#include <algorithm>
#include <cmath>

#include "experiments/support/order_fit.hpp"
#include "experiments/support/step_study.hpp"

namespace stiffbench {

// Stage 1: from h, towards the coarsest step allowed, where the error is about `target`, while
// fewer than kProbeRuns - 2 runs (counted in `runs` by `probe`) have been made.
ProbeBracket probe_coarsest(double h, double lo, double hi, double target, int q, const int& runs,
                            const ProbeFn& probe, const ProbeFn& floor_at) {
  ProbeBracket b;
  const int stage1_runs = kProbeRuns - 2;
  while (runs < stage1_runs) {
    const double e = probe(h);
    double next;
    if (std::isfinite(e) && e > target && e <= 2 * target && e > kFloorFactor * floor_at(h)) {
      // Within a factor 2 above the target: close enough; the step e ∝ h^p gives the target.
      b.h_hint = h * std::pow(target / e, 1.0 / q);
      break;
    }
    if (!std::isfinite(e) || e > target) {
      if (!(b.h_above > 0) || h < b.h_above) {
        b.h_above = h;
        b.e_above = std::isfinite(e) ? e : 0;
      }
      if (h <= lo) break;
      next = std::max(lo, h / 4);
    } else if (e <= kFloorFactor * floor_at(h)) {
      b.floor_hit = true;
      b.h_below = std::max(b.h_below, h);
      b.e_below = 0;
      if (h >= hi) break;
      next = std::min(hi, h * 4);
    } else {
      b.h_below = h;
      b.e_below = e;
      if (e > target / 3) break;  // within a factor 3 below the target: close enough
      if (h >= hi) break;
      next = std::min(hi, h * std::pow(target / e, 1.0 / q));
    }
    // Inside a bracket: interpolate in log-log when both ends have errors, else bisect.
    if (b.h_below > 0 && b.h_above > 0) {
      if (b.e_below > 0 && b.e_above > 0)
        next = b.h_below * std::exp(std::log(b.h_above / b.h_below) * std::log(target / b.e_below) /
                                    std::log(b.e_above / b.e_below));
      else
        next = std::sqrt(b.h_below * b.h_above);
      next = std::clamp(next, std::min(b.h_below, b.h_above), std::max(b.h_below, b.h_above));
    }
    if (std::abs(next - h) <= 0.02 * h) break;  // no progress (e.g. the same step count)
    h = next;
  }
  return b;
}

// h_top: the largest usable probe at or below the target, else the model's prediction.
double top_step(const ProbeBracket& b, const std::vector<std::pair<double, double>>& good,
                double target, double lo, double hi, int q) {
  double h_top = 0;
  for (const auto& [gh, ge] : good)
    if (ge <= target) h_top = std::max(h_top, gh);
  if (!(h_top > 0)) h_top = std::clamp(b.h_below > 0 ? b.h_below : lo, lo, hi);
  if (b.h_hint > 0) h_top = std::clamp(std::max(h_top, b.h_hint), lo, hi);
  if (b.h_hint == 0 && b.e_below > 0 && b.e_below < target / 3) {
    const double predicted = b.h_below * std::pow(target / b.e_below, 1.0 / q);
    // Never at or beyond a step whose run failed or overshot the target.
    if (!(b.h_above > 0) || predicted < b.h_above) h_top = std::min(hi, std::max(h_top, predicted));
  }
  return h_top;
}

// Stage 2: the ladder moves down (at most by its own length span = h0/h_finest, not below lo)
// from h_top until its finest error is about kLadderFloorMargin times the floors: the most
// asymptotic levels. Returns h0.
double probe_finest(double h_top, double lo, double span, int q, const int& runs,
                    const ProbeFn& probe, const ProbeFn& predict, const ProbeFn& floor_at,
                    const std::function<void(double)>& calibrate) {
  const double h0_min = std::max(lo, h_top / span);
  const double fine_lo = h0_min / span, fine_hi = h_top / span;
  double h_fine = fine_hi;
  if (calibrate) calibrate(fine_hi);
  auto fine_target = [&](double hf) { return kLadderFloorMargin * floor_at(hf); };
  if (predict(h_fine) <= fine_target(h_fine)) return h_top;  // already reaches the floor region
  for (int it = 0; it < 3; ++it)
    h_fine = std::clamp(h_fine * std::pow(fine_target(h_fine) / predict(h_fine), 1.0 / q), fine_lo,
                        fine_hi);
  while (runs < kProbeRuns) {
    const double e = probe(h_fine);
    if (!std::isfinite(e)) break;
    const double ratio = fine_target(h_fine) / std::max(e, 1e-300);
    if (std::abs(std::log(ratio)) <= std::log(3.0)) break;
    const double next =
        std::clamp(h_fine * std::clamp(std::pow(ratio, 1.0 / q), 1.0 / 16, 16.0), fine_lo, fine_hi);
    if (next == h_fine) break;
    h_fine = next;
  }
  return std::clamp(h_fine * span, h0_min, h_top);
}

}  // namespace stiffbench
