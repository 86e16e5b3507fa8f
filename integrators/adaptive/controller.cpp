#include "integrators/adaptive/controller.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stiffbench {

std::vector<ParamSpec> controller_param_specs() {
  using P = ParamType;
  using B = Bounds;
  return {
      {"rtol", P::real, "1e-6", "relative tolerance (adaptive mode)", B::positive()},
      {"atol", P::real, "1e-10", "absolute tolerance (adaptive mode)", B::non_negative()},
      {"max_steps", P::integer, "100000", "maximum trial steps per output interval",
       B::at_least(1)},
      {"h0", P::real, "0",
       "first step of an adaptive run; 0: the starting-step heuristic of Hairer-Norsett-Wanner "
       "I, II.4",
       B::non_negative()},
      {"h_max", P::real, "0", "largest step of an adaptive run; 0: no limit", B::non_negative()},
  };
}

ControllerOptions read_controller_options(const Params& p) {
  ControllerOptions o;
  o.rtol = p.real("rtol");
  o.atol = p.real("atol");
  require_input(o.rtol > 0, "parameter 'rtol' must be > 0");
  require_input(o.atol >= 0, "parameter 'atol' must be >= 0");
  o.max_steps = p.integer("max_steps");
  require_input(o.max_steps >= 1, "parameter 'max_steps' must be >= 1");
  o.h0 = p.real("h0");
  require_input(o.h0 >= 0, "parameter 'h0' must be >= 0");
  const double h_max = p.real("h_max");
  require_input(h_max >= 0, "parameter 'h_max' must be >= 0");
  if (h_max > 0) o.h_max = h_max;
  return o;
}

std::string step_too_small_message(double t, double h, CVecRef y) {
  std::ostringstream msg;
  msg.precision(12);  // t apart from its neighbours at the steps where this fires
  msg << "step size too small: h = " << h << " <= 10·u·|t| = " << step_too_small_limit(t)
      << " at t = " << t;
  if (y.size() > 0) {
    Index i_max = 0;
    y.cwiseAbs().maxCoeff(&i_max);
    msg << "; largest state component y[" << i_max << "] = " << y[i_max];
  }
  return msg.str();
}

double wrms_norm(CVecRef e, CVecRef y0, CVecRef y1, double rtol, double atol) {
  const Index n = e.size();
  double sum = 0.0;
  for (Index i = 0; i < n; ++i) {
    const double sc = atol + rtol * std::max(std::abs(y0[i]), std::abs(y1[i]));
    const double q = e[i] / sc;
    sum += q * q;
  }
  return std::sqrt(sum / static_cast<double>(std::max<Index>(n, 1)));
}

StepController::StepController(ControllerOptions opt, int k) : opt_(opt) {
  inv_k_ = 1.0 / k;
  alpha_ = 0.7 * inv_k_;
  beta_ = 0.4 * inv_k_;
}

void StepController::reset() {
  err_prev_ = 1.0;
  after_reject_ = false;
}

bool StepController::judge(double err, double h, double* h_next) {
  if (!std::isfinite(err)) {
    *h_next = opt_.fac_min * h;
    after_reject_ = true;
    return false;
  }
  if (err <= 1.0) {
    const double e = std::max(err, 1e-10);  // err = 0 (e.g. a constant solution): grow fully
    double fac = opt_.safety * std::pow(e, -alpha_) * std::pow(err_prev_, beta_);
    fac = std::clamp(fac, opt_.fac_min, after_reject_ ? 1.0 : opt_.fac_max);
    *h_next = h * fac;
    err_prev_ = std::max(err, 1e-4);
    after_reject_ = false;
    return true;
  }
  *h_next = h * std::max(opt_.fac_min, opt_.safety * std::pow(err, -inv_k_));
  after_reject_ = true;
  return false;
}

double StepController::initial_step(const OdeSystem& sys, double t0, CVecRef y0, CVecRef f0, int p,
                                    double span, Vec& y1, Vec& f1) const {
  // Norms weighted by atol + rtol |y0| (HNW I §II.4, p. 169).
  const double d0 = wrms_norm(y0, y0, y0, opt_.rtol, opt_.atol);
  const double d1 = wrms_norm(f0, y0, y0, opt_.rtol, opt_.atol);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min({h0, span, opt_.h_max});
  y1 = y0 + h0 * f0;
  sys.rhs(t0 + h0, y1, f1);
  y1 = f1 - f0;  // reuse y1 for the difference
  const double d2 = wrms_norm(y1, y0, y0, opt_.rtol, opt_.atol) / h0;
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, 1e-3 * h0) : std::pow(0.01 / dm, 1.0 / (p + 1));
  return std::min({100.0 * h0, h1, span, opt_.h_max});
}

}  // namespace stiffbench
