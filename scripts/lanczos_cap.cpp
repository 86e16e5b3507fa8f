// The stiffness estimate's Lanczos cap (300 steps, models/mass_spring/stiffness_spectrum.cpp)
// against longer runs on a cloth at its initial state (docs/performance.md). The operator is the
// model's own ∂a/∂x (force_jacobians' K, already divided by the mass) negated and restricted to the
// free coordinates, the matrix whose largest eigenvalue the model's stiffness() estimates.
// Build after the Release build (scripts/build.sh) and run, e.g. for a 128² cloth (about 4 min):
//   c++ -O2 -std=c++20 -fopenmp -I. -Iinclude -isystem /usr/include/eigen3
//     scripts/lanczos_cap.cpp build/models/libstiffbench_models.a
//     build/core/libstiffbench_core.a -o /tmp/lanczos_cap
//   /tmp/lanczos_cap 128
// (the first three lines are one command).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/lanczos.hpp"
#include "models/mass_spring/builders.hpp"

using namespace stiffbench;

int main(int argc, char** argv) {
  ClothOptions o;
  o.n = argc > 1 ? std::atol(argv[1]) : 64;
  o.m = o.n;
  const auto net = make_cloth(o);
  const Index nd = net->dofs();
  const Vec y = net->initial_state();
  SparseMat k, d;
  net->force_jacobians(0.0, y.head(nd), y.tail(nd), k, d);
  std::vector<Index> free_dofs;
  for (Index p = 0; p < net->num_points(); ++p)
    if (!net->points()[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < 3; ++c) free_dofs.push_back(3 * p + c);
  const auto nf = static_cast<Index>(free_dofs.size());
  Vec z = Vec::Zero(nd), kz(nd);
  const auto apply = [&](const Vec& u, Vec& out) {
    for (Index i = 0; i < nf; ++i) z[free_dofs[static_cast<std::size_t>(i)]] = u[i];
    kz = -(k * z);
    for (Index i = 0; i < nf; ++i) out[i] = kz[free_dofs[static_cast<std::size_t>(i)]];
  };
  for (const Index steps : {300, 1000, 3000}) {
    LanczosOptions lo;
    lo.max_iter = steps;
    lo.max_basis_bytes = 1e12;  // always the stored basis (full reorthogonalisation)
    const auto [lo_eig, hi_eig] = lanczos_extreme_eigenvalues(nf, apply, lo);
    std::printf("cloth %ld²: at most %ld steps: omega_max %.10g\n", static_cast<long>(o.n),
                static_cast<long>(steps), std::sqrt(std::max(std::abs(lo_eig), std::abs(hi_eig))));
  }
  std::printf("model stiffness(): %.10g\n", *net->stiffness(0.0, y));
}
