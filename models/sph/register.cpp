// Registration of the SPH scenes (models/sph/scenes.hpp) with their parameters. The physics and
// its options are documented in models/sph/sph_fluid.hpp.
#include <algorithm>
#include <cmath>

#include "models/register.hpp"
#include "models/sph/scenes.hpp"

namespace stiffbench {

namespace {

using P = ParamType;
using B = Bounds;

struct SceneDefaults {
  std::string n, c0, gravity, eos = "linear", clamp = "true", viscosity = "artificial",
                              alpha = "0.05", form = "variational";
  bool walls = true;
  // Equilibrium masses by default: with lattice masses Akinci's volumes make the first fluid row
  // at a wall 5% over-dense at the start (7% in a corner), and the resulting kick sent the 3D
  // dam break's front 30% ahead of Koshizuka & Oka at T = 1.16 (equilibrium: +3%) and up the
  // left wall (README, SPH fluid, for the measured 2D fronts).
  std::string masses = "equilibrium";
  std::string support = "2.5";
};

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

void add_dam_break(ModelRegistry& reg, int dim) {
  const std::string name = dim == 2 ? "sph_dam_break_2d" : "sph_dam_break_3d";
  const SceneDefaults d{std::to_string(dim == 2 ? 32 : 12), "0", "9.81"};
  std::vector<ParamSpec> scene = {
      {"a", P::real, "0.146", "column width a (m); the column is a x 2a, the tank 4a long",
       B::positive()},
      {"n", P::integer, d.n, "particles across the column width a", B::in(2, 2000)},
      {"wall_height", P::real, "4", "height of the tank walls in units of a", B::at_least(2)}};
  if (dim == 3)
    scene.push_back({"depth", P::real, "0", "tank depth (m); 0: a/2", B::non_negative()});
  reg.add({.info = {.name = name,
                    .description = describe_dim(
                        dim,
                        " SPH dam break: water column a x 2a released in a tank of length 4a; "
                        "observables front, height_left"),
                    .mechanical = true,
                    .source = "Koshizuka & Oka 1996 (surge front Z = front/a vs T = t sqrt(2g/a), "
                              "Nucl. Sci. Eng. 123); Martin & Moyce 1952",
                    .size =
                        [dim](const Params& p) {
                          // Column a x 2a (x depth) with n particles across a; tank 4a long,
                          // wall_height·a high.
                          const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                          const double wh = std::max(p.real("wall_height"), 0.0);
                          const double layers =
                              std::max(static_cast<double>(p.integer("boundary_layers")), 0.0);
                          if (dim == 2)
                            return sph_size(2, 2 * n * n, layers * (4 + 2 * wh) * n + 16, p);
                          const double depth =
                              p.real("depth") > 0 ? ratio(p.real("depth"), p.real("a")) : 0.5;
                          const double nd = depth * n + 1;
                          return sph_size(
                              3, 2 * n * n * nd,
                              layers * (4 * n * nd + 2 * (4 + wh) * n * n + 2 * wh * n * nd), p);
                        }},
           .params = fluid_specs(d, scene),
           .make = [dim, name](const Params& p) {
             DamBreakOptions o;
             o.dim = dim;
             o.a = p.real("a");
             o.n = int_param(p, "n", name, 2, 2000);
             o.wall_height_factor = p.real("wall_height");
             require_input(std::isfinite(o.wall_height_factor) && o.wall_height_factor >= 2,
                           name + ": parameter 'wall_height' must be >= 2");
             if (dim == 3) o.depth = p.real("depth");
             o.layers = int_param(p, "boundary_layers", name, 1, 10);
             const SphOptions f = read_fluid(p, o.a / o.n, 2.0 * o.a, name, true);
             return std::make_unique<SphFluid>(name, make_dam_break_scene(o), f);
           }});
}

void add_tank(ModelRegistry& reg, int dim) {
  const std::string name = dim == 2 ? "sph_tank_2d" : "sph_tank_3d";
  const SceneDefaults d{std::to_string(dim == 2 ? 20 : 10), "0", "9.81"};
  std::vector<ParamSpec> scene = {
      {"width", P::real, "0.2", "tank width (m), rounded to a multiple of the spacing",
       B::positive()},
      {"height", P::real, "0.1", "fluid height H (m)", B::positive()},
      {"n", P::integer, d.n, "particles across the fluid height", B::in(2, 2000)}};
  if (dim == 3)
    scene.push_back({"depth", P::real, "0", "tank depth (m); 0: the width", B::non_negative()});
  reg.add({.info = {.name = name,
                    .description = describe_dim(
                        dim,
                        " SPH tank: fluid at rest under gravity; pressure probes at depths H/4, "
                        "H/2, 3H/4"),
                    .mechanical = true,
                    .source = "hydrostatic pressure p = rho0 g (H - y) (docs/reference-values.md)",
                    .size =
                        [dim](const Params& p) {
                          // Fluid width x height with n particles across the height, walls 2H high.
                          const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                          const double nw = ratio(p.real("width"), p.real("height")) * n + 1;
                          const double layers =
                              std::max(static_cast<double>(p.integer("boundary_layers")), 0.0);
                          if (dim == 2) return sph_size(2, nw * n, layers * (nw + 4 * n + 16), p);
                          const double nd =
                              (p.real("depth") > 0 ? ratio(p.real("depth"), p.real("height")) * n
                                                   : nw) +
                              1;
                          return sph_size(3, nw * n * nd,
                                          layers * (nw * nd + 4 * n * (nw + nd) + 64), p);
                        }},
           .params = fluid_specs(d, scene),
           .make = [dim, name](const Params& p) {
             TankOptions o;
             o.dim = dim;
             o.width = p.real("width");
             o.height = p.real("height");
             o.n = int_param(p, "n", name, 2, 2000);
             if (dim == 3) o.depth = p.real("depth");
             o.layers = int_param(p, "boundary_layers", name, 1, 10);
             const SphOptions f = read_fluid(p, o.height / o.n, o.height, name, true);
             return std::make_unique<SphFluid>(name, make_tank_scene(o), f);
           }});
}

void add_drop(ModelRegistry& reg) {
  const std::string name = "sph_drop_2d";
  const SceneDefaults d{"20", "10",          "0",   "linear",      "false", "none",
                        "0",  "variational", false, "equilibrium", "2.5"};
  std::vector<ParamSpec> scene = {
      {"radius", P::real, "0.1", "drop radius R (m)", B::positive()},
      {"n", P::integer, d.n, "particles across the diameter", B::in(2, 4000)},
      {"velocity",
       P::text,
       "oscillation",
       "initial velocity about the centre: oscillation A(x, -y), rotation A(-y, x), none",
       {"oscillation", "rotation", "none"}},
      {"rate", P::real, "1", "A (1/s)", B::any()},
      {"drift", P::real, "0", "uniform initial velocity along x (m/s)", B::any()}};
  reg.add(
      {.info =
           {.name = name,
            .description =
                "2D SPH drop: no gravity, no walls, inviscid by default, oscillating or rotating "
                "(momentum, angular momentum, energy and convergence tests)",
            .mechanical = true,
            .source = "Monaghan's elliptic drop; invariants energy, momentum and angular momentum",
            .size =
                [](const Params& p) {
                  // A disc n particles across: about (pi/4) n^2 particles (no walls).
                  const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                  return sph_size(2, 0.8 * n * n + 8, 0, p);
                }},
       .params = fluid_specs(d, scene),
       .make = [name](const Params& p) {
         DropOptions o;
         o.radius = p.real("radius");
         o.n = int_param(p, "n", name, 2, 4000);
         const std::string& v = p.text("velocity");
         o.velocity = v == "rotation"      ? DropOptions::Velocity::rotation
                      : v == "oscillation" ? DropOptions::Velocity::oscillation
                                           : DropOptions::Velocity::none;
         o.rate = p.real("rate");
         o.drift = p.real("drift");
         const SphOptions f = read_fluid(p, 2.0 * o.radius / o.n, 2.0 * o.radius, name, false);
         return std::make_unique<SphFluid>(name, make_drop_scene(o), f);
       }});
}

}  // namespace

void register_sph_models(ModelRegistry& reg) {
  add_dam_break(reg, 2);
  add_dam_break(reg, 3);
  add_tank(reg, 2);
  add_tank(reg, 3);
  add_drop(reg);
}

}  // namespace stiffbench
