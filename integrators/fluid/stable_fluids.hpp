// stable_fluids — Stam's splitting for incompressible flow ("Stable Fluids", SIGGRAPH 1999), the
// scheme graphics codes use, as a fixed-step integrator so that it runs in every experiment beside
// the general methods. One step of size h from the divergence-free velocity w0:
//   w1 = w0 + h g                    body force
//   w2 = w1 advected by itself       semi-Lagrangian: w2(x) = w1(x - h w1(x)) (traced back)
//   w3 = (I - hνΔ)⁻¹ w2              implicit (backward Euler) diffusion
//   w4 = P w3                        pressure projection
// Each operator is the model's (core/grid_fluid.hpp), so the integrator runs only on systems
// that expose GridFluid (fluid_2d; Requirements::grid_fluid). It never evaluates f: its cost is
// the advection sweep and two linear solves per step (diffusion, pressure), counted as lin_solves.
// First order in h (the splitting and backward Euler); stable for every h (semi-Lagrangian
// advection is unconditionally stable, the diffusion is implicit), and dissipative: see the
// model's header for the numerical viscosity of its interpolation.
#pragma once

#include "core/integrator.hpp"

namespace stiffbench {

class StableFluids final : public Integrator {
 public:
  StableFluids();
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override;

 private:
  Vec w1_, w2_;
};

}  // namespace stiffbench
