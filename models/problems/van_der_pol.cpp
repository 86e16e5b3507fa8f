#include "models/problems/van_der_pol.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

VanDerPol::VanDerPol(Form form, double mu) : form_(form), mu_(mu), eps_(1.0 / (mu * mu)) {
  require_input(mu > 0, "van_der_pol: parameter 'mu' must be > 0");
  require_input(std::isfinite(eps_) && eps_ > 0,
                "van_der_pol: parameter 'mu' gives ε = 1/μ² outside the double range");
}

void VanDerPol::eval_rhs(double, CVecRef y, VecRef dydt) const {
  dydt[0] = y[1];
  if (form_ == Form::scaled) {
    dydt[1] = ((1 - y[0] * y[0]) * y[1] - y[0]) / eps_;  // Hairer–Wanner's VDPOL as written
  } else {
    dydt[1] = mu_ * (1 - y[0] * y[0]) * y[1] - y[0];
  }
}

void VanDerPol::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  double j10 = 0, j11 = 0;
  if (form_ == Form::scaled) {
    j10 = -(2 * y[0] * y[1] + 1) / eps_;
    j11 = (1 - y[0] * y[0]) / eps_;
  } else {
    j10 = -2 * mu_ * y[0] * y[1] - 1;
    j11 = mu_ * (1 - y[0] * y[0]);
  }
  const std::vector<Eigen::Triplet<double>> t{{0, 1, 1.0}, {1, 0, j10}, {1, 1, j11}};
  jac.resize(2, 2);
  jac.setFromTriplets(t.begin(), t.end());
}

std::optional<double> VanDerPol::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

ModelRegistry::Entry van_der_pol_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "van_der_pol",
               .description = "van der Pol oscillator, scaled y2' = ((1-y1²)y2 - y1)/ε with ε = "
                              "1/μ² (default) or "
                              "classical y2' = μ(1-y1²)y2 - y1; literature end time t = 2 "
                              "(scaled) or t = 2μ (form=mu)",
               .source =
                   "Hairer & Wanner II §IV.10 (VDPOL, ε = 1e-6); IVP test set 'vdpol' (μ = 1000)",
               .size = fixed_problem_size},
      .params = {{"form",
                  P::text,
                  "scaled",
                  "scaled (time x = t/μ, ε = 1/μ²) or mu (classical)",
                  {"scaled", "mu"}},
                 {"mu", P::real, "1000",
                  "damping parameter μ; the scaled form uses ε = 1/μ² (1000: ε = 1e-6)",
                  B::positive()}},
      .make = [](const Params& p) {
        const auto form =
            p.text("form") == "scaled" ? VanDerPol::Form::scaled : VanDerPol::Form::mu;
        return std::make_unique<VanDerPol>(form, p.real("mu"));
      }};
}

}  // namespace stiffbench
