#include "bench/plain_cloth.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bench/bench_common.hpp"

namespace stiffbench::bench {

namespace {

void check_supported(const MassSpringNetwork& net) {
  if (net.dim() != 3) throw std::invalid_argument("plain cloth: 3D networks only");
  if (net.options().point_damping != 0.0) throw std::invalid_argument("plain cloth: no damping");
  for (const auto& s : net.springs())
    if (s.damping != 0.0) throw std::invalid_argument("plain cloth: no dashpots");
  if (net.has_constraints()) throw std::invalid_argument("plain cloth: no constraints");
}

}  // namespace

PlainClothRhs::PlainClothRhs(const MassSpringNetwork& net) {
  check_supported(net);
  const Index np = net.num_points();
  const auto& pts = net.points();
  inv_mass_.resize(static_cast<std::size_t>(np));
  for (Index p = 0; p < np; ++p) {
    const auto& pt = pts[static_cast<std::size_t>(p)];
    inv_mass_[static_cast<std::size_t>(p)] = pt.pinned ? 0.0 : 1.0 / pt.mass;
  }
  for (int d = 0; d < 3; ++d) g_[d] = net.options().gravity[static_cast<std::size_t>(d)];
  std::vector<std::int32_t> count(static_cast<std::size_t>(np) + 1, 0);
  for (const auto& s : net.springs()) {
    ++count[static_cast<std::size_t>(s.i) + 1];
    ++count[static_cast<std::size_t>(s.j) + 1];
  }
  for (std::size_t p = 0; p < static_cast<std::size_t>(np); ++p) count[p + 1] += count[p];
  start_ = count;
  adj_.resize(static_cast<std::size_t>(count.back()));
  for (const auto& s : net.springs()) {
    adj_[static_cast<std::size_t>(count[static_cast<std::size_t>(s.i)]++)] = {
        s.k, s.rest, static_cast<std::int32_t>(s.j)};
    adj_[static_cast<std::size_t>(count[static_cast<std::size_t>(s.j)]++)] = {
        s.k, s.rest, static_cast<std::int32_t>(s.i)};
  }
  springs_ = static_cast<Index>(net.springs().size());
}

void PlainClothRhs::acceleration(const double* x, double* a) const {
  const std::int64_t np = static_cast<std::int64_t>(inv_mass_.size());
  const double gx = g_[0], gy = g_[1], gz = g_[2];
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < np; ++i) {
    const double w = inv_mass_[static_cast<std::size_t>(i)];
    double* ai = a + 3 * i;
    if (w == 0.0) {
      ai[0] = ai[1] = ai[2] = 0.0;
      continue;
    }
    const double* xi = x + 3 * i;
    double fx = 0.0, fy = 0.0, fz = 0.0;
    for (std::int32_t e = start_[static_cast<std::size_t>(i)];
         e < start_[static_cast<std::size_t>(i) + 1]; ++e) {
      const Entry& nb = adj_[static_cast<std::size_t>(e)];
      const double* xj = x + 3 * static_cast<std::int64_t>(nb.other);
      const double dx = xj[0] - xi[0], dy = xj[1] - xi[1], dz = xj[2] - xi[2];
      const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double s = nb.k * (l - nb.rest) / l;
      fx += s * dx;
      fy += s * dy;
      fz += s * dz;
    }
    ai[0] = w * fx + gx;
    ai[1] = w * fy + gy;
    ai[2] = w * fz + gz;
  }
}

