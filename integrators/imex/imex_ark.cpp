#include "integrators/imex/imex_ark.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/split_views.hpp"
#include "integrators/implicit/dirk.hpp"

namespace stiffbench {

namespace {

// Whether stage i's slope of table t enters a later stage, the weights or the embedded weights.
std::vector<char> slopes_used(const ButcherTableau& t) {
  const int s = t.stages();
  std::vector<char> used(static_cast<std::size_t>(s), 0);
  for (int i = 0; i < s; ++i) {
    bool u = t.b[i] != 0.0 || (t.b_embedded.size() == s && t.b_embedded[i] != 0.0);
    for (int j = i + 1; j < s; ++j) u = u || t.a(j, i) != 0.0;
    used[static_cast<std::size_t>(i)] = u ? 1 : 0;
  }
  return used;
}

}  // namespace

ImexArkIntegrator::ImexArkIntegrator(AdditiveTableau tableau, std::string description,
                                     ImplicitOptions opt, ControllerOptions control,
                                     bool error_filter)
    : Integrator({tableau.name, Family::imex, tableau.order, tableau.stages(),
                  Requirements{.split = true}, std::move(description)}),
      tab_(std::move(tableau)),
      core_(opt),
      filter_(error_filter),
      newton_tol_(opt.newton_tol),
      control_(control) {
  adaptive_ = tab_.has_embedded();
  if (adaptive_) ctrl_ = StepController(control_, std::min(tab_.order, tab_.embedded_order) + 1);
  need_e_ = slopes_used(tab_.explicit_table);
  need_i_ = slopes_used(tab_.implicit_table);
}

std::optional<LinearStability> ImexArkIntegrator::explicit_part_stability() const {
  return tableau_stability(tab_.explicit_table);
}

std::optional<LinearStability> ImexArkIntegrator::partitioned_stability() const {
  return partitioned_imex_stability(tab_);
}

void ImexArkIntegrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  require_split(sys, "integrator '" + info().name + "'");
  implicit_view_ = implicit_part_view(sys);
  view_of_ = &sys;
  core_.reset(*implicit_view_, t0, y0);
  core_.set_newton_tol(newton_tol_);
  const Index n = sys.dimension();
  ke_.setZero(n, tab_.stages());
  ki_.setZero(n, tab_.stages());
  for (Vec* v : {&psi_, &z_, &fz_, &ynew_, &err_, &work_, &work2_}) v->setZero(n);
  t_ = t0;
  h_ = 0.0;
  counts_ = {};
  ctrl_.reset();
}

Status ImexArkIntegrator::stages(const OdeSystem& sys, double t, VecRef y, double h,
                                 SolveStats& stats) {
  if (&sys != view_of_)
    throw std::logic_error("ImexArkIntegrator: step() on another system than reset()'s");
  const ButcherTableau& e = tab_.explicit_table;
  const ButcherTableau& im = tab_.implicit_table;
  const int s = tab_.stages();
  core_.new_step();
  z_ = y;  // predictor of the first implicit stage; later ones start from the previous z
  for (int i = 0; i < s; ++i) {
    psi_ = y;
    for (int j = 0; j < i; ++j) {
      if (const double a = e.a(i, j); a != 0.0) psi_.noalias() += (h * a) * ke_.col(j);
      if (const double a = im.a(i, j); a != 0.0) psi_.noalias() += (h * a) * ki_.col(j);
    }
    const double ti = t + im.c[i] * h;
    const double aii = im.a(i, i);
    const auto k = static_cast<std::size_t>(i);
    if (aii == 0.0) {
      z_ = psi_;
      if (need_i_[k]) sys.rhs_implicit_part(ti, z_, ki_.col(i));
    } else {
      const Status st = core_.solve_stage(*implicit_view_, ti, psi_, h * aii, z_, fz_, stats);
      if (st != Status::ok) return st;
      ki_.col(i) = (z_ - psi_) / (h * aii);  // from the stage equation (see the header)
    }
    if (need_e_[k]) sys.rhs_explicit_part(t + e.c[i] * h, z_, ke_.col(i));
  }
  for (int i = 0; i < s; ++i) {
    if (const double b = e.b[i]; b != 0.0) y.noalias() += (h * b) * ke_.col(i);
    if (const double b = im.b[i]; b != 0.0) y.noalias() += (h * b) * ki_.col(i);
  }
  return Status::ok;
}

Status ImexArkIntegrator::step(const OdeSystem& sys, double t, VecRef y, double h,
                               SolveStats& stats) {
  return stages(sys, t, y, h, stats);
}

void ImexArkIntegrator::embedded_difference(double h, VecRef e) const {
  e.setZero();
  const ButcherTableau& ex = tab_.explicit_table;
  const ButcherTableau& im = tab_.implicit_table;
  for (int i = 0; i < tab_.stages(); ++i) {
    if (const double d = ex.b[i] - ex.b_embedded[i]; d != 0.0) e.noalias() += (h * d) * ke_.col(i);
    if (const double d = im.b[i] - im.b_embedded[i]; d != 0.0) e.noalias() += (h * d) * ki_.col(i);
  }
}

Status ImexArkIntegrator::advance_to(const OdeSystem& sys, double t_out, VecRef y,
                                     SolveStats& stats) {
  if (!adaptive_) return Integrator::advance_to(sys, t_out, y, stats);
  const ButcherTableau& im = tab_.implicit_table;
  const double gamma = im.a(im.stages() - 1, im.stages() - 1);
  if (h_ == 0.0) {
    const int p = std::min(tab_.order, tab_.embedded_order);
    if (control_.h0 > 0) {
      h_ = std::min(control_.h0, t_out - t_);
    } else {
      sys.rhs_explicit_part(t_, y, fz_);
      sys.rhs_implicit_part(t_, y, psi_);
      fz_ += psi_;
      h_ = ctrl_.initial_step(sys, t_, y, fz_, p, t_out - t_, work_, work2_);
    }
  }
  const auto trial = [&](double t, double h) {
    // Newton tolerance two orders below the controller's scale (integrators/implicit/dirk.hpp).
    core_.set_newton_tol(adaptive_newton_tolerance(y, control_));
    ynew_ = y;
    const Status st = stages(sys, t, ynew_, h, stats);
    if (st != Status::ok || !ynew_.allFinite()) {
      stats.message.clear();  // the trial is retried with a smaller step
      return TrialResult{0.0, 0.5};
    }
    embedded_difference(h, err_);
    if (filter_ && gamma != 0.0) {
      if (!core_.prepare(h * gamma, stats)) return TrialResult{0.0, 0.5};
      work_.setZero();
      if (!core_.solve(err_, work_, stats)) return TrialResult{0.0, 0.5};
      err_ = work_;
    }
    return TrialResult{ctrl_.norm(err_, y, ynew_), 0.0};
  };
  const auto commit = [&](double, double) { y = ynew_; };
  const Status st =
      advance_adaptive(ctrl_, t_, t_out, h_, y, counts_, stats.message, trial, commit);
  stats.steps = counts_.accepted;
  stats.error_test_failures = counts_.rejected;
  return st;
}

}  // namespace stiffbench
