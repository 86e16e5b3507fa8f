#include "integrators/fluid/stable_fluids.hpp"

#include "core/grid_fluid.hpp"
#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {
Requirements fluid_needs() {
  Requirements r;
  r.grid_fluid = true;
  return r;
}
}  // namespace

constexpr MethodText kStableFluidsText{
    .description =
        "Stam's stable fluids (1999): body force, semi-Lagrangian advection, implicit "
        "diffusion, pressure projection; grid fluids only (fluid_2d)",
    .kind = "operator splitting (semi-Lagrangian)",
    .reference = "J. Stam, Stable fluids, SIGGRAPH 1999, 121-128"};

StableFluids::StableFluids()
    : Integrator(method_info("stable_fluids", Family::operator_splitting, 1, 0, fluid_needs(),
                             kStableFluidsText)) {}

void StableFluids::reset(const OdeSystem& sys, double, CVecRef y0) {
  check_compatible(info(), sys);
  w1_.resize(y0.size());
  w2_.resize(y0.size());
}

Status StableFluids::step(const OdeSystem& sys, double, VecRef y, double h, SolveStats& stats) {
  const GridFluid* fluid = sys.as_grid_fluid();
  w1_ = y;
  fluid->add_body_force(h, w1_);
  fluid->advect(h, w1_, w1_, w2_);
  stats.lin_solves += fluid->diffuse(h, w2_, w1_);
  stats.lin_solves += fluid->project_divergence_free(w1_);
  y = w1_;
  return y.allFinite() ? Status::ok : Status::unstable;
}

}  // namespace stiffbench
