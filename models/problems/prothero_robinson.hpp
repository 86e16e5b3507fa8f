// Prothero–Robinson problem (Prothero & Robinson, Math. Comp. 28, 1974):
//   y' = λ (y - φ(t)) + φ'(t),   y(0) = φ(0) + y0_offset.
// Exact solution y(t) = φ(t) + y0_offset·e^{λt}; with the default offset 0, y = φ exactly.
// Parameters: lambda (λ = -1e6 by default: the stiffness knob), phi (sin | cos | exp, i.e.
// φ = sin t, cos t or e^t), y0_offset. Jacobian λ; spectral radius |λ|. Explicit methods are
// stable only for h|λ| below their real-axis limit (2 for Euler), while L-stable implicit
// methods track φ for any h; the error of non-stiffly-accurate methods shows order reduction.
// Additive split (the only one, named stiff; no parameter): f_I = λ(y - φ(t)) (the stiff part,
// implicit), f_E = φ'(t) (explicit, independent of y). J_I = λ (= J); ∂f_E/∂y = 0, so
// explicit_part_spectrum() is exactly 0 (an explicit treatment of f_E limits no step).
#pragma once

#include <string>

#include "core/ode_system.hpp"

namespace stiffbench {

class ProtheroRobinson final : public OdeSystem {
 public:
  enum class Phi { sin, cos, exp };
  ProtheroRobinson(double lambda, Phi phi, double y0_offset)
      : lambda_(lambda), phi_(phi), offset_(y0_offset) {}

  std::string name() const override { return "prothero_robinson"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Constant(1, phi(0.0) + offset_); }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override;
  std::optional<double> stiffness(double, CVecRef) const override { return std::abs(lambda_); }
  // IMEX split: f_I = λ(y - φ(t)) (stiff), f_E = φ'(t) (independent of y, so J_I = J = λ).
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override;
  bool has_implicit_part_jacobian() const override { return true; }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double, CVecRef) const override {
    return SpectrumEstimate{0.0, SpectrumEstimate::Ray::negative_real};
  }

  double phi(double t) const;
  double phi_dot(double t) const;

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
  void eval_rhs_explicit_part(double t, CVecRef, VecRef fe) const override { fe[0] = phi_dot(t); }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override {
    fi[0] = lambda_ * (y[0] - phi(t));
  }
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    eval_jacobian(t, y, jac);  // ∂f_I/∂y = λ = ∂f/∂y
  }

 private:
  double lambda_;
  Phi phi_;
  double offset_;
};

}  // namespace stiffbench
