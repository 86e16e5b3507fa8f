#include "models/sph/scenes.hpp"

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

}  // namespace stiffbench
