// The plain 3D SPH peer: the right-hand side of a weakly compressible SPH fluid
// written directly over arrays, as a straightforward gather with neighbour lists rebuilt from a
// cell grid at every call. Same kernel and equations as SphFluid (models/sph/sph_fluid.hpp) for
// the options of the dam-break scenes: Wendland C2 kernel (Wendland 1995) for density and
// gradient, density by summation with Akinci et al.'s (2012) boundary volumes, linear clamped
// equation of state p = max(0, k (ρ - ρ0)), the variational pressure force
// -Σ_j m_j (p_i/ρ_i² + p_j/ρ_j²) ∇W_ij, Akinci's boundary pressure -Σ_b ρ0 V_b p_i/ρ_i² ∇W_ib,
// Monaghan's (1992) artificial viscosity on fluid and boundary pairs, and gravity. The geometry
// (masses, boundary particles, volumes) is read from the SphFluid it is compared with; any other
// option is refused (std::invalid_argument).
//
// Per call: a dense cell grid (cells of the support h) over the fluid particles by counting sort,
// then for every particle its neighbour list (fluid, then boundary from a boundary grid built
// once) in CSR form, then the density pass and the force pass over those lists; OpenMP over
// particles (static schedule) in every pass.
#pragma once

#include <cstdint>
#include <vector>

#include "models/sph/sph_fluid.hpp"

namespace stiffbench::bench {

class PlainSph3d {
 public:
  explicit PlainSph3d(const SphFluid& fluid);
  // x, v: 3 coordinates per fluid particle (the testbed's layout); a: accelerations.
  void acceleration(const double* x, const double* v, double* a) const;
  Index particles() const { return n_; }

 private:
  struct Grid {
    double inv_cell = 1.0;
    std::int64_t lo[3] = {0, 0, 0}, dims[3] = {1, 1, 1};
    std::vector<std::size_t> start;  // per cell, + 1
    std::vector<std::int32_t> items;
    void build(const double* x, Index n, double cell);
    std::int64_t coord(double x, int d) const;
  };
  void build_lists(const double* x) const;

  Index n_ = 0;
  double h_ = 0, rho0_ = 0, k_ = 0, alpha_c_hs_ = 0, eps2_ = 0, sigma_ = 0;
  double g_[3] = {0, 0, 0};
  std::vector<double> m_, bx_, bvol_;
  Grid bgrid_;
  mutable Grid grid_;
  mutable std::vector<std::size_t> start_, bstart_;
  mutable std::vector<std::int32_t> nbr_, bnbr_;
  mutable std::vector<double> rho_, pr2_;
};

}  // namespace stiffbench::bench
