#include "integrators/adaptive/embedded_rk.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stiffbench {

EmbeddedRungeKutta::EmbeddedRungeKutta(ButcherTableau tableau, std::string description,
                                       ControllerOptions opt)
    : Integrator({tableau.name,
                  Family::explicit_rk,
                  tableau.order,
                  tableau.stages() - (tableau.fsal ? 1 : 0),
                  {},
                  std::move(description)}),
      tableau_(std::move(tableau)),
      opt_(opt),
      ctrl_(opt, std::min(tableau_.order, tableau_.embedded_order) + 1) {
  // BadInput naming the defect (sizes, nodes, claimed orders, shape, FSAL); completes an
  // empty c.
  tableau_.validate(ButcherTableau::Shape::explicit_rk);
  require_input(tableau_.b_embedded.size() == tableau_.b.size(),
                "tableau '" + tableau_.name +
                    "' has no embedded weights (an embedded pair needs "
                    "b_embedded)");
  d_ = tableau_.b - tableau_.b_embedded;
}

void EmbeddedRungeKutta::reset(const OdeSystem& sys, double t0, CVecRef) {
  check_compatible(info(), sys);
  const Index n = sys.dimension();
  k_.resize(n, tableau_.stages());
  ytmp_.resize(n);
  ynew_.resize(n);
  err_.resize(n);
  work_.resize(n);
  t_ = t0;
  h_ = 0.0;
  k1_valid_ = false;
  counts_ = {};
  ctrl_.reset();
  cache_valid_ = false;
  cached_y_ = nullptr;
  const MechanicalSystem* m = sys.as_mechanical();
  constrained_ = m && m->has_constraints();
  if (constrained_) cached_values_.resize(n);
}

void EmbeddedRungeKutta::stages(const OdeSystem& sys, double t, CVecRef y, double h,
                                bool estimate) {
  const int s = tableau_.stages();
  const int last_explicit = tableau_.fsal ? s - 1 : s;  // FSAL: the last stage is f(t + h, y⁺)
  for (int i = 1; i < last_explicit; ++i) {
    ytmp_ = y;
    for (int j = 0; j < i; ++j)
      if (const double a = tableau_.a(i, j); a != 0.0) ytmp_.noalias() += (h * a) * k_.col(j);
    sys.rhs(t + tableau_.c[i] * h, ytmp_, k_.col(i));
  }
  ynew_ = y;
  for (int j = 0; j < s; ++j)
    if (const double b = tableau_.b[j]; b != 0.0) ynew_.noalias() += (h * b) * k_.col(j);
  if (tableau_.fsal) sys.rhs(t + h, ynew_, k_.col(s - 1));
  if (estimate) {
    err_.setZero();
    for (int j = 0; j < s; ++j)
      if (d_[j] != 0.0) err_.noalias() += (h * d_[j]) * k_.col(j);
  }
}

Status EmbeddedRungeKutta::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  const int s = tableau_.stages();
  // The driver computes step k's start as t0 + k·h, which may differ from the cached t + h by
  // rounding: the time test only rules out a restart elsewhere.
  const bool reuse = tableau_.fsal && cache_valid_ && cached_y_ == y.data() &&
                     std::abs(cached_t_ - t) <= 1e-12 * (std::abs(t) + std::abs(h)) &&
                     (!constrained_ || cached_values_ == y);
  if (reuse)
    k_.col(0) = k_.col(s - 1);
  else
    sys.rhs(t, y, k_.col(0));
  stages(sys, t, y, h, false);
  y = ynew_;
  if (tableau_.fsal) {
    cache_valid_ = true;
    cached_y_ = y.data();
    cached_t_ = t + h;
    if (constrained_) cached_values_ = y;
  }
  return Status::ok;
}

Status EmbeddedRungeKutta::advance_to(const OdeSystem& sys, double t_out, VecRef y,
                                      SolveStats& stats) {
  const int s = tableau_.stages();
  if (!k1_valid_) {
    sys.rhs(t_, y, k_.col(0));
    k1_valid_ = true;
  }
  if (h_ == 0.0)
    h_ = opt_.h0 > 0
             ? std::min(opt_.h0, t_out - t_)
             : ctrl_.initial_step(sys, t_, y, k_.col(0), tableau_.order, t_out - t_, ytmp_, work_);
  // Stage 1 of a trial is f(t, y): kept across rejections, taken from the last stage after an
  // accepted FSAL step, otherwise evaluated once at each new accepted point.
  const auto trial = [&](double t, double h) {
    if (!k1_valid_) {
      sys.rhs(t, y, k_.col(0));
      k1_valid_ = true;
    }
    stages(sys, t, y, h, true);
    if (!ynew_.allFinite()) return TrialResult{0.0, opt_.fac_min};
    return TrialResult{ctrl_.norm(err_, y, ynew_), 0.0};
  };
  const auto commit = [&](double, double) {
    y = ynew_;
    if (tableau_.fsal)
      k_.col(0) = k_.col(s - 1);
    else
      k1_valid_ = false;
  };
  const Status st =
      advance_adaptive(ctrl_, t_, t_out, h_, y, counts_, stats.message, trial, commit);
  stats.steps = counts_.accepted;
  stats.error_test_failures = counts_.rejected;
  return st;
}

}  // namespace stiffbench
