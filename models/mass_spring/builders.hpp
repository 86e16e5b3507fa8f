// Builders of the registered mass-spring models (see network.hpp for forces, Jacobians,
// invariants, stiffness and constraints). Units are nondimensional, like the other models.
//
// spring_chain — N free masses on a line (1D, longitudinal motion) joined by N+1 springs to a
//   pinned point at each end (fixed–fixed) or N springs with only the left end pinned
//   (fixed–free); equal k, m, rest length L; point i at x = iL (the pins at 0 and (N+1)L).
//   Normal modes (docs/reference-values.md): fixed–fixed φ_j(i) = sin(jπi/(N+1)),
//   ω_j = 2√(k/m) sin(jπ/(2(N+1))); fixed–free φ_j(i) = sin((2j-1)πi/(2N+1)),
//   ω_j = 2√(k/m) sin((2j-1)π/(2(2N+1))). Initial state: mode j displaced by amplitude A
//   (x_i = iL + A φ_j(i), v = 0) plus, when perturbation > 0, a seeded uniform random
//   displacement in [-perturbation, perturbation] of every free mass. In 1D the spring force
//   k(x_j - x_i - L) is linear while neighbours do not meet (|A| < L/2 guarantees it for the
//   mode), point damping gives D = -(γ/m)I and dashpots D = (c/k)K, so each mode is the damped
//   oscillator q'' + (γ/m + cω_j²/k) q' + ω_j² q = 0 and the model has the exact solution
//   x_i = iL + A φ_j(i) q(t), q(0) = 1, q'(0) = 0, whenever perturbation = 0.
//
// cloth — an n × m grid in 3D in the plane z = 0, centred on the origin: point (i, j) at
//   ((i - (n-1)/2) s, (j - (m-1)/2) s, 0), equal point masses; structural springs to (i+1, j),
//   (i, j+1); shear springs along both cell diagonals; bend springs to (i+2, j), (i, j+2); each
//   kind its own stiffness; every rest length is the initial length divided by `prestretch`
//   (> 1: initially stretched). Pins: `top_edge` = the whole row j = m-1, `corners` = the two
//   ends of that row, `none`. Gravity -g e_z. A seeded uniform random displacement in
//   [-perturbation, perturbation] of every coordinate of every free point. Point damping γ and a
//   dashpot c on every spring (both 0 by default, so the Verlet family applies). Air drag
//   (`drag` = β_d = ½ρC_d, 0 by default): each cell cut into two triangles along its shear spring
//   (i, j)-(i+1, j+1), each feeling F = -β_d A (v̄·n)|v̄·n| n (network.hpp). Starts at rest.
//   Defaults: 16 × 16, s = 0.1, m = 0.01, k = 12 / 1 / 0.5 (structural / shear / bend), top
//   edge pinned, g = 1, perturbation 0.003 (3% of s): a soft nondimensional cloth, chosen so
//   that the reference convergence study (T = 1, h = 1e-3 … 6.25e-5) is in the asymptotic range
//   of all of euler, heun, rk4, symplectic_euler and velocity_verlet. Measured at the initial
//   state: ω_max = 71.78 (Lanczos; cheap bound 103.9), so h ω_max = 0.072 at h = 1e-3, and
//   explicit Euler's growth exp(T h ω²/2) is 13 at h = 1e-3, 1.38 at 1.25e-4 and 1.17 at
//   6.25e-5. The perturbation puts energy into the fast spring modes: under gravity alone the
//   motion is slow and RK4's error at h = 6.25e-5 falls below the round-off floor (~1e-12) of
//   the reference run; with it RK4's error there is 2.6e-11 and its observed order 3.94. Spring
//   strains stay below 15% up to t = 1 (the top rows carry the cloth's weight).
//
// soft_cube — an n × n × n lattice in 3D with spacing s, equal point masses; edge springs to
//   the 6 axis neighbours, face-diagonal springs (12 per point) and body-diagonal springs
//   (8 per point), each kind its own stiffness (edge springs are `structural`, diagonals `shear`);
//   rest lengths from the undeformed lattice. No ground. Scenarios:
//     drop:     the undeformed cube, lowest corner at z = height, spinning rigidly with angular
//               velocity `spin` about the axis (1, 2, 3)/√14 through its centre, released under
//               gravity: the centre of mass falls freely (x_cm'' = g exactly, internal forces
//               cancel) while centrifugal stretching excites internal vibration;
//     compress: the lattice scaled by `factor` about its centre (factor < 1 compresses), at rest,
//               released under gravity (set gravity=0 for a body oscillating in place).
//
// pendulum_chain — n bobs hanging from a pinned point at the origin in 2D under gravity -g e_y,
//   links of length L, initially a straight line at angle θ from the downward vertical, at rest.
//   Links are stiff springs (stiffness k) or, with constrained=true, exact distance constraints
//   |x_i - x_{i+1}| = L enforced by projection (network.hpp), in which case k is ignored.
//   As k → ∞ the spring chain converges to the constrained motion (tests/models/test_mass_spring).
#pragma once

#include <memory>

#include "models/mass_spring/network.hpp"

namespace stiffbench {

struct SpringChainOptions {
  long n = 10;
  double k = 1.0, mass = 1.0, rest_length = 1.0;
  bool fixed_free = false;
  long mode = 1;  // 0: no mode displacement
  double amplitude = 0.1;
  unsigned long seed = 1;
  double perturbation = 0.0;
  double point_damping = 0.0, dashpot = 0.0;
  NetworkSplit split = NetworkSplit::none;  // none or springs (network.hpp)
};
std::unique_ptr<MassSpringNetwork> make_spring_chain(const SpringChainOptions& o);

// Angular frequency of normal mode j (1..n) of the chain (docs/reference-values.md).
double spring_chain_frequency(const SpringChainOptions& o, long j);

struct ClothOptions {
  long n = 16, m = 16;
  double spacing = 0.1, mass = 0.01;
  double k_struct = 12.0, k_shear = 1.0, k_bend = 0.5;
  enum class Pin { corners, top_edge, none } pin = Pin::top_edge;
  double gravity = 1.0, prestretch = 1.0;
  double perturbation = 0.003;
  unsigned long seed = 1;
  double point_damping = 0.0, dashpot = 0.0;
  double air_drag = 0.0;  // β_d = ½ρC_d of the quadratic drag on the cells' triangles (network.hpp)
  bool compressed_dd_only = false;
  long parallel_threshold = 2048;
  NetworkSplit split = NetworkSplit::none;  // none, springs or stretch (network.hpp)
};
std::unique_ptr<MassSpringNetwork> make_cloth(const ClothOptions& o);

struct SoftCubeOptions {
  long n = 4;
  double spacing = 0.25, mass = 0.02;
  double k_edge = 100.0, k_face = 50.0, k_body = 50.0;
  enum class Scenario { drop, compress } scenario = Scenario::drop;
  double height = 1.0, spin = 3.0, factor = 0.8;
  double gravity = 9.81;
  double point_damping = 0.0, dashpot = 0.0;
  bool compressed_dd_only = false;
  long parallel_threshold = 2048;
  NetworkSplit split = NetworkSplit::none;  // none or springs (network.hpp)
};
std::unique_ptr<MassSpringNetwork> make_soft_cube(const SoftCubeOptions& o);

struct PendulumChainOptions {
  long n = 5;
  double length = 0.2, mass = 0.2, gravity = 9.81;
  double k = 1e4;
  bool constrained = false;
  double angle = 0.5;  // rad from the downward vertical
};
std::unique_ptr<MassSpringNetwork> make_pendulum_chain(const PendulumChainOptions& o);

}  // namespace stiffbench
