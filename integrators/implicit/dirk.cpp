#include "integrators/implicit/dirk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "integrators/method_entry.hpp"
#include "integrators/method_file.hpp"

namespace stiffbench {

namespace {

// Floor of the adaptive Newton tolerance (relative to 1 + |z_i|): a few hundred ulps.
constexpr double kMinAdaptiveNewtonTol = 1e-14;

std::vector<ButcherTableau> dirk_of(bool embedded) {
  std::vector<ButcherTableau> out;
  for (const MethodDefinition& m : built_in_methods())
    if (m.kind == MethodKind::dirk && (m.tableau.b_embedded.size() != 0) == embedded)
      out.push_back(m.tableau);
  return out;
}

}  // namespace

double adaptive_newton_tolerance(CVecRef y, const ControllerOptions& control) {
  double tol = std::numeric_limits<double>::infinity();
  for (Index i = 0; i < y.size(); ++i) {
    const double ay = std::abs(y[i]);
    tol = std::min(tol, (control.atol + control.rtol * ay) / (1.0 + ay));
  }
  return std::max(0.01 * tol, kMinAdaptiveNewtonTol);
}

const std::vector<ButcherTableau>& esdirk_tableaux() {
  static const std::vector<ButcherTableau> all = dirk_of(true);
  return all;
}

const std::vector<ButcherTableau>& implicit_tableaux() {
  static const std::vector<ButcherTableau> all = dirk_of(false);
  return all;
}

const ButcherTableau& implicit_tableau(const std::string& name) {
  for (const auto& t : implicit_tableaux())
    if (t.name == name) return t;
  throw std::logic_error("no implicit tableau '" + name + "'");
}

void DirkStepper::reset(Index n) {
  k_.resize(n, tableau_.stages());
  psi_.resize(n);
  z_.resize(n);
  fz_.resize(n);
}

Status DirkStepper::step(ImplicitCore& core, const OdeSystem& sys, double t, VecRef y, double h,
                         SolveStats& stats, bool k1_given) {
  const int s = tableau_.stages();
  core.new_step();
  z_ = y;  // predictor for the first implicit stage; later stages start from the previous z
  for (int i = 0; i < s; ++i) {
    psi_ = y;
    for (int j = 0; j < i; ++j)
      if (const double aij = tableau_.a(i, j); aij != 0.0) psi_.noalias() += (h * aij) * k_.col(j);
    const double ti = t + tableau_.c[i] * h;
    const double aii = tableau_.a(i, i);
    if (aii == 0.0) {
      if (i > 0 || !k1_given) sys.rhs(ti, psi_, k_.col(i));
      z_ = psi_;
      continue;
    }
    const Status st = core.solve_stage(sys, ti, psi_, h * aii, z_, fz_, stats);
    if (st != Status::ok) return st;
    // k_i from the stage equation rather than f(z_i): the Newton error in z_i is not amplified
    // by a stiff Jacobian, and a stiffly accurate method returns y⁺ = z_s (Hairer–Wanner IV.8).
    k_.col(i) = (z_ - psi_) / (h * aii);
  }
  for (int i = 0; i < s; ++i)
    if (const double bi = tableau_.b[i]; bi != 0.0) y.noalias() += (h * bi) * k_.col(i);
  return Status::ok;
}

void DirkStepper::embedded_difference(double h, VecRef e) const {
  e.setZero();
  for (int i = 0; i < tableau_.stages(); ++i)
    if (const double d = tableau_.b[i] - tableau_.b_embedded[i]; d != 0.0)
      e.noalias() += (h * d) * k_.col(i);
}

std::vector<ParamSpec> esdirk_param_specs(bool filter_by_default) {
  std::vector<ParamSpec> specs = implicit_param_specs(true);
  for (ParamSpec& s : specs)
    if (s.key == "newton_tol")
      s.help =
          "fixed-step mode: Newton stops when its predicted error theta/(1-theta) |dz| is below "
          "this (weighted max-norm) or an update is at round-off, the default iterates to "
          "round-off; adaptive mode uses 0.01 of the controller's scale min_i (atol + rtol "
          "|y_i|)/(1 + |y_i|), at least 1e-14";
  for (ParamSpec& s : controller_param_specs()) specs.push_back(std::move(s));
  specs.push_back(
      {"error_filter",
       ParamType::text,
       filter_by_default ? "on" : "off",
       filter_by_default
           ? "adaptive mode: filter the embedded error estimate with (I - h gamma J)^-1 (damps "
             "stiff components, one more linear solve per trial) or use it raw"
           : "adaptive mode: use the embedded error estimate raw (the default, as Kennedy & "
             "Carpenter and ARKODE do) or filter it with (I - h gamma J_I)^-1: the filter "
             "divides the error the explicit table leaves in stiff components by about h gamma "
             "|lambda| and hides it (ark324l2sa on prothero_robinson, lambda = -1e6, rtol 1e-6: "
             "error 6.5e-3 filtered, 2.1e-6 raw)",
       {"on", "off"}});
  return specs;
}

bool read_error_filter(const Params& p) { return p.text("error_filter") == "on"; }

namespace {
// The tableau checked against its claims (sizes, c completed from the row sums or checked,
// diagonally implicit shape, claimed order) before the stepper is built: BadInput naming the
// defect instead of a crash in the stepper.
ButcherTableau validated_dirk(ButcherTableau t) {
  t.validate(ButcherTableau::Shape::diagonally_implicit);
  return t;
}
}  // namespace

DirkIntegrator::DirkIntegrator(ButcherTableau tableau, std::string description, ImplicitOptions opt,
                               ControllerOptions control, bool error_filter)
    : Integrator({tableau.name,
                  Family::implicit,
                  tableau.order,
                  tableau.stages() - (tableau.fsal ? 1 : 0),
                  {},
                  std::move(description)}),
      stepper_(validated_dirk(std::move(tableau))),
      core_(opt),
      filter_(error_filter),
      newton_tol_(opt.newton_tol),
      control_(control) {
  const ButcherTableau& t = stepper_.tableau();
  const bool explicit_first = t.a(0, 0) == 0.0;
  adaptive_ = t.b_embedded.size() == t.b.size() && explicit_first;
  fsal_ = t.fsal && explicit_first;
  if (adaptive_) ctrl_ = StepController(control_, std::min(t.order, t.embedded_order) + 1);
}

void DirkIntegrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  restart_state(sys, t0);
}

