#include "models/mass_spring/builders.hpp"
#include "models/mass_spring/param_blocks.hpp"

#include <cmath>
#include <numbers>
#include <random>

#include "models/problems/harmonic_oscillator.hpp"

namespace stiffbench {

namespace {

// BadInput "<model>: parameter '<key>' must be <what>" unless cond.
void check(bool cond, const char* model, const char* key, const char* what) {
  require_input(cond, std::string(model) + ": parameter '" + key + "' must be " + what);
}

bool positive(double x) { return std::isfinite(x) && x > 0; }
bool non_negative(double x) { return std::isfinite(x) && x >= 0; }

// Mode shape of the chain at mass i (1..n).
double chain_mode_shape(const SpringChainOptions& o, long j, long i) {
  const double pi = std::numbers::pi;
  const auto n = static_cast<double>(o.n);
  return o.fixed_free ? std::sin((2.0 * j - 1.0) * pi * i / (2.0 * n + 1.0))
                      : std::sin(j * pi * i / (n + 1.0));
}

}  // namespace

using namespace spring_params;

double spring_chain_frequency(const SpringChainOptions& o, long j) {
  const double pi = std::numbers::pi;
  const auto n = static_cast<double>(o.n);
  const double s = o.fixed_free ? std::sin((2.0 * j - 1.0) * pi / (2.0 * (2.0 * n + 1.0)))
                                : std::sin(j * pi / (2.0 * (n + 1.0)));
  return 2.0 * std::sqrt(o.k / o.mass) * s;
}

std::unique_ptr<MassSpringNetwork> make_spring_chain(const SpringChainOptions& o) {
  const char* model = "spring_chain";
  check(o.n >= 1, model, "n", ">= 1");
  check(positive(o.k), model, "k", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(positive(o.rest_length), model, "rest_length", "> 0");
  check(o.mode >= 0 && o.mode <= o.n, model, "mode", "between 0 and n");
  check(std::isfinite(o.amplitude) && std::abs(o.amplitude) < 0.5 * o.rest_length, model,
        "amplitude", "smaller than rest_length/2 in magnitude (neighbours must not meet)");
  check(non_negative(o.perturbation) && o.perturbation < 0.5 * o.rest_length, model, "perturbation",
        ">= 0 and < rest_length/2");
  check(non_negative(o.point_damping), model, "gamma", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");

  const long n_points = o.n + (o.fixed_free ? 1 : 2);
  std::vector<MassPoint> points(static_cast<std::size_t>(n_points));
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (long i = 0; i < n_points; ++i) {
    MassPoint& p = points[static_cast<std::size_t>(i)];
    p.mass = o.mass;
    p.x[0] = static_cast<double>(i) * o.rest_length;
    p.pinned = i == 0 || i == o.n + 1;
    if (!p.pinned) {
      if (o.mode > 0) p.x[0] += o.amplitude * chain_mode_shape(o, o.mode, i);
      if (o.perturbation > 0) p.x[0] += o.perturbation * uniform(rng);
    }
  }
  std::vector<Spring> springs;
  for (long i = 0; i + 1 < n_points; ++i)
    springs.push_back({i, i + 1, o.k, o.rest_length, o.dashpot, SpringKind::structural});
  NetworkOptions net;
  net.point_damping = o.point_damping;
  net.split = o.split;
  auto sys =
      std::make_unique<MassSpringNetwork>(model, 1, std::move(points), std::move(springs), net);
  if (o.perturbation == 0) {
    // Mode j as the damped oscillator q'' + (γ/m + cω²/k) q' + ω² q = 0, q(0) = 1, q'(0) = 0
    // (header comment), solved in closed form by HarmonicOscillator.
    const double omega = o.mode > 0 ? spring_chain_frequency(o, o.mode) : 1.0;
    const double damping = o.point_damping / o.mass + o.dashpot * omega * omega / o.k;
    const HarmonicOscillator mode(1.0, omega * omega, damping, 1.0, 0.0);
    const SpringChainOptions opt = o;
    sys->set_exact([opt, mode, n_points](double t, VecRef y) {
      Vec q(2);
      mode.exact(t, q);
      for (long i = 0; i < n_points; ++i) {
        const bool pinned = i == 0 || i == opt.n + 1;
        const double shape =
            (pinned || opt.mode == 0) ? 0.0 : opt.amplitude * chain_mode_shape(opt, opt.mode, i);
        y[i] = static_cast<double>(i) * opt.rest_length + shape * q[0];
        y[n_points + i] = shape * q[1];
      }
    });
  }
  return sys;
}

ModelRegistry::Entry spring_chain_entry() {
  using P = ParamType;
  using B = Bounds;
  const SpringChainOptions chain;
  return {
      .info =
          {.name = "spring_chain",
           .description =
               "1D chain of N masses between pinned ends (fixed-fixed or fixed-free), one normal "
               "mode excited",
           .mechanical = true,
           .exact = true,
           .source = "normal modes w_j = 2 sqrt(k/m) sin(j pi/(2(N+1))) "
                     "(docs/reference-values.md); exact "
                     "unless perturbation > 0",
           .size =
               [](const Params& p) {
                 return lattice_size(count(p, "n"), 1, 1, "n=" + std::to_string(p.integer("n")));
               },
           .rest_state = {{"mode", "0"}, {"perturbation", "0"}}},
      .params =
          {{"n", P::integer, str(chain.n), "number of free masses N", B::at_least(1)},
           {"k", P::real, str(chain.k), "spring stiffness", B::positive()},
           mass_spec(chain.mass, "point"),
           {"rest_length", P::real, str(chain.rest_length), "spring rest length (initial spacing)",
            B::positive()},
           {"ends",
            P::text,
            "fixed_fixed",
            "boundary: both ends pinned or the right end free",
            {"fixed_fixed", "fixed_free"}},
           {"mode", P::integer, str(chain.mode), "normal mode displaced initially (1..n; 0: none)",
            B::non_negative()},
           {"amplitude", P::real, str(chain.amplitude),
            "amplitude of the mode displacement (< rest_length/2)", B::any()},
           seed_spec(chain.seed),
           {"perturbation", P::real, str(chain.perturbation),
            "uniform random displacement in [-p, p] of every free mass (0: none; > 0 removes "
            "the exact solution)",
            B::non_negative()},
           point_damping_spec("gamma", chain.point_damping),
           dashpot_spec(chain.dashpot),
           split_spec(
               "additive split f = f_E + f_I: none, or springs (springs and dashpots implicit; "
               "point damping explicit)",
               {"none", "springs"})},
      .make = [](const Params& p) {
        SpringChainOptions o;
        o.n = p.integer("n");
        o.k = p.real("k");
        o.mass = p.real("mass");
        o.rest_length = p.real("rest_length");
        o.fixed_free = p.text("ends") == "fixed_free";
        o.mode = p.integer("mode");
        o.amplitude = p.real("amplitude");
        o.seed = seed_param(p, "spring_chain");
        o.perturbation = p.real("perturbation");
        o.point_damping = p.real("gamma");
        o.dashpot = p.real("dashpot");
        o.split = split_param(p);
        return make_spring_chain(o);
      }};
}

std::unique_ptr<MassSpringNetwork> make_cloth(const ClothOptions& o) {
  const char* model = "cloth";
  check(o.n >= 2, model, "n", ">= 2");
  check(o.m >= 2, model, "m", ">= 2 (or 0: same as n)");
  check(positive(o.spacing), model, "spacing", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.k_struct), model, "k_struct", ">= 0");
  check(non_negative(o.k_shear), model, "k_shear", ">= 0");
  check(non_negative(o.k_bend), model, "k_bend", ">= 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(positive(o.prestretch), model, "prestretch", "> 0");
  check(non_negative(o.perturbation) && o.perturbation < 0.25 * o.spacing, model, "perturbation",
        ">= 0 and < spacing/4");
  check(non_negative(o.point_damping), model, "damping", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");
  check(non_negative(o.air_drag), model, "drag", ">= 0");
  check(o.parallel_threshold >= 1, model, "parallel_threshold", ">= 1");

  const long nx = o.n, ny = o.m;
  auto id = [nx](long i, long j) { return static_cast<Index>(j * nx + i); };
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<MassPoint> points(static_cast<std::size_t>(nx * ny));
  for (long j = 0; j < ny; ++j) {
    for (long i = 0; i < nx; ++i) {
      MassPoint& p = points[static_cast<std::size_t>(id(i, j))];
      p.mass = o.mass;
      p.x = {(static_cast<double>(i) - 0.5 * static_cast<double>(nx - 1)) * o.spacing,
             (static_cast<double>(j) - 0.5 * static_cast<double>(ny - 1)) * o.spacing, 0.0};
      const bool top = j == ny - 1;
      p.pinned = (o.pin == ClothOptions::Pin::top_edge && top) ||
                 (o.pin == ClothOptions::Pin::corners && top && (i == 0 || i == nx - 1));
      if (!p.pinned && o.perturbation > 0)
        for (double& c : p.x) c += o.perturbation * uniform(rng);
    }
  }
  std::vector<Spring> springs;
  springs.reserve(static_cast<std::size_t>(6 * nx * ny));  // at most 6 per point
  const double rest = o.spacing / o.prestretch;
  const double diag = std::sqrt(2.0) * rest;
  auto add = [&](long i0, long j0, long i1, long j1, double k, double len, SpringKind kind) {
    if (i1 < 0 || i1 >= nx || j1 >= ny) return;
    springs.push_back({id(i0, j0), id(i1, j1), k, len, o.dashpot, kind});
  };
  for (long j = 0; j < ny; ++j) {
    for (long i = 0; i < nx; ++i) {
      add(i, j, i + 1, j, o.k_struct, rest, SpringKind::structural);
      add(i, j, i, j + 1, o.k_struct, rest, SpringKind::structural);
      add(i, j, i + 1, j + 1, o.k_shear, diag, SpringKind::shear);
      add(i, j, i - 1, j + 1, o.k_shear, diag, SpringKind::shear);
      add(i, j, i + 2, j, o.k_bend, 2 * rest, SpringKind::bend);
      add(i, j, i, j + 2, o.k_bend, 2 * rest, SpringKind::bend);
    }
  }
  NetworkOptions net;
  net.gravity = {0.0, 0.0, -o.gravity};
  net.point_damping = o.point_damping;
  net.compressed_dd_only = o.compressed_dd_only;
  net.parallel_threshold = o.parallel_threshold;
  net.split = o.split;
  net.air_drag = o.air_drag;
  // Air drag's triangles: each cell cut along its shear spring (i, j)-(i+1, j+1), both halves
  // with normal +z in the initial plane.
  std::vector<Triangle> triangles;
  if (o.air_drag > 0.0) {
    triangles.reserve(static_cast<std::size_t>(2 * (nx - 1) * (ny - 1)));
    for (long j = 0; j + 1 < ny; ++j)
      for (long i = 0; i + 1 < nx; ++i) {
        triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  }
  return std::make_unique<MassSpringNetwork>(model, 3, std::move(points), std::move(springs), net,
                                             std::vector<DistanceConstraint>{},
                                             std::move(triangles));
}

ModelRegistry::Entry cloth_entry() {
  using P = ParamType;
  using B = Bounds;
  const ClothOptions cloth;
  return {
      .info =
          {.name = "cloth",
           .description =
               "n x m cloth grid in 3D with structural, shear and bend springs, pinned corners or "
               "top edge, under gravity",
           .mechanical = true,
           .source = "mass-spring cloth (Provot 1995; Baraff & Witkin 1998 Jacobians)",
           .size =
               [](const Params& p) {
                 const double n = count(p, "n"), m = p.integer("m") == 0 ? n : count(p, "m");
                 return lattice_size(
                     n * m, 3, 6,
                     "n=" + std::to_string(p.integer("n")) +
                         (p.integer("m") ? " m=" + std::to_string(p.integer("m")) : ""));
               },
           .rest_state = {{"gravity", "0"}, {"perturbation", "0"}}},
      .params = {{"n", P::integer, str(cloth.n), "points along x", B::at_least(2)},
                 {"m", P::integer, "0", "points along y (0: same as n)", B::non_negative()},
                 {"spacing", P::real, str(cloth.spacing),
                  "grid spacing (initial length of structural springs)", B::positive()},
                 mass_spec(cloth.mass, "point"),
                 {"k_struct", P::real, str(cloth.k_struct),
                  "stiffness of structural springs (grid edges)", B::non_negative()},
                 {"k_shear", P::real, str(cloth.k_shear),
                  "stiffness of shear springs (cell diagonals)", B::non_negative()},
                 {"k_bend", P::real, str(cloth.k_bend),
                  "stiffness of bend springs (two cells apart)", B::non_negative()},
                 {"pin",
                  P::text,
                  "top_edge",
                  "pinned points: the two corners of the top edge, the whole top edge, or none",
                  {"corners", "top_edge", "none"}},
                 gravity_spec(cloth.gravity, "z"),
                 {"prestretch", P::real, str(cloth.prestretch),
                  "initial length / rest length of every spring (> 1: stretched)", B::positive()},
                 {"perturbation", P::real, str(cloth.perturbation),
                  "uniform random displacement in [-p, p] of every coordinate of every free point",
                  B::non_negative()},
                 seed_spec(cloth.seed),
                 point_damping_spec("damping", cloth.point_damping),
                 dashpot_spec(cloth.dashpot),
                 {"drag", P::real, str(cloth.air_drag),
                  "air drag coefficient b = rho C_d / 2: each triangle (two per cell) feels "
                  "-b A (vn)|vn| n, vn its mean velocity along its normal n, A its area",
                  B::non_negative()},
                 compressed_dd_spec(cloth.compressed_dd_only),
                 parallel_threshold_spec(cloth.parallel_threshold),
                 split_spec(
                     "additive split f = f_E + f_I: none; springs (springs and dashpots implicit; "
                     "gravity, point damping and air drag explicit); stretch (structural springs "
                     "implicit; shear, bend, gravity, point damping and air drag explicit)",
                     {"none", "springs", "stretch"})},
      .make = [](const Params& p) {
        ClothOptions o;
        o.perturbation = p.real("perturbation");
        o.seed = seed_param(p, "cloth");
        o.n = p.integer("n");
        o.m = p.integer("m") == 0 ? o.n : p.integer("m");
        o.spacing = p.real("spacing");
        o.mass = p.real("mass");
        o.k_struct = p.real("k_struct");
        o.k_shear = p.real("k_shear");
        o.k_bend = p.real("k_bend");
        o.pin = choice<ClothOptions::Pin>(
            p, "pin", {"corners", "top_edge", "none"},
            {ClothOptions::Pin::corners, ClothOptions::Pin::top_edge, ClothOptions::Pin::none});
        o.gravity = p.real("gravity");
        o.prestretch = p.real("prestretch");
        o.point_damping = p.real("damping");
        o.dashpot = p.real("dashpot");
        o.air_drag = p.real("drag");
        o.compressed_dd_only = p.boolean("compressed_dd");
        o.parallel_threshold = p.integer("parallel_threshold");
        o.split = split_param(p);
        return make_cloth(o);
      }};
}

std::unique_ptr<MassSpringNetwork> make_soft_cube(const SoftCubeOptions& o) {
  const char* model = "soft_cube";
  check(o.n >= 2, model, "n", ">= 2");
  check(positive(o.spacing), model, "spacing", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.k_edge), model, "k_edge", ">= 0");
  check(non_negative(o.k_face), model, "k_face", ">= 0");
  check(non_negative(o.k_body), model, "k_body", ">= 0");
  check(std::isfinite(o.height), model, "height", "finite");
  check(std::isfinite(o.spin), model, "spin", "finite");
  check(positive(o.factor), model, "factor", "> 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(non_negative(o.point_damping), model, "damping", ">= 0");
  check(non_negative(o.dashpot), model, "dashpot", ">= 0");
  check(o.parallel_threshold >= 1, model, "parallel_threshold", ">= 1");

  const long n = o.n;
  auto id = [n](long i, long j, long k) { return static_cast<Index>((k * n + j) * n + i); };
  const double s = o.spacing;
  const double half = 0.5 * s * static_cast<double>(n - 1);
  const bool drop = o.scenario == SoftCubeOptions::Scenario::drop;
  // Rigid rotation ω × r about the axis (1, 2, 3)/√14 through the centre (drop scenario).
  const double norm = std::sqrt(14.0);
  const double wx = (drop ? o.spin : 0.0) / norm, wy = 2 * wx, wz = 3 * wx;
  std::vector<MassPoint> points(static_cast<std::size_t>(n * n * n));
  for (long k = 0; k < n; ++k)
    for (long j = 0; j < n; ++j)
      for (long i = 0; i < n; ++i) {
        MassPoint& p = points[static_cast<std::size_t>(id(i, j, k))];
        p.mass = o.mass;
        const double scale = drop ? 1.0 : o.factor;
        const double rx = scale * (static_cast<double>(i) * s - half);
        const double ry = scale * (static_cast<double>(j) * s - half);
        const double rz = scale * (static_cast<double>(k) * s - half);
        p.x = {rx, ry, rz + half * scale + o.height};
        p.v = {wy * rz - wz * ry, wz * rx - wx * rz, wx * ry - wy * rx};
      }
  std::vector<Spring> springs;
  auto add = [&](long i, long j, long k, long di, long dj, long dk, double stiffness,
                 SpringKind kind) {
    const long i1 = i + di, j1 = j + dj, k1 = k + dk;
    if (i1 < 0 || i1 >= n || j1 < 0 || j1 >= n || k1 < 0 || k1 >= n) return;
    const double len = s * std::sqrt(static_cast<double>(di * di + dj * dj + dk * dk));
    springs.push_back({id(i, j, k), id(i1, j1, k1), stiffness, len, o.dashpot, kind});
  };
  // Each unordered pair once: offsets with a positive first non-zero component.
  for (long k = 0; k < n; ++k)
    for (long j = 0; j < n; ++j)
      for (long i = 0; i < n; ++i) {
        add(i, j, k, 1, 0, 0, o.k_edge, SpringKind::structural);
        add(i, j, k, 0, 1, 0, o.k_edge, SpringKind::structural);
        add(i, j, k, 0, 0, 1, o.k_edge, SpringKind::structural);
        for (long a : {1L, -1L}) {
          add(i, j, k, 1, a, 0, o.k_face, SpringKind::shear);
          add(i, j, k, 1, 0, a, o.k_face, SpringKind::shear);
          add(i, j, k, 0, 1, a, o.k_face, SpringKind::shear);
          for (long b : {1L, -1L}) add(i, j, k, 1, a, b, o.k_body, SpringKind::shear);
        }
      }
  NetworkOptions net;
  net.gravity = {0.0, 0.0, -o.gravity};
  net.point_damping = o.point_damping;
  net.compressed_dd_only = o.compressed_dd_only;
  net.parallel_threshold = o.parallel_threshold;
  net.split = o.split;
  return std::make_unique<MassSpringNetwork>(model, 3, std::move(points), std::move(springs), net);
}

ModelRegistry::Entry soft_cube_entry() {
  using P = ParamType;
  using B = Bounds;
  const SoftCubeOptions cube;
  return {
      .info = {.name = "soft_cube",
               .description =
                   "n x n x n lattice with edge, face- and body-diagonal springs, dropped spinning "
                   "under gravity or compressed and released",
               .mechanical = true,
               .source = "mass-spring soft body; centre of mass falls freely (x_cm'' = g)",
               .size =
                   [](const Params& p) {
                     const double n = count(p, "n");
                     return lattice_size(n * n * n, 3, 13, "n=" + std::to_string(p.integer("n")));
                   },
               .rest_state = {{"gravity", "0"}, {"spin", "0"}}},
      .params =
          {{"n", P::integer, str(cube.n), "points per edge", B::at_least(2)},
           {"spacing", P::real, str(cube.spacing), "lattice spacing", B::positive()},
           mass_spec(cube.mass, "point"),
           {"k_edge", P::real, str(cube.k_edge), "stiffness of edge springs", B::non_negative()},
           {"k_face", P::real, str(cube.k_face), "stiffness of face-diagonal springs",
            B::non_negative()},
           {"k_body", P::real, str(cube.k_body), "stiffness of body-diagonal springs",
            B::non_negative()},
           {"scenario",
            P::text,
            "drop",
            "drop: undeformed and spinning; compress: scaled by factor, at rest",
            {"drop", "compress"}},
           {"height", P::real, str(cube.height), "initial height of the lowest point", B::any()},
           {"spin", P::real, str(cube.spin),
            "drop: angular velocity about the axis (1,2,3)/sqrt(14)", B::any()},
           {"factor", P::real, str(cube.factor),
            "compress: initial scale of the lattice (< 1 compresses)", B::positive()},
           gravity_spec(cube.gravity, "z"),
           point_damping_spec("damping", cube.point_damping),
           dashpot_spec(cube.dashpot),
           compressed_dd_spec(cube.compressed_dd_only),
           parallel_threshold_spec(cube.parallel_threshold),
           split_spec(
               "additive split f = f_E + f_I: none, or springs (springs and dashpots implicit; "
               "gravity and point damping explicit)",
               {"none", "springs"})},
      .make = [](const Params& p) {
        SoftCubeOptions o;
        o.n = p.integer("n");
        o.spacing = p.real("spacing");
        o.mass = p.real("mass");
        o.k_edge = p.real("k_edge");
        o.k_face = p.real("k_face");
        o.k_body = p.real("k_body");
        o.scenario = choice<SoftCubeOptions::Scenario>(
            p, "scenario", {"drop", "compress"},
            {SoftCubeOptions::Scenario::drop, SoftCubeOptions::Scenario::compress});
        o.height = p.real("height");
        o.spin = p.real("spin");
        o.factor = p.real("factor");
        o.gravity = p.real("gravity");
        o.point_damping = p.real("damping");
        o.dashpot = p.real("dashpot");
        o.compressed_dd_only = p.boolean("compressed_dd");
        o.parallel_threshold = p.integer("parallel_threshold");
        o.split = split_param(p);
        return make_soft_cube(o);
      }};
}

std::unique_ptr<MassSpringNetwork> make_pendulum_chain(const PendulumChainOptions& o) {
  const char* model = "pendulum_chain";
  check(o.n >= 1, model, "n", ">= 1");
  check(positive(o.length), model, "length", "> 0");
  check(positive(o.mass), model, "mass", "> 0");
  check(non_negative(o.gravity), model, "gravity", ">= 0");
  check(positive(o.k), model, "k", "> 0");
  check(std::isfinite(o.angle), model, "angle", "finite");

  std::vector<MassPoint> points(static_cast<std::size_t>(o.n + 1));
  for (long i = 0; i <= o.n; ++i) {
    MassPoint& p = points[static_cast<std::size_t>(i)];
    p.mass = o.mass;
    const double r = static_cast<double>(i) * o.length;
    p.x = {r * std::sin(o.angle), -r * std::cos(o.angle), 0.0};
    p.pinned = i == 0;
  }
  std::vector<Spring> springs;
  std::vector<DistanceConstraint> constraints;
  for (long i = 0; i < o.n; ++i) {
    if (o.constrained)
      constraints.push_back({i, i + 1, o.length});
    else
      springs.push_back({i, i + 1, o.k, o.length, 0.0, SpringKind::structural});
  }
  NetworkOptions net;
  net.gravity = {0.0, -o.gravity, 0.0};
  return std::make_unique<MassSpringNetwork>(model, 2, std::move(points), std::move(springs), net,
                                             std::move(constraints));
}

ModelRegistry::Entry pendulum_chain_entry() {
  using P = ParamType;
  using B = Bounds;
  const PendulumChainOptions pend;
  return {
      .info = {.name = "pendulum_chain",
               .description =
                   "2D chain of n bobs hanging from a pin under gravity; stiff springs or exact "
                   "distance constraints (projection)",
               .mechanical = true,
               .source = "constrained version: SHAKE/RATTLE-style projection after every step",
               .size =
                   [](const Params& p) {
                     return lattice_size(count(p, "n"), 2, 1,
                                         "n=" + std::to_string(p.integer("n")));
                   }},
      .params = {{"n", P::integer, str(pend.n), "number of bobs", B::at_least(1)},
                 {"length", P::real, str(pend.length), "link length", B::positive()},
                 mass_spec(pend.mass, "bob"),
                 gravity_spec(pend.gravity, "y"),
                 {"k", P::real, str(pend.k), "link spring stiffness (ignored when constrained)",
                  B::positive()},
                 {"constrained", P::boolean, str(pend.constrained),
                  "links are exact distance constraints"},
                 {"angle", P::real, str(pend.angle),
                  "initial angle of the straight chain from the vertical (rad)", B::any()}},
      .make = [](const Params& p) {
        PendulumChainOptions o;
        o.n = p.integer("n");
        o.length = p.real("length");
        o.mass = p.real("mass");
        o.gravity = p.real("gravity");
        o.k = p.real("k");
        o.constrained = p.boolean("constrained");
        o.angle = p.real("angle");
        return make_pendulum_chain(o);
      }};
}

}  // namespace stiffbench
