#include "models/problems/dahlquist.hpp"

namespace stiffbench {

void Dahlquist::eval_rhs(double, CVecRef y, VecRef dydt) const {
  const double a = lambda_.real(), b = lambda_.imag();
  dydt[0] = a * y[0] - b * y[1];
  dydt[1] = b * y[0] + a * y[1];
}

void Dahlquist::eval_jacobian(double, CVecRef, SparseMat& jac) const {
  const double a = lambda_.real(), b = lambda_.imag();
  jac.resize(2, 2);
  std::vector<Eigen::Triplet<double>> t{{0, 0, a}, {0, 1, -b}, {1, 0, b}, {1, 1, a}};
  jac.setFromTriplets(t.begin(), t.end());
}

void Dahlquist::exact(double t, VecRef y) const {
  const std::complex<double> z = std::exp(lambda_ * t) * z0_;
  y[0] = z.real();
  y[1] = z.imag();
}

}  // namespace stiffbench
