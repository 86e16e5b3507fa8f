// Van der Pol oscillator in the two forms used in the stiff literature.
//   form=scaled (default; Hairer & Wanner, Solving ODEs II, §IV.10, problem VDPOL):
//     y1' = y2,   y2' = ((1 - y1²) y2 - y1) / ε,   ε = 1/μ²
//   form=mu (the classical equation y'' - μ (1 - y²) y' + y = 0; IVP test set of Mazzia &
//   Magherini, problem "vdpol"):
//     y1' = y2,   y2' = μ (1 - y1²) y2 - y1
// Parameterisation: one stiffness knob, `mu` (μ > 0, default 1000), in both forms. The scaled
// form is the classical one in the slow time x = t/μ with Y2 = μ y2, so ε = 1/μ² and the
// default μ = 1000 gives exactly Hairer–Wanner's ε = 1e-6 (1/1e6 rounds to the double 1e-6).
// (A separate `eps` key would let ε and μ contradict each other.) For ε = 1e-5 use
// mu=316.22776601683796.
// y(0) = (2, 0) in both forms. Literature time span: [0, 2] in the scaled form, [0, 2μ] = [0, 2000]
// in the μ form (the same trajectory: one relaxation period is (3 - 2 ln 2) ≈ 1.614 in x);
// literature_end_time() (and end_time(), the CLI's default when --t-end is omitted) returns it
// for the chosen form.
// Reference solution at the end (μ = 1000): scaled y(2) = (0.1706167732170483e+01,
// -0.8928097010247975e+00) (Hairer–Wanner); μ form y(2000) = (0.1706167732170469e+01,
// -0.8928097010248125e-03) (IVP test set "vdpol"); CVODE BDF (rtol 1e-13) on this class
// reproduces both to 2e-11 relative.
// The solution has slow phases on the manifold y2 ≈ y1/(1 - y1²) (scaled) separated by jumps of
// y1 from ±1 to ∓2 lasting O(ε) in x, and an initial layer of width O(ε) from y2(0) = 0 to the
// manifold (y2 ≈ -2/3): fixed-step runs over the whole span need h below the jump time scale.
// No invariants (the system is dissipative away from the limit cycle).
// Jacobian (fixed pattern, 3 entries; ∂f1/∂y1 = 0 structurally):
//   scaled: [[0, 1], [-(2 y1 y2 + 1)/ε, (1 - y1²)/ε]];   mu: [[0, 1], [-2μ y1 y2 - 1, μ(1 - y1²)]].
// stiffness(): min(‖J‖₁, ‖J‖∞), the Gershgorin bound on the spectral radius (≈ 3/ε = 3e6 at
// y(0) in the scaled form).
#pragma once

#include "core/ode_system.hpp"

namespace stiffbench {

class VanDerPol final : public OdeSystem {
 public:
  enum class Form { scaled, mu };
  VanDerPol(Form form, double mu);

  std::string name() const override { return "van_der_pol"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{2.0, 0.0}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  std::optional<double> stiffness(double t, CVecRef y) const override;

  Form form() const { return form_; }
  double mu() const { return mu_; }
  double eps() const { return eps_; }  // 1/μ² (used by the scaled form)
  // End of the literature time span: 2 (scaled) or 2μ (form=mu).
  double literature_end_time() const { return form_ == Form::scaled ? 2.0 : 2.0 * mu_; }
  std::optional<double> end_time() const override { return literature_end_time(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;

 private:
  Form form_;
  double mu_;
  double eps_;
};

}  // namespace stiffbench
