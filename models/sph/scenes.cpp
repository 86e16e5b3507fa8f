#include "models/sph/scenes.hpp"
#include "models/sph/fluid_params.hpp"

#include <cmath>

namespace stiffbench {

namespace {

std::array<double, 3> lattice_point(double dx, long i, long j, long k) {
  return {(static_cast<double>(i) + 0.5) * dx, (static_cast<double>(j) + 0.5) * dx,
          (static_cast<double>(k) + 0.5) * dx};
}

long cells(double extent, double dx) { return std::lround(extent / dx); }

}  // namespace

void add_tank_walls(const TankGeometry& t, SphScene& scene) {
  const long nx = cells(t.length, t.spacing), ny = cells(t.wall_height, t.spacing);
  const long nz = t.dim == 3 ? cells(t.depth, t.spacing) : 0;
  const long l = t.layers;
  const long k_lo = t.dim == 3 ? -l : 0, k_hi = t.dim == 3 ? nz + l : 1;
  for (long k = k_lo; k < k_hi; ++k)
    for (long j = -l; j < ny; ++j)
      for (long i = -l; i < nx + l; ++i) {
        const bool inside_x = i >= 0 && i < nx;
        const bool inside_z = t.dim == 2 || (k >= 0 && k < nz);
        if (inside_x && inside_z && j >= 0) continue;  // the tank's interior
        auto p = lattice_point(t.spacing, i, j, k);
        if (t.dim == 2) p[2] = 0.0;
        scene.boundary_x.push_back(p);
      }
  const double len = static_cast<double>(nx) * t.spacing;
  scene.walls.push_back({{1, 0, 0}, 0.0});    // left
  scene.walls.push_back({{-1, 0, 0}, -len});  // right
  scene.walls.push_back({{0, 1, 0}, 0.0});    // floor
  if (t.dim == 3) {
    const double dep = static_cast<double>(nz) * t.spacing;
    scene.walls.push_back({{0, 0, 1}, 0.0});
    scene.walls.push_back({{0, 0, -1}, -dep});
  }
}

namespace {

// Fluid particles filling the lattice cells [0, nx) × [0, ny) (× [0, nz)), at rest.
void fill_block(SphScene& scene, double dx, long nx, long ny, long nz) {
  for (long k = 0; k < std::max(1L, nz); ++k)
    for (long j = 0; j < ny; ++j)
      for (long i = 0; i < nx; ++i) {
        auto p = lattice_point(dx, i, j, k);
        if (scene.dim == 2) p[2] = 0.0;
        scene.fluid_x.push_back(p);
        scene.fluid_v.push_back({0.0, 0.0, 0.0});
      }
}

}  // namespace

SphScene make_dam_break_scene(const DamBreakOptions& o) {
  require_input(o.dim == 2 || o.dim == 3, "dam break: dim must be 2 or 3");
  require_input(std::isfinite(o.a) && o.a > 0, "dam break: parameter 'a' must be > 0");
  require_input(o.n >= 2, "dam break: parameter 'n' must be >= 2");
  require_input(o.layers >= 1, "dam break: parameter 'boundary_layers' must be >= 1");
  SphScene s;
  s.dim = o.dim;
  s.dam_break = true;
  s.column_width = o.a;
  s.rest_height = 2.0 * o.a;
  const double dx = o.a / o.n;
  const double depth = o.dim == 3 ? (o.depth > 0 ? o.depth : 0.5 * o.a) : 0.0;
  const long nz = o.dim == 3 ? std::max(1L, cells(depth, dx)) : 0;
  fill_block(s, dx, o.n, 2L * o.n, nz);
  TankGeometry t;
  t.dim = o.dim;
  t.spacing = dx;
  t.length = 4.0 * o.a;
  t.wall_height = o.wall_height_factor * o.a;
  t.depth = static_cast<double>(nz) * dx;
  t.layers = o.layers;
  add_tank_walls(t, s);
  s.description = "dam break: column a x 2a in a tank of length 4a";
  return s;
}

SphScene make_tank_scene(const TankOptions& o) {
  require_input(o.dim == 2 || o.dim == 3, "tank: dim must be 2 or 3");
  require_input(std::isfinite(o.width) && o.width > 0, "tank: parameter 'width' must be > 0");
  require_input(std::isfinite(o.height) && o.height > 0, "tank: parameter 'height' must be > 0");
  require_input(o.n >= 2, "tank: parameter 'n' must be >= 2");
  require_input(o.layers >= 1, "tank: parameter 'boundary_layers' must be >= 1");
  SphScene s;
  s.dim = o.dim;
  const double dx = o.height / o.n;
  const long nx = std::max(1L, cells(o.width, dx));
  const double depth = o.dim == 3 ? (o.depth > 0 ? o.depth : o.width) : 0.0;
  const long nz = o.dim == 3 ? std::max(1L, cells(depth, dx)) : 0;
  fill_block(s, dx, nx, o.n, nz);
  s.rest_height = o.height;
  TankGeometry t;
  t.dim = o.dim;
  t.spacing = dx;
  t.length = static_cast<double>(nx) * dx;
  t.wall_height = 1.5 * o.height;
  t.depth = static_cast<double>(nz) * dx;
  t.layers = o.layers;
  add_tank_walls(t, s);
  const double xc = 0.5 * t.length, zc = 0.5 * t.depth;
  for (double f : {0.25, 0.5, 0.75}) s.probes.push_back({xc, (1.0 - f) * o.height, zc});
  s.description = "tank at rest";
  return s;
}

SphScene make_drop_scene(const DropOptions& o) {
  require_input(std::isfinite(o.radius) && o.radius > 0, "drop: parameter 'radius' must be > 0");
  require_input(o.n >= 2, "drop: parameter 'n' must be >= 2");
  require_input(std::isfinite(o.rate) && std::isfinite(o.drift),
                "drop: parameters 'rate' and 'drift' must be finite");
  SphScene s;
  s.dim = 2;
  const double dx = 2.0 * o.radius / o.n;
  // Lattice points (i + ½)Δx - R inside the circle of radius R about the origin.
  for (long j = 0; j < o.n; ++j)
    for (long i = 0; i < o.n; ++i) {
      const double x = (static_cast<double>(i) + 0.5) * dx - o.radius;
      const double y = (static_cast<double>(j) + 0.5) * dx - o.radius;
      if (x * x + y * y > o.radius * o.radius) continue;
      s.fluid_x.push_back({x, y, 0.0});
      std::array<double, 3> v{o.drift, 0.0, 0.0};
      if (o.velocity == DropOptions::Velocity::oscillation) {
        v[0] += o.rate * x;
        v[1] -= o.rate * y;
      } else if (o.velocity == DropOptions::Velocity::rotation) {
        v[0] -= o.rate * y;
        v[1] += o.rate * x;
      }
      s.fluid_v.push_back(v);
    }
  s.description = "free drop";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Registry entries (listed by models/sph/register.cpp) with their parameters: each scene's own,
// then the fluid's (fluid_params.hpp).

namespace {
using namespace sph_params;
using P = ParamType;
using B = Bounds;
}  // namespace

ModelRegistry::Entry sph_dam_break_entry(int dim) {
  const std::string name = dim == 2 ? "sph_dam_break_2d" : "sph_dam_break_3d";
  const SceneDefaults d{std::to_string(dim == 2 ? 32 : 12), "0", "9.81"};
  std::vector<ParamSpec> scene = {
      {"a", P::real, "0.146", "column width a (m); the column is a x 2a, the tank 4a long",
       B::positive()},
      {"n", P::integer, d.n, "particles across the column width a", B::in(2, 2000)},
      {"wall_height", P::real, "4", "height of the tank walls in units of a", B::at_least(2)}};
  if (dim == 3)
    scene.push_back({"depth", P::real, "0", "tank depth (m); 0: a/2", B::non_negative()});
  return {.info = {.name = name,
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
          }};
}

ModelRegistry::Entry sph_tank_entry(int dim) {
  const std::string name = dim == 2 ? "sph_tank_2d" : "sph_tank_3d";
  const SceneDefaults d{std::to_string(dim == 2 ? 20 : 10), "0", "9.81"};
  std::vector<ParamSpec> scene = {
      {"width", P::real, "0.2", "tank width (m), rounded to a multiple of the spacing",
       B::positive()},
      {"height", P::real, "0.1", "fluid height H (m)", B::positive()},
      {"n", P::integer, d.n, "particles across the fluid height", B::in(2, 2000)}};
  if (dim == 3)
    scene.push_back({"depth", P::real, "0", "tank depth (m); 0: the width", B::non_negative()});
  return {
      .info = {.name = name,
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
                         (p.real("depth") > 0 ? ratio(p.real("depth"), p.real("height")) * n : nw) +
                         1;
                     return sph_size(3, nw * n * nd, layers * (nw * nd + 4 * n * (nw + nd) + 64),
                                     p);
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
      }};
}

ModelRegistry::Entry sph_drop_entry() {
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
  return {
      .info =
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
      }};
}

}  // namespace stiffbench
