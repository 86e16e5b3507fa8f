// StiffnessSpectrum: ω_max of a mass-spring network (models/mass_spring/network.hpp), the
// largest |eigenvalue|^½ of M⁻¹ ∂f_s/∂x over free dofs (springs only; pinned dofs excluded),
// i.e. the spectral radius of the first-order Jacobian [[0, I], [K, 0]] of the undamped network.
// Two estimates:
//   omega_max_bound: the cheap bound ω² <= max_i (2/m_i) Σ_e k_e max(1, |1 - L/l|) over free
//     points (block Gershgorin on M⁻¹ ∂f/∂x);
//   omega_max_estimate: Lanczos (core/lanczos.hpp: full reorthogonalisation, fixed start
//     vector, residual <= 1e-10 |θ|max or 300 steps) on the symmetric matrix
//     S = M^{-1/2} (-∂f_s/∂x) M^{-1/2} restricted to free dofs, applied spring by spring
//     without forming it; exact when the Krylov space fills up (the 10-mass chain: 10 steps).
//     Cost: 0.03 s for the 16 × 16 cloth, 0.9 s for 64 × 64. Each spring's direction and
//     coefficients are computed once per run, the products split between threads on large
//     networks, and above 256 MiB of Krylov basis Lanczos runs without storing it: on the 512 ×
//     512 cloth (786,432 coordinates, 300 steps) `solve`'s stiffness line took 15 s and 1.5 GB in
//     all (the model's Jacobian pattern included) against 130 s and 3 GB before
//     (two runs of the same command on a quiet machine, before and after, not alternated).
// Both ignore dashpots and point damping (with them the first-order spectral radius differs:
// for uniform γ/m and an underdamped mode it is still ω).
//
// A view: it holds references to the network's points and spring adjacency, which must outlive
// it (MassSpringNetwork makes one per call).
#pragma once

#include <utility>
#include <vector>

#include "core/types.hpp"
#include "models/mass_spring/elements.hpp"

namespace stiffbench {

class StiffnessSpectrum {
 public:
  StiffnessSpectrum(int dim, const std::vector<MassPoint>& points, const SpringAdjacency& adjacency)
      : dim_(dim), points_(points), adj_(adjacency) {}

  // ω_max at positions x (dim × points entries).
  double omega_max_bound(CVecRef x) const;
  double omega_max_estimate(CVecRef x) const;
  // Smallest and largest eigenvalue of S on free dofs (Lanczos); {0, 0} without free dofs or
  // springs.
  std::pair<double, double> eigen_range(CVecRef x) const;

 private:
  // Each adjacency entry's unit direction and its two coefficients at positions x (D + 2 numbers).
  template <int D>
  std::vector<double> spring_terms(const double* x) const;
  // out = H z with H = -∂f_s/∂x (springs only, exact J_s), from spring_terms.
  template <int D>
  void matvec(const double* terms, const double* z, double* out) const;

  int dim_;
  const std::vector<MassPoint>& points_;
  const SpringAdjacency& adj_;
};

}  // namespace stiffbench
