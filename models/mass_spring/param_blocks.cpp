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

}  // namespace stiffbench::spring_params
