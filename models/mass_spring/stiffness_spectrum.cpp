#include "models/mass_spring/stiffness_spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/lanczos.hpp"
#include "models/detail/with_dim.hpp"

namespace stiffbench {

namespace {

// Lanczos: stop when both extreme Ritz values have residual <= 1e-10 · max|θ|, or after 300
// steps, from the start vector of seed 20240521 (the defaults of LanczosOptions).
const LanczosOptions kLanczos{1e-10, 300, 20240521};

// Networks with at least this many points split spring_terms and matvec between the threads
// (the default parallel_threshold of the right-hand side, NetworkOptions).
constexpr Index kParallelPoints = 2048;

}  // namespace

double StiffnessSpectrum::omega_max_bound(CVecRef x) const {
  double w2 = 0.0;
  const Index np = static_cast<Index>(points_.size());
  for (Index p = 0; p < np; ++p) {
    const MassPoint& pt = points_[static_cast<std::size_t>(p)];
    if (pt.pinned) continue;
    double sum = 0.0;
    for (Index e = adj_.start[static_cast<std::size_t>(p)];
         e < adj_.start[static_cast<std::size_t>(p) + 1]; ++e) {
      const SpringNeighbour& s = adj_.neighbours[static_cast<std::size_t>(e)];
      double l2 = 0.0;
      for (int c = 0; c < dim_; ++c) {
        const double r = x[dim_ * s.other + c] - x[dim_ * p + c];
        l2 += r * r;
      }
      sum += s.k * std::max(1.0, std::abs(1.0 - s.rest / std::sqrt(l2)));
    }
    w2 = std::max(w2, 2.0 * sum / pt.mass);
  }
  return std::sqrt(w2);
}

// Per adjacency entry (point p, neighbour q): the unit direction d from p to q, then
// along = k L/l and across = k (1 - L/l), so that J_s,e = along d dᵀ + across I. They depend on x
// only, which stays fixed over a Lanczos run: computed once, not in every product.
template <int D>
std::vector<double> StiffnessSpectrum::spring_terms(const double* x) const {
  std::vector<double> terms((D + 2) * adj_.neighbours.size());
  const Index np = static_cast<Index>(points_.size());
#pragma omp parallel for schedule(static) if (np >= kParallelPoints)
  for (Index p = 0; p < np; ++p) {
    const double* xp = x + D * p;
    for (Index e = adj_.start[static_cast<std::size_t>(p)];
         e < adj_.start[static_cast<std::size_t>(p) + 1]; ++e) {
      const SpringNeighbour& s = adj_.neighbours[static_cast<std::size_t>(e)];
      const double* xq = x + D * s.other;
      double* t = terms.data() + (D + 2) * e;
      double l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        t[c] = xq[c] - xp[c];
        l2 += t[c] * t[c];
      }
      const double l = std::sqrt(l2);
      for (int c = 0; c < D; ++c) t[c] /= l;
      const double across = s.k * (1.0 - s.rest / l);
      t[D] = s.k - across;  // along
      t[D + 1] = across;
    }
  }
  return terms;
}

// (H z)_p = Σ_e J_s,e (z_p - z_q). Each point's row is summed by one thread in adjacency order,
// so the result does not depend on the thread count; large networks split the points between
// the threads (the same size threshold as the right-hand side's default).
template <int D>
void StiffnessSpectrum::matvec(const double* terms, const double* z, double* out) const {
  const Index np = static_cast<Index>(points_.size());
#pragma omp parallel for schedule(static) if (np >= kParallelPoints)
  for (Index p = 0; p < np; ++p) {
    double acc[D] = {};
    const double* zp = z + D * p;
    for (Index e = adj_.start[static_cast<std::size_t>(p)];
         e < adj_.start[static_cast<std::size_t>(p) + 1]; ++e) {
      const double* zq = z + D * adj_.neighbours[static_cast<std::size_t>(e)].other;
      const double* t = terms + (D + 2) * e;
      double dz[D], ddz = 0.0;
      for (int c = 0; c < D; ++c) {
        dz[c] = zp[c] - zq[c];
        ddz += t[c] * dz[c];
      }
      for (int c = 0; c < D; ++c) acc[c] += t[D] * t[c] * ddz + t[D + 1] * dz[c];
    }
    for (int c = 0; c < D; ++c) out[D * p + c] = acc[c];
  }
}

std::pair<double, double> StiffnessSpectrum::eigen_range(CVecRef x) const {
  std::vector<Index> free_dofs;
  const Index np = static_cast<Index>(points_.size());
  for (Index p = 0; p < np; ++p)
    if (!points_[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < dim_; ++c) free_dofs.push_back(dim_ * p + c);
  const Index nf = static_cast<Index>(free_dofs.size());
  if (nf == 0 || adj_.neighbours.empty()) return {0.0, 0.0};

  // S u = M^{-1/2} H M^{-1/2} u on free dofs (pinned entries of z are zero).
  Vec z = Vec::Zero(dim_ * np), hz(dim_ * np), inv_sqrt_m(nf);
  for (Index i = 0; i < nf; ++i)
    inv_sqrt_m[i] = 1.0 / std::sqrt(points_[static_cast<std::size_t>(free_dofs[i] / dim_)].mass);
  std::pair<double, double> range;
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    constexpr int D = decltype(dim)::value;
    const std::vector<double> terms = spring_terms<D>(x.data());
    const auto apply = [&](const Vec& u, Vec& out) {
      for (Index i = 0; i < nf; ++i) z[free_dofs[i]] = inv_sqrt_m[i] * u[i];
      matvec<D>(terms.data(), z.data(), hz.data());
      for (Index i = 0; i < nf; ++i) out[i] = inv_sqrt_m[i] * hz[free_dofs[i]];
    };
    range = lanczos_extreme_eigenvalues(nf, apply, kLanczos);
  });
  return range;
}

double StiffnessSpectrum::omega_max_estimate(CVecRef x) const {
  const auto [lo, hi] = eigen_range(x);
  return std::sqrt(std::max(std::abs(lo), std::abs(hi)));
}

}  // namespace stiffbench
