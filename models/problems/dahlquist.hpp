// Dahlquist's test equation y' = λ y with complex λ = lambda_re + i·lambda_im, written as a
// real 2-dimensional system y = (Re z, Im z):
//   y0' = a y0 - b y1,   y1' = b y0 + a y1,   λ = a + i b.
// Exact solution z(t) = exp(λ t) z0. Jacobian [[a, -b], [b, a]] (constant); spectral radius |λ|.
// One step of a Runge–Kutta method multiplies z by R(hλ): the link between tableau stability
// functions and runs. No invariant (|z| is conserved only for a = 0).
#pragma once

#include <complex>

#include "core/ode_system.hpp"

namespace stiffbench {

class Dahlquist final : public OdeSystem {
 public:
  Dahlquist(std::complex<double> lambda, std::complex<double> z0) : lambda_(lambda), z0_(z0) {}

  std::string name() const override { return "dahlquist"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{z0_.real(), z0_.imag()}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::optional<double> stiffness(double, CVecRef) const override { return std::abs(lambda_); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  std::complex<double> lambda_, z0_;
};

}  // namespace stiffbench
