// The stages of the per-method ladder probe of the step-size studies (the rules:
// experiments/studies/convergence.hpp, "Ladders"): stage 1 finds the coarsest step allowed, stage
// 2 moves the ladder down towards the floors.
#pragma once

#include <functional>
#include <utility>
#include <vector>

namespace stiffbench {

constexpr double kLadderTop = 1e-2;  // per-method ladder: coarsest error ≤ about 1e-2·s
constexpr int kProbeRuns = 8;        // at most this many probe runs per integrator

// Stage 1 of the per-method probe: what the probes found about the target error.
struct ProbeBracket {
  double h_below = 0, h_above = 0;  // bracket: error below / above the target
  double e_below = 0, e_above = 0;
  bool floor_hit = false;
  double h_hint = 0;  // set when a probe lands just above the target
};

using ProbeFn = std::function<double(double)>;

// Stage 1: from h, towards the coarsest step allowed, where the error is about `target`, while
// fewer than kProbeRuns - 2 runs (counted in `runs` by `probe`) have been made.
ProbeBracket probe_coarsest(double h, double lo, double hi, double target, int q, const int& runs,
                            const ProbeFn& probe, const ProbeFn& floor_at);

// h_top: the largest usable probe at or below the target, else the model's prediction.
double top_step(const ProbeBracket& b, const std::vector<std::pair<double, double>>& good,
                double target, double lo, double hi, int q);

// Stage 2: the ladder moves down (at most by its own length span = h0/h_finest, not below lo)
// from h_top until its finest error is about kLadderFloorMargin times the floors: the most
// asymptotic levels. Returns h0.
double probe_finest(double h_top, double lo, double span, int q, const int& runs,
                    const ProbeFn& probe, const ProbeFn& predict, const ProbeFn& floor_at,
                    const std::function<void(double)>& calibrate);

}  // namespace stiffbench
