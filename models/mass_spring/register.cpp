// Registration of the mass-spring models with their parameters (defaults and meaning for
// `stiffbench describe`). Models and their physics: models/mass_spring/builders.hpp.
#include <algorithm>
#include <charconv>

#include "models/mass_spring/builders.hpp"
#include "models/register.hpp"

namespace stiffbench {

namespace {

template <class Enum>
Enum choice(const Params& p, const std::string& key, const std::vector<std::string>& names,
            const std::vector<Enum>& values) {
  const std::string& v = p.text(key);
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == v) return values[i];
  throw BadInput("parameter '" + key + "': unknown value '" + v + "'");
}

// Shortest round-trip text of a default value, so `describe` shows the builders' own defaults.
std::string str(double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}
std::string str(long x) { return std::to_string(x); }
std::string str(bool x) { return x ? "true" : "false"; }

NetworkSplit split_param(const Params& p) {
  return choice<NetworkSplit>(p, "split", {"none", "springs", "stretch"},
                              {NetworkSplit::none, NetworkSplit::springs, NetworkSplit::stretch});
}

unsigned long seed_param(const Params& p, const std::string& model) {
  const long seed = p.integer("seed");
  require_input(seed >= 0, model + ": parameter 'seed' must be >= 0");
  return static_cast<unsigned long>(seed);
}

// Sizes from the parameters alone (ModelSize): `points` point masses in `dim` dimensions with
// about `springs_per_point` springs each. Per spring about 96 bytes (ends, rest length,
// stiffness, damping, scratch); the force Jacobian has a dim x dim block per point and two per
// spring, and the first-order form [0 I; K D] twice that.
ModelSize lattice_size(double points, int dim, double springs_per_point, std::string driver) {
  points = std::max(points, 0.0) + 2;  // chains also keep their two end points in the state
  const double springs = points * springs_per_point;
  const double block = static_cast<double>(dim * dim);
  return {2.0 * dim * points, 96.0 * springs + 64.0 * points,
          2.0 * block * (points + 2.0 * springs), std::move(driver)};
}

double count(const Params& p, const std::string& key) {
  return std::max(static_cast<double>(p.integer(key)), 0.0);
}

}  // namespace

void register_mass_spring_models(ModelRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  const std::string threshold_help =
      "points from which the right-hand side runs in parallel with OpenMP (results do not "
      "depend on it)";

  const SpringChainOptions chain;
  reg.add(
      {.info =
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
            {"mass", P::real, str(chain.mass), "mass of each point", B::positive()},
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
            {"seed", P::integer, str(static_cast<long>(chain.seed)),
             "seed of the random perturbation", B::non_negative()},
            {"perturbation", P::real, str(chain.perturbation),
             "uniform random displacement in [-p, p] of every free mass (0: none; > 0 removes "
             "the exact solution)",
             B::non_negative()},
            {"gamma", P::real, str(chain.point_damping),
             "point damping coefficient (force -gamma v)", B::non_negative()},
            {"dashpot", P::real, str(chain.dashpot), "dashpot coefficient of every spring",
             B::non_negative()},
            {"split",
             P::text,
             "none",
             "additive split f = f_E + f_I: none, or springs (springs and dashpots implicit; "
             "point damping explicit)",
             {"none", "springs"}}},
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
       }});

  const ClothOptions cloth;
  reg.add(
      {.info =
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
                  {"mass", P::real, str(cloth.mass), "mass of each point", B::positive()},
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
                  {"gravity", P::real, str(cloth.gravity), "gravitational acceleration (along -z)",
                   B::non_negative()},
                  {"prestretch", P::real, str(cloth.prestretch),
                   "initial length / rest length of every spring (> 1: stretched)", B::positive()},
                  {"perturbation", P::real, str(cloth.perturbation),
                   "uniform random displacement in [-p, p] of every coordinate of every free point",
                   B::non_negative()},
                  {"seed", P::integer, str(static_cast<long>(cloth.seed)),
                   "seed of the random perturbation", B::non_negative()},
                  {"damping", P::real, str(cloth.point_damping),
                   "point damping coefficient (force -damping v)", B::non_negative()},
                  {"dashpot", P::real, str(cloth.dashpot), "dashpot coefficient of every spring",
                   B::non_negative()},
                  {"drag", P::real, str(cloth.air_drag),
                   "air drag coefficient b = rho C_d / 2: each triangle (two per cell) feels "
                   "-b A (vn)|vn| n, vn its mean velocity along its normal n, A its area",
                   B::non_negative()},
                  {"compressed_dd", P::boolean, str(cloth.compressed_dd_only),
                   "Jacobian keeps only k d d^T for compressed springs (inexact, definite)"},
                  {"parallel_threshold", P::integer, str(cloth.parallel_threshold), threshold_help,
                   B::at_least(1)},
                  {"split",
                   P::text,
                   "none",
                   "additive split f = f_E + f_I: none; springs (springs and dashpots implicit; "
                   "gravity, point damping and air drag explicit); stretch (structural springs "
                   "implicit; shear, bend, gravity, point damping and air drag explicit)",
                   {"none", "springs", "stretch"}}},
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
       }});

  const SoftCubeOptions cube;
  reg.add(
      {.info =
           {.name = "soft_cube",
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
       .params = {{"n", P::integer, str(cube.n), "points per edge", B::at_least(2)},
                  {"spacing", P::real, str(cube.spacing), "lattice spacing", B::positive()},
                  {"mass", P::real, str(cube.mass), "mass of each point", B::positive()},
                  {"k_edge", P::real, str(cube.k_edge), "stiffness of edge springs",
                   B::non_negative()},
                  {"k_face", P::real, str(cube.k_face), "stiffness of face-diagonal springs",
                   B::non_negative()},
                  {"k_body", P::real, str(cube.k_body), "stiffness of body-diagonal springs",
                   B::non_negative()},
                  {"scenario",
                   P::text,
                   "drop",
                   "drop: undeformed and spinning; compress: scaled by factor, at rest",
                   {"drop", "compress"}},
                  {"height", P::real, str(cube.height), "initial height of the lowest point",
                   B::any()},
                  {"spin", P::real, str(cube.spin),
                   "drop: angular velocity about the axis (1,2,3)/sqrt(14)", B::any()},
                  {"factor", P::real, str(cube.factor),
                   "compress: initial scale of the lattice (< 1 compresses)", B::positive()},
                  {"gravity", P::real, str(cube.gravity), "gravitational acceleration (along -z)",
                   B::non_negative()},
                  {"damping", P::real, str(cube.point_damping),
                   "point damping coefficient (force -damping v)", B::non_negative()},
                  {"dashpot", P::real, str(cube.dashpot), "dashpot coefficient of every spring",
                   B::non_negative()},
                  {"compressed_dd", P::boolean, str(cube.compressed_dd_only),
                   "Jacobian keeps only k d d^T for compressed springs (inexact, definite)"},
                  {"parallel_threshold", P::integer, str(cube.parallel_threshold), threshold_help,
                   B::at_least(1)},
                  {"split",
                   P::text,
                   "none",
                   "additive split f = f_E + f_I: none, or springs (springs and dashpots implicit; "
                   "gravity and point damping explicit)",
                   {"none", "springs"}}},
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
       }});

  const PendulumChainOptions pend;
  reg.add(
      {.info = {.name = "pendulum_chain",
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
                  {"mass", P::real, str(pend.mass), "mass of each bob", B::positive()},
                  {"gravity", P::real, str(pend.gravity), "gravitational acceleration (along -y)",
                   B::non_negative()},
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
       }});
}

}  // namespace stiffbench
