// The mass-spring entries' shared parameters (models/mass_spring/param_blocks.hpp).
#include "models/mass_spring/param_blocks.hpp"

#include <algorithm>
#include <charconv>

namespace stiffbench::spring_params {

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

ParamSpec mass_spec(double mass, const char* each) {
  return {"mass", ParamType::real, str(mass), std::string("mass of each ") + each,
          Bounds::positive()};
}

ParamSpec gravity_spec(double gravity, const char* axis) {
  return {"gravity", ParamType::real, str(gravity),
          std::string("gravitational acceleration (along -") + axis + ")", Bounds::non_negative()};
}

ParamSpec seed_spec(unsigned long seed) {
  return {"seed", ParamType::integer, str(static_cast<long>(seed)),
          "seed of the random perturbation", Bounds::non_negative()};
}

ParamSpec point_damping_spec(const char* key, double point_damping) {
  return {key, ParamType::real, str(point_damping),
          std::string("point damping coefficient (force -") + key + " v)", Bounds::non_negative()};
}

ParamSpec dashpot_spec(double dashpot) {
  return {"dashpot", ParamType::real, str(dashpot), "dashpot coefficient of every spring",
          Bounds::non_negative()};
}

ParamSpec compressed_dd_spec(bool compressed_dd_only) {
  return {"compressed_dd", ParamType::boolean, str(compressed_dd_only),
          "Jacobian keeps only k d d^T for compressed springs (inexact, definite)"};
}

ParamSpec parallel_threshold_spec(long parallel_threshold) {
  return {"parallel_threshold", ParamType::integer, str(parallel_threshold),
          "points from which the right-hand side runs in parallel with OpenMP (results do not "
          "depend on it)",
          Bounds::at_least(1)};
}

ParamSpec split_spec(std::string help, std::vector<std::string> choices) {
  return {"split", ParamType::text, "none", std::move(help), std::move(choices)};
}

}  // namespace stiffbench::spring_params
