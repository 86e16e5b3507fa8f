// Kick/drift methods: symplectic splittings of mechanical systems y = [x; v] (of the flow into
// kicks and drifts; not the operator splitting of Family::operator_splitting), as coefficient
// data (core/theory/tableau.hpp KickDriftCoefficients; the built-in ones are method files,
// methods/NAME.toml with kind = "kick_drift") read by one stepper, KickDriftIntegrator:
//   for j = 1..s:  v ← v + h·kick_j·a(t_j, x, v);   x ← x + h·drift_j·v.
// When a stage's kick is followed only by zero drifts, the acceleration it evaluates is the
// one at the end of the step; for velocity-independent forces the next step reuses it
// (first-same-as-last), so velocity Verlet costs one evaluation per step after the first.
// The reuse relies on the Integrator contract (y is what the previous step left), checked in
// O(1): same storage (y.data()), no reset in between. The one caller that edits y between steps
// is the driver's constraint projection, so on systems with constraints the position is
// compared with the one the cached acceleration belongs to (a copy and a compare of x per step,
// as before); without constraints there is no whole-vector copy or compare.
#pragma once

#include <vector>

#include "core/integrator.hpp"
#include "core/theory/tableau.hpp"

namespace stiffbench {

// The coefficients of one kick/drift method, and whether it requires velocity-independent
// forces (which also lets it reuse its last acceleration, see above).
struct KickDriftScheme {
  KickDriftCoefficients kick_drift;
  bool velocity_independent;
  const std::string& name() const { return kick_drift.name; }
};

// The built-in kick/drift methods of order 1 and 2 (the method files of kind splitting with
// order <= 2, in the order of built_in_methods(): symplectic_euler (v first, the seed's form),
// symplectic_euler_x (x first), velocity_verlet); the higher-order compositions and splittings
// are composition_methods() (composition.hpp).
const std::vector<KickDriftCoefficients>& kick_drift_coefficients();

class KickDriftIntegrator final : public Integrator {
 public:
  KickDriftIntegrator(KickDriftCoefficients coeffs, bool velocity_independent,
                      std::string description);

  const KickDriftCoefficients& coefficients() const { return coeffs_; }
  const KickDriftCoefficients* kick_drift_coefficients() const override { return &coeffs_; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  std::optional<LinearStability> linear_stability() const override {
    return kick_drift_stability(coeffs_);
  }
  // ‖y‖∞ taken by the last stages that wrote x and v (in the same pass).
  std::optional<double> last_step_max_norm() const override;

 private:
  KickDriftCoefficients coeffs_;
  bool fsal_;  // reuse the last stage's acceleration as the next step's first
  const MechanicalSystem* mech_ = nullptr;
  Vec acc_;       // acceleration workspace
  Vec cached_x_;  // position at which acc_ was last evaluated (constrained systems only)
  const double* cached_y_ = nullptr;  // storage of the state acc_ belongs to
  bool cache_valid_ = false;
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t last_kick_ = kNone, last_drift_ = kNone;  // the last stages that write v and x
  double last_norm_ = 0.0;                              // ‖y‖∞ after the last step
  bool norm_valid_ = false;
};

}  // namespace stiffbench
