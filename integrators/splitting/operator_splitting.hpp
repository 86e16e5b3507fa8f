// Operator splitting of an additive split f = f_E + f_I (OdeSystem::has_imex_split): `lie` and
// `strang` advance the two parts one after the other, each with a sub-integrator named by a
// parameter and run on the part's view (core/split_views.hpp):
//
//   lie      one step = E(h) then I(h)                 (order 1; Lie–Trotter)
//   strang   one step = E(h/2), I(h), E(h/2)           (order 2; Strang 1968)
//
// where E(τ) is one step of the explicit sub-integrator (parameter `explicit`, default rk4) on
// explicit_part_view(sys) and I(τ) one step of the implicit sub-integrator (parameter
// `implicit`, default sdirk3) on implicit_part_view(sys). Each sub-integrator is any registered
// fixed-step integrator, created through the registry with its own defaults (the implicit
// sub-integrator's Newton and linear-solver options are its defaults; they are not passed
// through). BadInput naming the parameter for an unknown name, an adaptive-only integrator, or
// one the part's view cannot run (e.g. verlet on the explicit part, which is not mechanical).
//
// Sub-integrators keep state between their steps (the FSAL stage of a DIRK, BDF2's history, a
// library's internal state) keyed on (t, storage): between two calls of one sub-integrator the
// other part changed y, so each substep starts with the sub-integrator's reset() at the
// substep's (t, y). Correct for every integrator, at the price of the sub-integrator's set-up
// (workspace and linear-solver set-up) once per substep; a multistep sub-integrator (bdf2) then
// takes its start-up step every time.
//
// Orders: 1 and 2 on smooth problems when the sub-integrators have at least that order (the
// splitting error is O(h) per unit time for lie, O(h²) for strang, from the commutator of the
// parts: E. Hairer, C. Lubich & G. Wanner, Geometric Numerical Integration, 2nd ed., 2006,
// Sect. II.5; G. Strang, On the construction and comparison of difference schemes, SIAM J.
// Numer. Anal. 5 (1968) 506-517). linear_stability() is empty (the composition's R is not a
// function of one hλ when the parts do not commute); explicit_part_stability() is the explicit
// sub-integrator's linear_stability() over one step h: R(z) for lie, R(z/2)² for strang (two
// half steps; `substepped` in core/theory/linear_stability.hpp), so its limits are twice the
// sub-integrator's.
#pragma once

#include <memory>
#include <string>

#include "core/integrator.hpp"
#include "core/registry_types.hpp"

namespace stiffbench {

enum class SplittingScheme { lie, strang };

class OperatorSplitting final : public Integrator {
 public:
  // The sub-integrators as the registry created them (their info().name is the registered one).
  OperatorSplitting(SplittingScheme scheme, std::unique_ptr<Integrator> explicit_part,
                    std::unique_ptr<Integrator> implicit_part);

  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;
  // lie: the explicit sub-integrator's R(z); strang: its two half steps, R(z/2)².
  std::optional<LinearStability> explicit_part_stability() const override;
  // On a mechanical split with x' = v in f_I: kick–drift maps with R-damped kicks (the .cpp).
  std::optional<LinearStability> partitioned_stability() const override;

  const Integrator& explicit_integrator() const { return *explicit_; }
  const Integrator& implicit_integrator() const { return *implicit_; }

 private:
  Status explicit_substep(double t, VecRef y, double h, SolveStats& stats);
  Status implicit_substep(double t, VecRef y, double h, SolveStats& stats);

  SplittingScheme scheme_;
  std::unique_ptr<Integrator> explicit_, implicit_;
  const OdeSystem* sys_ = nullptr;
  std::unique_ptr<OdeSystem> explicit_view_, implicit_view_;
};

// Registers lie and strang; their factories create the sub-integrators from `reg` (which must
// outlive the registrations: the process-wide registry).
void register_splitting_integrators(IntegratorRegistry& reg);

}  // namespace stiffbench
