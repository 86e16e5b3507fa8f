// The Integrator interface and the metadata the registry lists.
//
// A fixed-step integrator advances y in place by one step of size h. It may carry history
// between steps (two-step Verlet, leapfrog's staggered velocity, BDF2); reset() starts it at
// (t0, y0), allocates its workspaces (never per step) and checks that it can run on the system.
// step() assumes y is what the previous step() or reset() left: the driver never edits it.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/ode_system.hpp"
#include "core/solve_stats.hpp"
#include "core/theory/linear_stability.hpp"

namespace stiffbench {

// graphics: the graphics community's spring solvers (xpbd, projective_dynamics);
// operator_splitting: schemes that compose a model's own operators (stable_fluids) or advance the
// two parts of an additive split one after the other (lie, strang) — printed "splitting" (the
// family name in `list` and the CSVs); imex: additive (implicit–explicit) Runge–Kutta methods. The
// symplectic kick/drift splittings are Family::symplectic (KickDriftIntegrator,
// integrators/symplectic/kick_drift.hpp).
enum class Family {
  explicit_rk,
  implicit,
  symplectic,
  graphics,
  operator_splitting,
  imex,
  reference
};
std::string to_string(Family f);

// What an integrator needs from the system.
struct Requirements {
  bool mechanical = false;            // y = [x; v] split (MechanicalSystem)
  bool velocity_independent = false;  // a(t, x) must not depend on v
  bool jacobian = false;              // an analytic Jacobian (otherwise finite differences)
  // Holonomic constraints offered as equations (MechanicalSystem::holonomic_constraints()); the
  // method enforces them itself, so the driver does not project after its steps.
  bool constraints = false;
  bool spring_network = false;  // the system's springs (OdeSystem::spring_network())
  bool grid_fluid = false;      // the GridFluid operators (core/grid_fluid.hpp)
  bool split = false;           // an additive split f = f_E + f_I (OdeSystem::has_imex_split)
};

struct MethodInfo {
  std::string name;
  Family family = Family::explicit_rk;
  int order = 0;
  int stages = 0;  // f (or acceleration) evaluations per step, after start-up
  Requirements requires_ = {};
  std::string description;
  // The method class within its family ("embedded RK pair", "Rosenbrock", "Gauss collocation")
  // and the literature reference, for `list integrators` and `describe` (built-in methods keep
  // them beside their coefficients or constructor: integrators/method_entry.hpp).
  std::string kind = {};
  std::string reference = {};
};

// Human-readable list of requirements ("mechanical system, velocity-independent acceleration").
std::string describe_requirements(const Requirements& r);

// BadInput naming the integrator and the model when the system lacks what the method needs.
void check_compatible(const MethodInfo& info, const OdeSystem& sys);

class Integrator {
 public:
  explicit Integrator(MethodInfo info) : info_(std::move(info)) {}
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  const MethodInfo& info() const { return info_; }

  // The name the method was created under: the registry's create() sets the registered name
  // (core/registry.hpp), so two registrations of one tableau are two rows of every study.
  void set_name(std::string name) { info_.name = std::move(name); }

  // The Butcher tableau of a Runge–Kutta method (its coefficients, for `stiffbench audit`);
  // nullptr for methods that are not defined by one.
  virtual const ButcherTableau* butcher_tableau() const { return nullptr; }
  // Likewise the coefficients of a Rosenbrock method and of a kick/drift splitting (for
  // `stiffbench analyze`); nullptr for other methods.
  virtual const RosenbrockTableau* rosenbrock_tableau() const { return nullptr; }
  virtual const KickDriftCoefficients* kick_drift_coefficients() const { return nullptr; }
  // The two tables of an additive (IMEX) Runge–Kutta method; nullptr for other methods.
  virtual const AdditiveTableau* additive_tableau() const { return nullptr; }

  // Starts a run at (t0, y0) on `sys`; checks compatibility, allocates workspaces, clears
  // history. The same system must be passed to the following step() calls.
  virtual void reset(const OdeSystem& sys, double t0, CVecRef y0) = 0;

  // Starts again at (t, y) on the system of the last reset(): clears what depends on the state
  // (history, cached stages, an evaluated Jacobian and its factorisation) and keeps what depends
  // only on the system's structure (work vectors, sparsity patterns, symbolic analyses). Operator
  // splitting restarts its sub-integrators at every substep: a full reset() there would redo the
  // structure's analysis (and, on a mechanical system, evaluate a force Jacobian for the pattern
  // that no counter sees) at every step. The default is reset(); on another system, too.
  virtual void restart(const OdeSystem& sys, double t, CVecRef y) { reset(sys, t, y); }

  // Advances y from t to t + h. Returns Status::ok or the reason the step failed (e.g.
  // newton_failed); it never returns a silently wrong step. Integrator-side counters (Newton
  // iterations, linear solves) are added to `stats`; the driver counts steps and evaluations.
  virtual Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) = 0;

  // ‖y‖∞ of the state the last step() returned (NaN when an entry is NaN), when the method
  // computed it while writing that state: the fixed-step driver's blow-up check then skips its
  // own pass over y. nullopt (the default) when the method did not.
  virtual std::optional<double> last_step_max_norm() const { return std::nullopt; }

  // Adaptive mode (the library references): after reset(), advance_to() integrates from the
  // current time to t_out with the method's own step-size control, writes y(t_out) and sets
  // the library's own counters in `stats` (cumulative since reset). A fixed-step run calls
  // only step(), an adaptive run only advance_to().
  virtual bool supports_fixed_step() const { return true; }
  virtual bool supports_adaptive() const { return false; }
  virtual Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats);
  // The absolute tolerance advance_to() controls the error to (the method's scalar `atol`): an
  // adaptive run's bound for the admissible-set check (core/driver.hpp, run_adaptive). nullopt
  // (the default) for methods without one; the driver then uses a bound from round-off.
  virtual std::optional<double> absolute_tolerance() const { return std::nullopt; }

  // The method's linear stability (core/theory/linear_stability.hpp) from its coefficients, with
  // the parameters it was created with; empty where it has none (variable-order library methods).
  virtual std::optional<LinearStability> linear_stability() const { return std::nullopt; }

  // For methods that advance f_E of an additive split explicitly (IMEX Runge–Kutta, operator
  // splitting with an explicit sub-integrator): the linear stability of that explicit treatment
  // (the explicit table's R, or the explicit sub-integrator's), which limits the step on the
  // spectrum of ∂f_E/∂y when the implicit part is A-stable and does not interact (`stability`
  // predicts from it). Empty for other methods.
  virtual std::optional<LinearStability> explicit_part_stability() const { return std::nullopt; }
  // The same methods on a mechanical split that puts x' = v in f_I and the acceleration in f_E
  // (every built-in mechanical split): the step map on x'' = a x + b x', x advanced by the
  // implicit treatment and v by the explicit one (mechanical-only; for an IMEX pair
  // partitioned_imex_stability()). On such a split an undamped mode sees this map, not the
  // explicit treatment's R on ±iω. Empty for other methods.
  virtual std::optional<LinearStability> partitioned_stability() const { return std::nullopt; }

 private:
  MethodInfo info_;
};

}  // namespace stiffbench
