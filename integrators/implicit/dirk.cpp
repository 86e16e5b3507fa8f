#include "integrators/implicit/dirk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stiffbench {

namespace {

// Floor of the adaptive Newton tolerance (relative to 1 + |z_i|): a few hundred ulps.
constexpr double kMinAdaptiveNewtonTol = 1e-14;

ButcherTableau make(std::string name, int order, Mat a, Vec b) {
  ButcherTableau t;
  t.name = std::move(name);
  t.order = order;
  t.c = a.rowwise().sum();
  t.a = std::move(a);
  t.b = std::move(b);
  return t;
}

ButcherTableau make_embedded(std::string name, int order, int embedded_order, Mat a, Vec b,
                             Vec b_hat) {
  ButcherTableau t = make(std::move(name), order, std::move(a), std::move(b));
  t.b_embedded = std::move(b_hat);
  t.embedded_order = embedded_order;
  t.fsal = true;  // explicit first stage, stiffly accurate: k_s serves as the next k_1
  return t;
}

ButcherTableau sdirk2() {
  const double g = 1.0 - 1.0 / std::sqrt(2.0);
  return make("sdirk2", 2, Mat{{g, 0.0}, {1.0 - g, g}}, Vec{{1.0 - g, g}});
}

ButcherTableau sdirk3() {
  // Alexander (1977), SIAM J. Numer. Anal. 14; Hairer–Wanner II Table IV.6.5.
  const double g = 0.43586652150845899941601945;
  const double tau = (1.0 + g) / 2.0;
  const double b1 = -(6 * g * g - 16 * g + 1) / 4.0;
  const double b2 = (6 * g * g - 20 * g + 5) / 4.0;
  return make("sdirk3", 3, Mat{{g, 0.0, 0.0}, {tau - g, g, 0.0}, {b1, b2, g}}, Vec{{b1, b2, g}});
}

ButcherTableau trbdf2() {
  // Hosea & Shampine (1996), Appl. Numer. Math. 20: TR-BDF2 of Bank et al. (1985) as a
  // one-step ESDIRK; the embedded row is their third-order companion formula.
  const double g = 2.0 - std::sqrt(2.0), d = g / 2.0, w = std::sqrt(2.0) / 4.0;
  return make_embedded("trbdf2", 2, 3, Mat{{0.0, 0.0, 0.0}, {d, d, 0.0}, {w, w, d}}, Vec{{w, w, d}},
                       Vec{{(1.0 - w) / 3.0, (3.0 * w + 1.0) / 3.0, d / 3.0}});
}

ButcherTableau esdirk43() {
  // Kennedy & Carpenter (2003), Appl. Numer. Math. 44 (implicit part of ARK4(3)6L[2]SA):
  // γ = 1/4.
  const double q = 0.25;
  Mat a = Mat::Zero(6, 6);
  a(1, 0) = q;
  a(2, 0) = 8611.0 / 62500.0;
  a(2, 1) = -1743.0 / 31250.0;
  a(3, 0) = 5012029.0 / 34652500.0;
  a(3, 1) = -654441.0 / 2922500.0;
  a(3, 2) = 174375.0 / 388108.0;
  a(4, 0) = 15267082809.0 / 155376265600.0;
  a(4, 1) = -71443401.0 / 120774400.0;
  a(4, 2) = 730878875.0 / 902184768.0;
  a(4, 3) = 2285395.0 / 8070912.0;
  a(5, 0) = 82889.0 / 524892.0;
  a(5, 2) = 15625.0 / 83664.0;
  a(5, 3) = 69875.0 / 102672.0;
  a(5, 4) = -2260.0 / 8211.0;
  for (int i = 1; i < 6; ++i) a(i, i) = q;
  const Vec b = a.row(5).transpose();
  const Vec b_hat{{4586570599.0 / 29645900160.0, 0.0, 178811875.0 / 945068544.0,
                   814220225.0 / 1159782912.0, -3700637.0 / 11593932.0, 61727.0 / 225920.0}};
  return make_embedded("esdirk43", 4, 3, std::move(a), b, b_hat);
}

std::vector<ButcherTableau> tableaux_of(StepModes steps) {
  std::vector<ButcherTableau> out;
  for (const DirkMethod& m : dirk_methods())
    if (*m.steps == steps) out.push_back(*m.coefficients);
  return out;
}

}  // namespace

