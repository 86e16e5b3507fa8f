#include "bench/plain_sph.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stiffbench::bench {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

std::int64_t PlainSph3d::Grid::coord(double x, int d) const {
  const auto c = static_cast<std::int64_t>(std::floor(x * inv_cell)) - lo[d];
  return std::clamp<std::int64_t>(c, 0, dims[d] - 1);
}

void PlainSph3d::Grid::build(const double* x, Index n, double cell) {
  inv_cell = 1.0 / cell;
  double mn[3] = {1e300, 1e300, 1e300}, mx[3] = {-1e300, -1e300, -1e300};
  for (Index i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      mn[d] = std::min(mn[d], x[3 * i + d]);
      mx[d] = std::max(mx[d], x[3 * i + d]);
    }
  for (int d = 0; d < 3; ++d) {
    lo[d] = static_cast<std::int64_t>(std::floor(mn[d] * inv_cell));
    dims[d] = static_cast<std::int64_t>(std::floor(mx[d] * inv_cell)) - lo[d] + 1;
  }
  const auto cells = static_cast<std::size_t>(dims[0] * dims[1] * dims[2]);
  start.assign(cells + 1, 0);
  std::vector<std::size_t> cell_of(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) {
    const std::int64_t c =
        coord(x[3 * i], 0) + dims[0] * (coord(x[3 * i + 1], 1) + dims[1] * coord(x[3 * i + 2], 2));
    cell_of[static_cast<std::size_t>(i)] = static_cast<std::size_t>(c);
    ++start[static_cast<std::size_t>(c) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  items.resize(static_cast<std::size_t>(n));
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (Index i = 0; i < n; ++i)
    items[fill[cell_of[static_cast<std::size_t>(i)]]++] = static_cast<std::int32_t>(i);
}

PlainSph3d::PlainSph3d(const SphFluid& fluid) {
  const SphOptions& o = fluid.options();
  if (fluid.dim() != 3 || o.eos != SphEos::linear || !o.clamp ||
      o.form != SphPressureForm::variational || o.boundary != SphBoundary::particles ||
      o.mirror_boundary_pressure || o.viscosity == SphViscosity::muller ||
      o.density_kernel != sph::KernelType::wendland_c2 ||
      o.gradient_kernel != sph::KernelType::wendland_c2)
    throw std::invalid_argument("PlainSph3d: only the dam-break scenes' options");
  n_ = fluid.fluid_particles();
  h_ = o.support;
  rho0_ = o.rho0;
  k_ = o.k >= 0 ? o.k : o.c0 * o.c0;  // as SphFluid sets it (its sound speed is √k)
  const double hs = 0.5 * h_;
  alpha_c_hs_ = o.viscosity == SphViscosity::artificial ? o.alpha * fluid.sound_speed() * hs : 0.0;
  eps2_ = 0.01 * hs * hs;
  sigma_ = 21.0 / (2.0 * kPi * h_ * h_ * h_);
  for (int d = 0; d < 3; ++d) g_[d] = o.gravity[static_cast<std::size_t>(d)];
  m_ = fluid.particle_masses();
  bvol_ = fluid.boundary_volumes();
  for (const auto& p : fluid.scene().boundary_x) bx_.insert(bx_.end(), p.begin(), p.end());
  if (!bvol_.empty()) bgrid_.build(bx_.data(), static_cast<Index>(bvol_.size()), h_);
}

// Neighbour lists of every particle within h (self included): fluid from this call's grid,
// boundary from the grid built once. Two passes (count, fill) over the 27 cells around each.
void PlainSph3d::build_lists(const double* x) const {
  grid_.build(x, n_, h_);
  const std::size_t n = static_cast<std::size_t>(n_);
  start_.assign(n + 1, 0);
  bstart_.assign(n + 1, 0);
  const double h2 = h_ * h_;
  auto visit = [&](const Grid& g, const double* pts, const double* xi, auto&& f) {
    std::int64_t c[3];
    for (int d = 0; d < 3; ++d) c[d] = static_cast<std::int64_t>(std::floor(xi[d] * g.inv_cell));
    for (std::int64_t dz = -1; dz <= 1; ++dz)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dx = -1; dx <= 1; ++dx) {
          const std::int64_t cx = c[0] + dx - g.lo[0], cy = c[1] + dy - g.lo[1],
                             cz = c[2] + dz - g.lo[2];
          if (cx < 0 || cy < 0 || cz < 0 || cx >= g.dims[0] || cy >= g.dims[1] || cz >= g.dims[2])
            continue;
          const auto cell = static_cast<std::size_t>(cx + g.dims[0] * (cy + g.dims[1] * cz));
          for (std::size_t s = g.start[cell]; s < g.start[cell + 1]; ++s) {
            const std::int32_t j = g.items[s];
            const double* xj = pts + 3 * j;
            const double r2 = (xi[0] - xj[0]) * (xi[0] - xj[0]) +
                              (xi[1] - xj[1]) * (xi[1] - xj[1]) + (xi[2] - xj[2]) * (xi[2] - xj[2]);
            if (r2 < h2) f(j);
          }
        }
  };
  const bool wb = !bvol_.empty();
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n_; ++i) {
    std::size_t c = 0, cb = 0;
    visit(grid_, x, x + 3 * i, [&](std::int32_t) { ++c; });
    if (wb) visit(bgrid_, bx_.data(), x + 3 * i, [&](std::int32_t) { ++cb; });
    start_[static_cast<std::size_t>(i) + 1] = c;
    bstart_[static_cast<std::size_t>(i) + 1] = cb;
  }
  for (std::size_t i = 0; i < n; ++i) {
    start_[i + 1] += start_[i];
    bstart_[i + 1] += bstart_[i];
  }
  nbr_.resize(start_[n]);
  bnbr_.resize(bstart_[n]);
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n_; ++i) {
    std::size_t c = start_[static_cast<std::size_t>(i)], cb = bstart_[static_cast<std::size_t>(i)];
    visit(grid_, x, x + 3 * i, [&](std::int32_t j) { nbr_[c++] = j; });
    if (wb) visit(bgrid_, bx_.data(), x + 3 * i, [&](std::int32_t b) { bnbr_[cb++] = b; });
  }
}

