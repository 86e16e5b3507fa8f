// GridFluid: the optional face of an Eulerian (grid) fluid model that splitting schemes need
// beyond f. Stable fluids (Stam 1999) does not evaluate f = P[-(u·∇)u + νΔu + g]: it composes
// the model's operators — body force, semi-Lagrangian advection, implicit diffusion, pressure
// projection — each applied to a whole velocity state y (the model's own layout, e.g. the faces of
// a MAC grid). An OdeSystem offers this face through as_grid_fluid(); an integrator that needs it
// says so in its Requirements (grid_fluid) and never casts to a model class.
#pragma once

#include "core/types.hpp"

namespace stiffbench {

class GridFluid {
 public:
  virtual ~GridFluid() = default;

  // y += h g (the body force per unit mass on the velocity components).
  virtual void add_body_force(double h, VecRef y) const = 0;

  // Semi-Lagrangian advection: out(x) = q(x - h u(x)) at every velocity sample x, the departure
  // point traced back along the field `vel` (the model documents its tracing and interpolation);
  // q and vel may be the same state. out must not alias q.
  virtual void advect(double h, CVecRef vel, CVecRef q, VecRef out) const = 0;

  // Implicit (backward Euler) diffusion: solves (I - hν Δ) out = in with the model's boundary
  // conditions; returns the number of linear solves made.
  virtual int diffuse(double h, CVecRef in, VecRef out) const = 0;

  // Pressure projection onto the discretely divergence-free fields, in place; returns the number
  // of linear solves made.
  virtual int project_divergence_free(VecRef y) const = 0;
};

}  // namespace stiffbench