const std::vector<DirkMethod>& dirk_methods() {
  constexpr const char* kAlexander = "R. Alexander, SIAM J. Numer. Anal. 14 (1977) 1006-1021";
  static const std::vector<DirkMethod> all = {
      {make("backward_euler", 1, Mat::Constant(1, 1, 1.0), Vec::Constant(1, 1.0)),
       {"backward (implicit) Euler with Newton; L-stable", "implicit RK",
        cite(kHairerWanner, "Sect. IV.3")},
       StepModes::fixed},
      {make("implicit_midpoint", 2, Mat::Constant(1, 1, 0.5), Vec::Constant(1, 1.0)),
       {"implicit midpoint rule; A-stable, symplectic, no damping", "Gauss collocation (1 stage)",
        cite(kGeometricIntegration, "Sect. II.1")},
       StepModes::fixed},
      {make("trapezoidal", 2, Mat{{0.0, 0.0}, {0.5, 0.5}}, Vec{{0.5, 0.5}}),
       {"trapezoidal rule (Crank-Nicolson); A-stable, no damping at infinity", "implicit RK",
        "J. Crank & P. Nicolson, Proc. Cambridge Philos. Soc. 43 (1947) 50-67"},
       StepModes::fixed},
      {sdirk2(),
       {"two-stage SDIRK, gamma = 1 - 1/sqrt(2); L-stable, stiffly accurate", "SDIRK", kAlexander},
       StepModes::fixed},
      {sdirk3(),
       {"three-stage SDIRK of Alexander (1977); L-stable, stiffly accurate", "SDIRK", kAlexander},
       StepModes::fixed},
      // ESDIRK pairs with an embedded estimate: fixed step with --h, adaptive with rtol/atol.
      {trbdf2(),
       {"TR-BDF2 (Bank et al. 1985, IEEE Trans. CAD 4; as an ESDIRK 2(3) pair after Hosea & "
        "Shampine 1996, Appl. Numer. Math. 20), gamma = 2 - sqrt(2); L-stable, stiffly "
        "accurate, FSAL; adaptive or fixed step",
        "ESDIRK (embedded pair)",
        "R. E. Bank, W. M. Coughran, W. Fichtner, E. H. Grosse, D. J. Rose & R. K. Smith, "
        "Transient simulation of silicon devices and circuits, IEEE Trans. Computer-Aided Design "
        "4 (1985) 436-451; as an ESDIRK pair: M. E. Hosea & L. F. Shampine, Analysis and "
        "implementation of TR-BDF2, Appl. Numer. Math. 20 (1996) 21-37"},
       StepModes::fixed_and_adaptive},
      {esdirk43(),
       {"ESDIRK4(3)6L[2]SA, implicit part of ARK4(3)6L[2]SA (Kennedy & Carpenter 2003, Appl. "
        "Numer. Math. 44), gamma = 1/4; L-stable, stiffly accurate, FSAL; adaptive or fixed step",
        "ESDIRK (embedded pair)",
        "C. A. Kennedy & M. H. Carpenter, Additive Runge-Kutta schemes for "
        "convection-diffusion-reaction equations, Appl. Numer. Math. 44 (2003) 139-181 "
        "(ESDIRK4(3)6L[2]SA, the implicit part of ARK4(3)6L[2]SA)"},
       StepModes::fixed_and_adaptive},
  };
  return all;
}

const std::vector<ButcherTableau>& esdirk_tableaux() {
  static const std::vector<ButcherTableau> all = tableaux_of(StepModes::fixed_and_adaptive);
  return all;
}

const std::vector<ButcherTableau>& implicit_tableaux() {
  static const std::vector<ButcherTableau> all = tableaux_of(StepModes::fixed);
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

std::vector<ParamSpec> esdirk_param_specs() {
  std::vector<ParamSpec> specs = implicit_param_specs(true);
  for (ParamSpec& s : specs)
    if (s.key == "newton_tol")
      s.help =
          "fixed-step mode: Newton stops when its predicted error theta/(1-theta) |dz| is below "
          "this (weighted max-norm) or an update is at round-off, the default iterates to "
          "round-off; adaptive mode uses 0.01 of the controller's scale min_i (atol + rtol "
          "|y_i|)/(1 + |y_i|), at least 1e-14";
  for (ParamSpec& s : controller_param_specs()) specs.push_back(std::move(s));
  specs.push_back({"error_filter",
                   ParamType::text,
                   "on",
                   "adaptive mode: filter the embedded error estimate with (I - h gamma J)^-1 "
                   "(damps stiff components, one more linear solve per trial) or use it raw",
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
    double tol = std::numeric_limits<double>::infinity();
    for (Index i = 0; i < y.size(); ++i) {
      const double ay = std::abs(y[i]);
      tol = std::min(tol, (control_.atol + control_.rtol * ay) / (1.0 + ay));
    }
    core_.set_newton_tol(std::max(0.01 * tol, kMinAdaptiveNewtonTol));
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
  const Status st = advance_adaptive(ctrl_, t_, t_out, h_, counts_, stats.message, trial, commit);
  stats.steps = counts_.accepted;
  stats.error_test_failures = counts_.rejected;
  return st;
}

constexpr MethodText kBdf2Text{
    .description = "two-step backward differentiation formula; sdirk2 start-up step",
    .kind = "multistep (BDF)",
    .reference = cite(kHairerWanner, "Sect. V.1 (Curtiss & Hirschfelder 1952)")};

Bdf2Integrator::Bdf2Integrator(ImplicitOptions opt)
    : Integrator(method_info("bdf2", Family::implicit, 2, 1, {}, kBdf2Text)),
      core_(std::move(opt)),
      startup_(implicit_tableau("sdirk2")) {}

void Bdf2Integrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  const Index n = sys.dimension();
  startup_.reset(n);
  y_prev_.resize(n);
  y_last_.resize(n);
  psi_.resize(n);
  z_.resize(n);
  fz_.resize(n);
  started_ = false;
}

Status Bdf2Integrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (!started_ || h != h_last_ || y != y_last_) {
    y_prev_ = y;
    const Status st = startup_.step(core_, sys, t, y, h, stats);
    if (st != Status::ok) return st;
  } else {
    core_.new_step();
    psi_ = (4.0 / 3.0) * y - (1.0 / 3.0) * y_prev_;
    z_ = 2.0 * y - y_prev_;
    const Status st = core_.solve_stage(sys, t + h, psi_, (2.0 / 3.0) * h, z_, fz_, stats);
    if (st != Status::ok) return st;
    y_prev_ = y;
    y = z_;
  }
  y_last_ = y;
  h_last_ = h;
  started_ = true;
  return Status::ok;
}

}  // namespace stiffbench