void PlainSph3d::acceleration(const double* x, const double* v, double* a) const {
  build_lists(x);
  const std::size_t n = static_cast<std::size_t>(n_);
  rho_.resize(n);
  pr2_.resize(n);
  const double inv_h = 1.0 / h_, grad = -20.0 * sigma_ * inv_h * inv_h;
  // Wendland C2 in 3D: W = σ (1 - q)⁴ (4q + 1), dW/dr / r = -20 σ/h² (1 - q)³, σ = 21/(2π h³).
  const auto w = [&](double r) {
    const double d = 1.0 - r * inv_h, d2 = d * d;
    return sigma_ * d2 * d2 * (4.0 * r * inv_h + 1.0);
  };
  const auto dist = [](const double* p, const double* q) {
    return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                     (p[2] - q[2]) * (p[2] - q[2]));
  };
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n_; ++i) {
    const std::size_t iu = static_cast<std::size_t>(i);
    const double* xi = x + 3 * i;
    double rho = 0.0, bsum = 0.0;
    for (std::size_t q = start_[iu]; q < start_[iu + 1]; ++q)
      rho += m_[static_cast<std::size_t>(nbr_[q])] * w(dist(xi, x + 3 * nbr_[q]));
    for (std::size_t q = bstart_[iu]; q < bstart_[iu + 1]; ++q)
      bsum += bvol_[static_cast<std::size_t>(bnbr_[q])] * w(dist(xi, bx_.data() + 3 * bnbr_[q]));
    rho += rho0_ * bsum;
    const double p = std::max(0.0, k_ * (rho - rho0_));
    rho_[iu] = rho;
    pr2_[iu] = p / (rho * rho);
  }
#pragma omp parallel for schedule(static)
  for (Index i = 0; i < n_; ++i) {
    const std::size_t iu = static_cast<std::size_t>(i);
    const double* xi = x + 3 * i;
    const double* vi = v + 3 * i;
    double acc[3] = {g_[0], g_[1], g_[2]};
    for (std::size_t q = start_[iu]; q < start_[iu + 1]; ++q) {
      const std::int32_t j = nbr_[q];
      if (j == i) continue;
      const double* xj = x + 3 * j;
      const double* vj = v + 3 * j;
      const double dx[3] = {xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]};
      const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
      const double r = std::sqrt(r2), d = 1.0 - r * inv_h;
      const double dwr = grad * d * d * d;
      const double mj = m_[static_cast<std::size_t>(j)];
      double coef = mj * (pr2_[iu] + pr2_[static_cast<std::size_t>(j)]);
      const double vr = (vi[0] - vj[0]) * dx[0] + (vi[1] - vj[1]) * dx[1] + (vi[2] - vj[2]) * dx[2];
      if (vr < 0.0)
        coef -= mj * alpha_c_hs_ * vr /
                (0.5 * (rho_[iu] + rho_[static_cast<std::size_t>(j)]) * (r2 + eps2_));
      for (int k = 0; k < 3; ++k) acc[k] -= coef * dwr * dx[k];
    }
    for (std::size_t q = bstart_[iu]; q < bstart_[iu + 1]; ++q) {
      const std::size_t b = static_cast<std::size_t>(bnbr_[q]);
      const double* xb = bx_.data() + 3 * b;
      const double dx[3] = {xi[0] - xb[0], xi[1] - xb[1], xi[2] - xb[2]};
      const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
      const double r = std::sqrt(r2), d = 1.0 - r * inv_h;
      const double dwr = grad * d * d * d;
      const double vb = bvol_[b];
      double coef = rho0_ * vb * pr2_[iu];
      const double vr = vi[0] * dx[0] + vi[1] * dx[1] + vi[2] * dx[2];
      if (vr < 0.0)
        coef -= rho0_ * vb * alpha_c_hs_ * vr / (0.5 * (rho_[iu] + rho0_) * (r2 + eps2_));
      for (int k = 0; k < 3; ++k) acc[k] -= coef * dwr * dx[k];
    }
    for (int k = 0; k < 3; ++k) a[3 * i + k] = acc[k];
  }
}

}  // namespace stiffbench::bench
