#include "models/problems/van_der_pol.hpp"

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

}  // namespace stiffbench
