// The SPH scenes' shared fluid parameters (models/sph/fluid_params.hpp).
#include "models/sph/fluid_params.hpp"

#include <algorithm>
#include <cmath>

namespace stiffbench::sph_params {

using P = ParamType;
using B = Bounds;

std::vector<ParamSpec> fluid_specs(const SceneDefaults& d, std::vector<ParamSpec> scene) {
  std::vector<ParamSpec> s = std::move(scene);
  const auto& kernels = sph::kernel_names();
  std::vector<std::string> smooth_kernels;
  for (const auto& k : kernels)
    if (k != "viscosity") smooth_kernels.push_back(k);
  s.push_back({"support", P::real, d.support, "kernel support radius h in particle spacings (h/dx)",
               B::above(1)});
  s.push_back({"masses",
               P::text,
               d.masses,
               "particle masses: lattice (rho0 / kernel sum over a full lattice) or equilibrium "
               "(every particle starts at exactly rho0, or at the hydrostatic density in scenes "
               "at rest under gravity)",
               {"lattice", "equilibrium"}});
  s.push_back({"rho0", P::real, "1000", "rest density (kg/m^3)", B::positive()});
  s.push_back({"c0", P::real, d.c0,
               "speed of sound (m/s); 0: 10 x sqrt(2 g H), the speed of a free fall from the "
               "fluid height H",
               B::non_negative()});
  s.push_back({"k", P::real, "-1",
               "linear EOS constant k in p = k (rho - rho0) (m^2/s^2); < 0: c0^2", B::any()});
  s.push_back({"eos", P::text, d.eos, "equation of state", {"linear", "tait"}});
  s.push_back({"clamp", P::boolean, d.clamp, "clamp the pressure at 0 (no tension)"});
  s.push_back({"tait_gamma", P::real, "7", "Tait exponent gamma", B::above(1)});
  s.push_back({"form",
               P::text,
               d.form,
               "pressure force: symmetric (Mueller 2003) or variational (p_i/rho_i^2 + "
               "p_j/rho_j^2; energy-conserving)",
               {"symmetric", "variational"}});
  s.push_back(
      {"density_kernel", P::text, "wendland_c2", "kernel of the density sum", smooth_kernels});
  s.push_back({"gradient_kernel", P::text, "wendland_c2", "kernel of the pressure gradient",
               smooth_kernels});
  s.push_back({"viscosity",
               P::text,
               d.viscosity,
               "viscosity: Mueller's Laplacian form (mu) or Monaghan's artificial viscosity "
               "(alpha)",
               {"none", "muller", "artificial"}});
  s.push_back(
      {"mu", P::real, "0", "dynamic viscosity of the Mueller form (Pa s)", B::non_negative()});
  s.push_back(
      {"alpha", P::real, d.alpha, "Monaghan artificial viscosity alpha", B::non_negative()});
  s.push_back(
      {"gravity", P::real, d.gravity, "gravitational acceleration along -y (m/s^2)", B::any()});
  if (d.walls) {
    s.push_back({"boundary",
                 P::text,
                 "particles",
                 "walls: boundary particles (Akinci et al. 2012) or a smooth penalty force",
                 {"particles", "penalty"}});
    s.push_back({"boundary_layers", P::integer, "3", "layers of boundary particles", B::in(1, 10)});
    s.push_back({"boundary_pressure",
                 P::text,
                 "akinci",
                 "boundary particles' pressure force: akinci (-rho0 V_b p_i/rho_i^2 grad W, "
                 "energy-consistent) or mirrored (twice that: p_b = p_i)",
                 {"akinci", "mirrored"}});
  }
  s.push_back({"parallel_threshold", P::integer, "512",
               "fluid particles from which the right-hand side runs with OpenMP (results do not "
               "depend on it)",
               B::non_negative()});
  s.push_back({"split",
               P::text,
               "none",
               "additive split f = f_E + f_I: none, or viscosity (viscosity with its boundary "
               "terms implicit; pressure, walls and gravity explicit)",
               {"none", "viscosity"}});
  return s;
}

// Reads the fluid parameters; `fall_height` sets the automatic sound speed.
SphOptions read_fluid(const Params& p, double spacing, double fall_height, const std::string& model,
                      bool walls) {
  const std::string who = model + ": parameter ";
  SphOptions o;
  o.spacing = spacing;
  const double support = p.real("support");
  require_input(std::isfinite(support) && support > 1.0, who + "'support' must be > 1");
  o.support = support * spacing;
  o.equilibrium_masses = p.text("masses") == "equilibrium";
  o.rho0 = p.real("rho0");
  const double g = p.real("gravity");
  require_input(std::isfinite(g), who + "'gravity' must be finite");
  o.gravity = {0.0, -g, 0.0};
  double c0 = p.real("c0");
  require_input(std::isfinite(c0) && c0 >= 0, who + "'c0' must be >= 0");
  if (c0 == 0) {
    require_input(g != 0, who + "'c0' = 0 (automatic) needs gravity != 0");
    c0 = 10.0 * std::sqrt(2.0 * std::abs(g) * fall_height);
  }
  o.c0 = c0;
  o.k = p.real("k");
  o.eos = p.text("eos") == "tait" ? SphEos::tait : SphEos::linear;
  o.clamp = p.boolean("clamp");
  o.tait_gamma = p.real("tait_gamma");
  o.form =
      p.text("form") == "symmetric" ? SphPressureForm::symmetric : SphPressureForm::variational;
  o.density_kernel = sph::kernel_from_string(p.text("density_kernel"));
  o.gradient_kernel = sph::kernel_from_string(p.text("gradient_kernel"));
  const std::string& visc = p.text("viscosity");
  o.viscosity = visc == "muller"       ? SphViscosity::muller
                : visc == "artificial" ? SphViscosity::artificial
                                       : SphViscosity::none;
  o.mu = p.real("mu");
  o.alpha = p.real("alpha");
  if (walls) {
    o.boundary = p.text("boundary") == "penalty" ? SphBoundary::penalty : SphBoundary::particles;
    o.mirror_boundary_pressure = p.text("boundary_pressure") == "mirrored";
  }
  o.split = p.text("split") == "viscosity" ? SphSplit::viscosity : SphSplit::none;
  const long threshold = p.integer("parallel_threshold");
  require_input(threshold >= 0, who + "'parallel_threshold' must be >= 0");
  o.parallel_threshold = threshold;
  return o;
}

int int_param(const Params& p, const std::string& key, const std::string& model, long lo, long hi) {
  const long v = p.integer(key);
  require_input(v >= lo && v <= hi, model + ": parameter '" + key + "' must be in [" +
                                        std::to_string(lo) + ", " + std::to_string(hi) + "] (got " +
                                        std::to_string(v) + ")");
  return static_cast<int>(v);
}

// Sizes from the parameters alone (ModelSize): `fluid` moving particles (2·dim unknowns each)
// and `boundary` fixed ones. Per particle about 1.5 KB: with support 2.5 spacings a particle
// has ~20 neighbours in 2D and ~65 in 3D, kept as index + weight pairs, plus the grid and
// per-particle fields. Ratios of lengths are clamped to >= 0 (bad values are refused later by
// the model itself).
ModelSize sph_size(int dim, double fluid, double boundary, const Params& p) {
  fluid = std::max(fluid, 0.0);
  boundary = std::max(boundary, 0.0);
  const double neighbours = dim == 2 ? 30 : 100;
  return {2.0 * dim * fluid, 1536.0 * (fluid + boundary), fluid * 2.0 * dim * dim * neighbours,
          "n=" + std::to_string(p.integer("n"))};
}

double ratio(double a, double b) { return b > 0 && a > 0 ? a / b : 0.0; }

// "2D ..." / "3D ..." (appended, not concatenated: g++ 12 warns falsely on operator+ here).
std::string describe_dim(int dim, const char* text) {
  std::string s = dim == 2 ? "2D" : "3D";
  s.append(text);
  return s;
}

}  // namespace stiffbench::sph_params
