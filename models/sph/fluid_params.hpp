// The fluid parameters every SPH scene's registry entry takes (support, masses, equation of
// state, viscosity, walls, split; their physics: models/sph/sph_fluid.hpp), and the helpers the
// entries (models/sph/scenes.cpp, listed by models/sph/register.cpp) share.
#pragma once

#include "core/registry_types.hpp"
#include "models/sph/sph_fluid.hpp"

#include <string>
#include <vector>

namespace stiffbench::sph_params {

struct SceneDefaults {
  std::string n, c0, gravity, eos = "linear", clamp = "true", viscosity = "artificial",
                              alpha = "0.05", form = "variational";
  bool walls = true;
  // Equilibrium masses by default: with lattice masses Akinci's volumes make the first fluid row
  // at a wall 5% over-dense at the start (7% in a corner), and the resulting kick sent the 3D
  // dam break's front 30% ahead of Koshizuka & Oka at T = 1.16 (equilibrium: +3%) and up the
  // left wall (README, SPH fluid, for the measured 2D fronts).
  std::string masses = "equilibrium";
  std::string support = "2.5";
};

// The fluid parameters after the scene's own (`scene`), with the scene's defaults `d`.
std::vector<ParamSpec> fluid_specs(const SceneDefaults& d, std::vector<ParamSpec> scene);

// Reads the fluid parameters; `fall_height` sets the automatic sound speed.
SphOptions read_fluid(const Params& p, double spacing, double fall_height, const std::string& model,
                      bool walls);

// Integer parameter `key` of `model`, checked to lie in [lo, hi].
int int_param(const Params& p, const std::string& key, const std::string& model, long lo, long hi);

// Sizes from the parameters alone (ModelSize): `fluid` moving particles and `boundary` fixed ones.
ModelSize sph_size(int dim, double fluid, double boundary, const Params& p);

// a/b, 0 unless both are positive.
double ratio(double a, double b);

// "2D ..." / "3D ...".
std::string describe_dim(int dim, const char* text);

}  // namespace stiffbench::sph_params
