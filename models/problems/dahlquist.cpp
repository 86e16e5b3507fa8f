#include "models/problems/dahlquist.hpp"
#include "models/problems/problem_entry.hpp"

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

ModelRegistry::Entry dahlquist_entry() {
  using P = ParamType;
  using B = Bounds;
  return {.info = {.name = "dahlquist",
                   .description = "y' = λy with complex λ as a 2-dimensional real system",
                   .exact = true,
                   .source = "Dahlquist 1963; exact solution exp(λt) y0",
                   .size = fixed_problem_size},
          .params = {{"lambda_re", P::real, "-1", "real part of λ", B::any()},
                     {"lambda_im", P::real, "0", "imaginary part of λ", B::any()},
                     {"y0_re", P::real, "1", "real part of y(0)", B::any()},
                     {"y0_im", P::real, "0", "imaginary part of y(0)", B::any()}},
          .make = [](const Params& p) {
            return std::make_unique<Dahlquist>(
                std::complex<double>(p.real("lambda_re"), p.real("lambda_im")),
                std::complex<double>(p.real("y0_re"), p.real("y0_im")));
          }};
}

}  // namespace stiffbench
