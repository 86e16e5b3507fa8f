// What the mass-spring models' registry entries (NAME_entry() beside each builder in
// models/mass_spring/builders.cpp, listed by models/mass_spring/register.cpp) share.
#pragma once

#include "core/registry_types.hpp"
#include "models/mass_spring/network.hpp"

#include <string>
#include <vector>

namespace stiffbench::spring_params {

template <class Enum>
Enum choice(const Params& p, const std::string& key, const std::vector<std::string>& names,
            const std::vector<Enum>& values) {
  const std::string& v = p.text(key);
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == v) return values[i];
  throw BadInput("parameter '" + key + "': unknown value '" + v + "'");
}

// Shortest round-trip text of a default value, so `describe` shows the builders' own defaults.
std::string str(double x);
std::string str(long x);
std::string str(bool x);

// The `split` parameter.
NetworkSplit split_param(const Params& p);

// The `seed` parameter, checked to be >= 0.
unsigned long seed_param(const Params& p, const std::string& model);

// Sizes from the parameters alone (ModelSize): `points` point masses in `dim` dimensions with
// about `springs_per_point` springs each.
ModelSize lattice_size(double points, int dim, double springs_per_point, std::string driver);

// Integer parameter `key`, at least 0, as a double.
double count(const Params& p, const std::string& key);

inline constexpr const char* kParallelThresholdHelp =
    "points from which the right-hand side runs in parallel with OpenMP (results do not "
    "depend on it)";

}  // namespace stiffbench::spring_params