PlainBaraffWitkin::PlainBaraffWitkin(const MassSpringNetwork& net, double tol) {
  check_supported(net);
  np_ = net.num_points();
  const auto& pts = net.points();
  for (int d = 0; d < 3; ++d) g_[d] = net.options().gravity[static_cast<std::size_t>(d)];
  free_of_.assign(static_cast<std::size_t>(np_), -1);
  for (Index p = 0; p < np_; ++p) {
    if (pts[static_cast<std::size_t>(p)].pinned) continue;
    free_of_[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(free_.size());
    free_.push_back(static_cast<std::int32_t>(p));
    mass_.push_back(pts[static_cast<std::size_t>(p)].mass);
  }
  const std::size_t nf = free_.size();
  // Adjacency of free points (springs seen from each free end).
  std::vector<std::int32_t> count(nf + 1, 0);
  for (const auto& s : net.springs()) {
    if (free_of_[static_cast<std::size_t>(s.i)] >= 0)
      ++count[static_cast<std::size_t>(free_of_[static_cast<std::size_t>(s.i)]) + 1];
    if (free_of_[static_cast<std::size_t>(s.j)] >= 0)
      ++count[static_cast<std::size_t>(free_of_[static_cast<std::size_t>(s.j)]) + 1];
  }
  for (std::size_t f = 0; f < nf; ++f) count[f + 1] += count[f];
  nb_start_ = count;
  nb_.resize(static_cast<std::size_t>(count.back()));
  for (const auto& s : net.springs()) {
    for (int end = 0; end < 2; ++end) {
      const Index me = end == 0 ? s.i : s.j, other = end == 0 ? s.j : s.i;
      const std::int32_t f = free_of_[static_cast<std::size_t>(me)];
      if (f < 0) continue;
      Nb& nb = nb_[static_cast<std::size_t>(count[static_cast<std::size_t>(f)]++)];
      nb.other = static_cast<std::int32_t>(other);
      nb.k = s.k;
      nb.rest = s.rest;
    }
  }
  // Row pattern: sorted block columns {f} ∪ {free neighbours}; each spring's block slot.
  diag_slot_.resize(nf);
  row_blocks_.resize(nf);
  std::vector<Eigen::Triplet<double, int>> trip;
  std::vector<std::int32_t> cols;
  for (std::size_t f = 0; f < nf; ++f) {
    cols.assign(1, static_cast<std::int32_t>(f));
    for (std::int32_t e = nb_start_[f]; e < nb_start_[f + 1]; ++e) {
      const std::int32_t o =
          free_of_[static_cast<std::size_t>(nb_[static_cast<std::size_t>(e)].other)];
      if (o >= 0) cols.push_back(o);
    }
    std::sort(cols.begin(), cols.end());
    if (std::adjacent_find(cols.begin(), cols.end()) != cols.end())
      throw std::invalid_argument("plain Baraff-Witkin: two springs join the same pair of points");
    row_blocks_[f] = static_cast<std::int32_t>(cols.size());
    diag_slot_[f] = static_cast<std::int32_t>(
        std::lower_bound(cols.begin(), cols.end(), static_cast<std::int32_t>(f)) - cols.begin());
    for (std::int32_t e = nb_start_[f]; e < nb_start_[f + 1]; ++e) {
      Nb& nb = nb_[static_cast<std::size_t>(e)];
      const std::int32_t o = free_of_[static_cast<std::size_t>(nb.other)];
      nb.block = o < 0 ? -1
                       : static_cast<std::int32_t>(std::lower_bound(cols.begin(), cols.end(), o) -
                                                   cols.begin());
    }
    for (int r = 0; r < 3; ++r)
      for (const std::int32_t c : cols)
        for (int cc = 0; cc < 3; ++cc)
          trip.emplace_back(static_cast<int>(3 * f) + r, 3 * c + cc, 0.0);
  }
  const int n = static_cast<int>(3 * nf);
  a_.resize(n, n);
  a_.setFromTriplets(trip.begin(), trip.end());
  a_.makeCompressed();
  // The in-place writes below assume row 3f + r holds the blocks in sorted order, 3 entries each.
  for (std::size_t f = 0; f < nf; ++f)
    for (int r = 0; r < 3; ++r)
      if (a_.outerIndexPtr()[3 * f + static_cast<std::size_t>(r) + 1] -
              a_.outerIndexPtr()[3 * f + static_cast<std::size_t>(r)] !=
          3 * row_blocks_[f])
        throw std::logic_error("plain Baraff-Witkin: unexpected matrix pattern");
  b_ = Eigen::VectorXd::Zero(n);
  dv_ = Eigen::VectorXd::Zero(n);
  guess_ = dv_;
  cg_.setTolerance(tol);
  cg_.setMaxIterations(1000);
}

void PlainBaraffWitkin::step(double* y, double h) {
  double* x = y;
  double* v = y + 3 * np_;
  const std::int64_t nf = static_cast<std::int64_t>(free_.size());
  const double h2 = h * h;
  double* values = a_.valuePtr();
  const int* outer = a_.outerIndexPtr();
  const double t0 = now_seconds();
#pragma omp parallel for schedule(static)
  for (std::int64_t f = 0; f < nf; ++f) {
    const std::size_t fu = static_cast<std::size_t>(f);
    const std::int64_t i = free_[fu];
    const double* xi = x + 3 * i;
    const double* vi = v + 3 * i;
    const double m = mass_[fu];
    double diag[9] = {m, 0, 0, 0, m, 0, 0, 0, m};
    double force[3] = {m * g_[0], m * g_[1], m * g_[2]};
    double kv[3] = {0, 0, 0};
    double* row[3] = {values + outer[3 * f], values + outer[3 * f + 1], values + outer[3 * f + 2]};
    for (std::int32_t e = nb_start_[fu]; e < nb_start_[fu + 1]; ++e) {
      const Nb& nb = nb_[static_cast<std::size_t>(e)];
      const double* xj = x + 3 * static_cast<std::int64_t>(nb.other);
      const double* vj = v + 3 * static_cast<std::int64_t>(nb.other);
      double d[3] = {xj[0] - xi[0], xj[1] - xi[1], xj[2] - xi[2]};
      const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      d[0] /= l;
      d[1] /= l;
      d[2] /= l;
      const double s = nb.k * (l - nb.rest);
      // J = beta d dᵀ + alpha I, alpha = k (1 − L/l), beta = k L/l.
      const double alpha = nb.k * (1.0 - nb.rest / l), beta = nb.k * nb.rest / l;
      const double du[3] = {vj[0] - vi[0], vj[1] - vi[1], vj[2] - vi[2]};
      const double ddu = d[0] * du[0] + d[1] * du[1] + d[2] * du[2];
      for (int r = 0; r < 3; ++r) {
        force[r] += s * d[r];
        kv[r] += beta * d[r] * ddu + alpha * du[r];
        for (int c = 0; c < 3; ++c) {
          const double j = beta * d[r] * d[c] + (r == c ? alpha : 0.0);
          diag[3 * r + c] += h2 * j;
          if (nb.block >= 0) row[r][3 * nb.block + c] = -h2 * j;
        }
      }
    }
    const std::int32_t ds = diag_slot_[fu];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) row[r][3 * ds + c] = diag[3 * r + c];
      b_[3 * f + r] = h * (force[r] + h * kv[r]);
    }
  }
  const double t1 = now_seconds();
  cg_.compute(a_);
  guess_ = dv_;
  dv_ = cg_.solveWithGuess(b_, guess_);
  iterations_ = static_cast<long>(cg_.iterations());
  const double t2 = now_seconds();
#pragma omp parallel for schedule(static)
  for (std::int64_t f = 0; f < nf; ++f) {
    const std::int64_t i = free_[static_cast<std::size_t>(f)];
    for (int r = 0; r < 3; ++r) {
      v[3 * i + r] += dv_[3 * f + r];
      x[3 * i + r] += h * v[3 * i + r];
    }
  }
  assembly_s_ = t1 - t0;
  solve_s_ = t2 - t1;
}

}  // namespace stiffbench::bench
