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

// The parameters several models share, with their keys, help texts and bounds; the model gives
// its default (its options struct's).
ParamSpec mass_spec(double mass, const char* each);        // "mass of each point" (each = "point")
ParamSpec gravity_spec(double gravity, const char* axis);  // along -axis
ParamSpec seed_spec(unsigned long seed);                   // of the random perturbation
ParamSpec point_damping_spec(const char* key, double point_damping);  // force -key v
ParamSpec dashpot_spec(double dashpot);                               // of every spring
ParamSpec compressed_dd_spec(bool compressed_dd_only);
ParamSpec parallel_threshold_spec(long parallel_threshold);
// `split`, default none, with the model's own help text and choices.
ParamSpec split_spec(std::string help, std::vector<std::string> choices);

}  // namespace stiffbench::spring_params
