// Extreme eigenvalues of a symmetric operator by Lanczos (Golub & Van Loan, Matrix
// Computations, 4th ed., 10.1), for stiffness estimates of large systems whose matrix is never
// formed (the mass-spring network's ω_max, models/mass_spring/stiffness_spectrum.hpp).
//
// lanczos_extreme_eigenvalues(n, apply) runs Lanczos with full reorthogonalisation (classical
// Gram–Schmidt, twice per step) from a fixed pseudo-random start vector (uniform in [-1, 1],
// std::mt19937_64 seeded with `seed`, so every call gives the same numbers), until both extreme
// Ritz values have residual <= rel_tol · max|θ| (then |λ - θ| is below that), the Krylov space
// is invariant (exact: the space filled up), or after max_iter steps (Ritz values always lie
// inside the spectrum, so a capped run underestimates the range). The tridiagonal eigenproblem
// is solved every step up to step 50, then every fifth step. Returns {smallest, largest} Ritz
// value; apply(u, out) must write S u into out (both of size n) for a symmetric S.
//
// When the basis would take more than max_basis_bytes (8 n · max_iter bytes; by default 256 MiB,
// n above about 110,000 at 300 steps), the basis is not stored: the plain three-term recurrence
// runs instead, with the same start vector, the same stopping rule and O(n) memory. In floating
// point it loses orthogonality as Ritz values converge; that adds copies of converged Ritz values
// but leaves the extreme ones where they are (Paige 1976; Golub & Van Loan, 10.3). Full
// reorthogonalisation costs O(n j²) over j steps and was the whole cost on large networks: 300
// steps on the 786,432 free coordinates of a 512 × 512 cloth took 130 s and 3 GB (with the
// other costs of that estimate, cut to 15 s and 1.5 GB; models/mass_spring/stiffness_spectrum.hpp).
#pragma once

#include <cstdint>
#include <functional>
#include <utility>

#include "core/types.hpp"

namespace stiffbench {

struct LanczosOptions {
  double rel_tol = 1e-10;
  Index max_iter = 300;
  std::uint64_t seed = 20240521;
  double max_basis_bytes = 256.0 * 1024 * 1024;
};

using SymmetricOperator = std::function<void(const Vec& u, Vec& out)>;

std::pair<double, double> lanczos_extreme_eigenvalues(Index n, const SymmetricOperator& apply,
                                                      const LanczosOptions& options = {});

}  // namespace stiffbench