void DirkIntegrator::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();
  restart_state(sys, t);
}

void DirkIntegrator::restart_state(const OdeSystem& sys, double t0) {
  core_.set_newton_tol(newton_tol_);
  const Index n = sys.dimension();
  stepper_.reset(n);
  for (Vec* v : {&ynew_, &err_, &work_, &work2_}) v->setZero(n);
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

Status DirkIntegrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  // The driver computes step k's start as t0 + k·h, which may differ from the cached t + h by
  // rounding: the time test only rules out a restart elsewhere.
  const bool reuse = fsal_ && cache_valid_ && cached_y_ == y.data() &&
                     std::abs(cached_t_ - t) <= 1e-12 * (std::abs(t) + std::abs(h)) &&
                     (!constrained_ || cached_values_ == y);
  cache_valid_ = false;
  const Status st = stepper_.step(core_, sys, t, y, h, stats, reuse);
  if (st != Status::ok || !fsal_) return st;
  stepper_.last_stage_to_first();
  cache_valid_ = true;
  cached_y_ = y.data();
  cached_t_ = t + h;
  if (constrained_) cached_values_ = y;
  return st;
}

Status DirkIntegrator::advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) {
  if (!adaptive_) return Integrator::advance_to(sys, t_out, y, stats);
  cache_valid_ = false;  // fixed-step continuation does not apply
  const ButcherTableau& tab = stepper_.tableau();
  const double gamma = tab.a(tab.stages() - 1, tab.stages() - 1);
  if (!k1_valid_) {
    sys.rhs(t_, y, stepper_.first_stage());
    k1_valid_ = true;
  }
  if (h_ == 0.0) {
    const int p = std::min(tab.order, tab.embedded_order);
    h_ = control_.h0 > 0
             ? std::min(control_.h0, t_out - t_)
             : ctrl_.initial_step(sys, t_, y, stepper_.first_stage(), p, t_out - t_, work_, work2_);
  }
  const auto trial = [&](double t, double h) {
    if (!k1_valid_) {
      sys.rhs(t, y, stepper_.first_stage());
      k1_valid_ = true;
    }
    // Newton tolerance two orders below the controller's scale (see the header).
    core_.set_newton_tol(adaptive_newton_tolerance(y, control_));
    ynew_ = y;
    const Status st = stepper_.step(core_, sys, t, ynew_, h, stats, true);
    if (st != Status::ok || !ynew_.allFinite()) {
      stats.message.clear();  // the trial is retried with a smaller step
      return TrialResult{0.0, 0.5};
    }
    stepper_.embedded_difference(h, err_);
    if (filter_) {
      if (!core_.prepare(h * gamma, stats)) return TrialResult{0.0, 0.5};
      work_.setZero();
      if (!core_.solve(err_, work_, stats)) return TrialResult{0.0, 0.5};
      err_ = work_;
    }
    return TrialResult{ctrl_.norm(err_, y, ynew_), 0.0};
  };
  const auto commit = [&](double, double) {
    y = ynew_;
    if (fsal_)
      stepper_.last_stage_to_first();
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
