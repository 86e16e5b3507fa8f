// Scenes of the SPH fluid (sph_fluid.hpp), registered as models in models/sph/register.cpp.
// All on a square (cubic) lattice of spacing Δx, particle centres at (i + ½)Δx, so a column of
// n particles fills [0, nΔx] exactly.
//
// Tank walls (dam break, tank): boundary particles continue the fluid lattice outside the tank
// [0, L] × [0, wall height] (× [0, depth] in 3D): `layers` layers below the floor and beyond each
// side wall (and the front/back walls in 3D), up to the wall height. The walls' inner faces are
// the planes x = 0, x = L, y = 0 (z = 0, z = depth), which the penalty boundary uses instead.
//
// sph_dam_break_2d / _3d — a water column of width a and height 2a at the left end of a tank of
//   length 4a (Koshizuka & Oka 1996; Martin & Moyce 1952), at rest, under gravity -g e_y. The 3D
//   scene extrudes it over `depth` with walls in front and behind. Observables: the surge front
//   (largest x of a fluid particle, plus Δx/2 so that it starts at a; the left wall is x = 0) and
//   the water height at the left wall. Dimensionless: Z = front/a, T = t √(2g/a).
// sph_tank_2d / _3d — fluid of height H filling a tank of width W (and depth) at rest under
//   gravity, pressure probes on the vertical centre line at depths H/4, H/2 and 3H/4 (hydrostatic
//   p = ρ0 g (H - y) once settled).
// sph_drop_2d — a circular drop of radius R (lattice points inside the circle), no gravity, no
//   walls, initial velocity about its centre: oscillation v = A (x, -y) (the divergence-free
//   elliptic deformation of Monaghan's drop test), rotation v = A (-y, x), or none; plus a
//   uniform drift velocity along x (so that total momentum is not zero).
#pragma once

#include <memory>

#include "models/sph/sph_fluid.hpp"

namespace stiffbench {

struct TankGeometry {
  int dim = 2;
  double spacing = 0.01;
  double length = 1.0;       // L along x
  double wall_height = 1.0;  // along y
  double depth = 0.0;        // along z (3D)
  int layers = 3;            // boundary particle layers
};

// Boundary particles and wall planes of a tank (appended to `scene`).
void add_tank_walls(const TankGeometry& tank, SphScene& scene);

struct DamBreakOptions {
  int dim = 2;
  double a = 0.146;                 // column width (m)
  int n = 32;                       // particles across a
  double depth = 0.0;               // 3D: depth (m); 0: a/2
  double wall_height_factor = 4.0;  // walls are this × a high
  int layers = 3;
};
SphScene make_dam_break_scene(const DamBreakOptions& o);

struct TankOptions {
  int dim = 2;
  double width = 0.2, height = 0.1, depth = 0.0;  // 3D depth 0: width
  int n = 20;                                     // particles across the fluid height
  int layers = 3;
};
SphScene make_tank_scene(const TankOptions& o);

struct DropOptions {
  double radius = 0.1;
  int n = 20;  // particles across the diameter
  enum class Velocity { oscillation, rotation, none } velocity = Velocity::oscillation;
  double rate = 1.0;   // A (1/s)
  double drift = 0.0;  // uniform velocity along x (m/s)
};
SphScene make_drop_scene(const DropOptions& o);

}  // namespace stiffbench
