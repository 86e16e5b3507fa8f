#include "models/mass_spring/network.hpp"

#include "models/detail/with_dim.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <type_traits>

namespace stiffbench {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Position-projection stop: |C| <= 1e-13 L, or the round-off floor of computing l from
// coordinates of size |x|.
constexpr double kConstraintRelTol = 1e-13;
constexpr int kMaxProjectionSweeps = 1000;  // Gauss–Seidel fallback
constexpr int kMaxNewtonIterations = 20;

// Lanczos: stop when both extreme Ritz values have residual <= kLanczosTol · max|θ|.
constexpr double kLanczosTol = 1e-10;
constexpr Index kLanczosMaxIter = 300;

// Runs body(p) for p in [0, n), over OpenMP threads when `parallel`. Each p is independent, so
// the result does not depend on the thread count.
template <class Body>
void for_points(Index n, bool parallel, const Body& body) {
  if (parallel) {
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) body(p);
  } else {
    for (Index p = 0; p < n; ++p) body(p);
  }
}

// Gradient sign of constraint c = (i, j) with respect to point p: ∂C/∂x_p = sign · n,
// n = (x_j - x_i)/l (-1 at i, +1 at j).
double end_sign(const DistanceConstraint& c, Index p) { return p == c.i ? -1.0 : 1.0; }

std::string item(const char* what, std::size_t index) {
  return std::string(what) + " " + std::to_string(index);
}

}  // namespace

MassSpringNetwork::MassSpringNetwork(std::string name, int dim, std::vector<MassPoint> points,
                                     std::vector<Spring> springs, NetworkOptions options,
                                     std::vector<DistanceConstraint> constraints)
    : name_(std::move(name)),
      dim_(dim),
      points_(std::move(points)),
      springs_(std::move(springs)),
      constraints_(std::move(constraints)),
      opt_(options) {
  const std::string who = name_ + ": ";
  // Per-item checks build their message only when they fail (a 512² cloth has 1.5 M springs).
  const auto check = [](bool ok, const auto& message) {
    if (!ok) throw BadInput(message());
  };
  require_input(dim_ >= 1 && dim_ <= 3, who + "dimension must be 1, 2 or 3");
  require_input(!points_.empty(), who + "the network has no points");
  const Index np = num_points();
  for (int c = dim_; c < 3; ++c)
    require_input(opt_.gravity[static_cast<std::size_t>(c)] == 0.0,
                  who + "gravity has a component beyond the network's dimension");
  for (int c = 0; c < dim_; ++c)
    require_input(std::isfinite(opt_.gravity[static_cast<std::size_t>(c)]),
                  who + "gravity must be finite");
  require_input(std::isfinite(opt_.point_damping) && opt_.point_damping >= 0,
                who + "point damping must be >= 0");
  for (std::size_t p = 0; p < points_.size(); ++p) {
    MassPoint& pt = points_[p];
    check(std::isfinite(pt.mass) && pt.mass > 0,
          [&] { return who + item("point", p) + ": mass <= 0"; });
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      check(std::isfinite(pt.x[cc]) && std::isfinite(pt.v[cc]),
            [&] { return who + item("point", p) + ": non-finite state"; });
      if (c >= dim_)
        check(pt.x[cc] == 0.0 && pt.v[cc] == 0.0,
              [&] { return who + item("point", p) + ": component beyond the dimension"; });
    }
    if (pt.pinned) pt.v = {0.0, 0.0, 0.0};
  }
  for (std::size_t e = 0; e < springs_.size(); ++e) {
    const Spring& s = springs_[e];
    check(s.i >= 0 && s.i < np && s.j >= 0 && s.j < np && s.i != s.j,
          [&] { return who + item("spring", e) + ": bad end points"; });
    check(std::isfinite(s.k) && s.k >= 0,
          [&] { return who + item("spring", e) + ": stiffness < 0"; });
    check(std::isfinite(s.rest) && s.rest >= 0,
          [&] { return who + item("spring", e) + ": rest length < 0"; });
    check(std::isfinite(s.damping) && s.damping >= 0,
          [&] { return who + item("spring", e) + ": dashpot coefficient < 0"; });
  }
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    const DistanceConstraint& dc = constraints_[c];
    check(dc.i >= 0 && dc.i < np && dc.j >= 0 && dc.j < np && dc.i != dc.j,
          [&] { return who + item("constraint", c) + ": bad end points"; });
    check(std::isfinite(dc.length) && dc.length > 0,
          [&] { return who + item("constraint", c) + ": length <= 0"; });
  }

  // Constraint couplings: constraints c != d sharing a point p couple in G M⁻¹ Gᵀ.
  active_.resize(constraints_.size());
  std::vector<std::vector<Index>> touching(points_.size());
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    const DistanceConstraint& dc = constraints_[c];
    active_[c] = !(points_[static_cast<std::size_t>(dc.i)].pinned &&
                   points_[static_cast<std::size_t>(dc.j)].pinned);
    if (!active_[c]) continue;
    active_list_.push_back(static_cast<Index>(c));
    touching[static_cast<std::size_t>(dc.i)].push_back(static_cast<Index>(c));
    touching[static_cast<std::size_t>(dc.j)].push_back(static_cast<Index>(c));
  }
  for (std::size_t p = 0; p < touching.size(); ++p) {
    if (points_[p].pinned) continue;  // w_p = 0: no coupling
    for (Index c : touching[p])
      for (Index e : touching[p]) {
        if (c == e) continue;
        const double sign =
            end_sign(constraints_[static_cast<std::size_t>(c)], static_cast<Index>(p)) *
            end_sign(constraints_[static_cast<std::size_t>(e)], static_cast<Index>(p));
        constraint_couplings_.push_back({c, e, static_cast<Index>(p), sign});
      }
  }

  velocity_dependent_ = opt_.point_damping != 0.0;
  for (const Spring& s : springs_) has_dashpots_ = has_dashpots_ || s.damping != 0.0;
  velocity_dependent_ = velocity_dependent_ || has_dashpots_;

  const Index n = dofs();
  y0_.resize(2 * n);
  dof_mass_.resize(n);
  inv_mass_.resize(points_.size());
  for (Index p = 0; p < np; ++p) {
    const MassPoint& pt = points_[static_cast<std::size_t>(p)];
    inv_mass_[static_cast<std::size_t>(p)] = pt.pinned ? 0.0 : 1.0 / pt.mass;
    for (int c = 0; c < dim_; ++c) {
      y0_[dim_ * p + c] = pt.x[static_cast<std::size_t>(c)];
      y0_[n + dim_ * p + c] = pt.v[static_cast<std::size_t>(c)];
      dof_mass_[dim_ * p + c] = pt.mass;
    }
  }

  // Springs for the right-hand side, grouped by partition of the points (see the header).
  {
    // The partition count depends on the size only (not on the threads or on the parallel
    // threshold), so the serial and the parallel path sum in the same order.
    const Index parts = np >= 64 * kRhsPartitions ? kRhsPartitions : 1;
    const auto part_of = [&](Index p) { return static_cast<Index>((p * parts) / np); };
    // part_of(p) inverts p0 = np·q/parts: the first q with np·(q+1)/parts > p.
    const auto owner = [&](Index p) {
      Index q = part_of(p);
      while (q + 1 < parts && np * (q + 1) / parts <= p) ++q;
      while (q > 0 && np * q / parts > p) --q;
      return q;
    };
    std::vector<std::int32_t> part(static_cast<std::size_t>(np));
    for (Index p = 0; p < np; ++p)
      part[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(owner(p));
    std::vector<Index> count(static_cast<std::size_t>(parts) + 1, 0);
    for (const Spring& sp : springs_) {
      const Index qi = part[static_cast<std::size_t>(sp.i)],
                  qj = part[static_cast<std::size_t>(sp.j)];
      ++count[static_cast<std::size_t>(qi == qj ? qi : parts)];
    }
    part_start_.assign(static_cast<std::size_t>(parts) + 1, 0);
    for (Index q = 0; q < parts; ++q)
      part_start_[static_cast<std::size_t>(q) + 1] =
          part_start_[static_cast<std::size_t>(q)] + count[static_cast<std::size_t>(q)];
    std::vector<Index> next(part_start_.begin(), part_start_.end() - 1);
    next.push_back(part_start_.back());  // cross springs after the partitions' own
    packed_.resize(springs_.size());
    packed_damping_.assign(has_dashpots_ ? springs_.size() : 0, 0.0);
    for (const Spring& sp : springs_) {
      const Index qi = part[static_cast<std::size_t>(sp.i)],
                  qj = part[static_cast<std::size_t>(sp.j)];
      const auto slot =
          static_cast<std::size_t>(next[static_cast<std::size_t>(qi == qj ? qi : parts)]++);
      packed_[slot] = {static_cast<std::int32_t>(sp.i), static_cast<std::int32_t>(sp.j), sp.k,
                       sp.rest};
      if (has_dashpots_) packed_damping_[slot] = sp.damping;
    }
  }

  // The adjacency lists and the Jacobian pattern are built on first use (build_structure): an
  // explicit run never needs them, and for a 512² cloth they are most of the construction cost.
}

// Adjacency lists (Jacobians, stiffness estimates) and the fixed pattern of K and D with the
// value positions of every block, built once, on first use, by whichever thread gets there first.
void MassSpringNetwork::ensure_structure() const {
  std::call_once(structure_once_, [this] { build_structure(); });
}

void MassSpringNetwork::build_structure() const {
  const Index np = num_points();
  const Index n = dofs();
  // CSR adjacency, each point's springs in the order of the spring list.
  start_.assign(static_cast<std::size_t>(np) + 1, 0);
  for (const Spring& s : springs_) {
    ++start_[static_cast<std::size_t>(s.i) + 1];
    ++start_[static_cast<std::size_t>(s.j) + 1];
  }
  for (std::size_t p = 0; p < static_cast<std::size_t>(np); ++p) start_[p + 1] += start_[p];
  neighbours_.resize(static_cast<std::size_t>(start_.back()));
  std::vector<Index> fill(start_.begin(), start_.end() - 1);
  for (const Spring& s : springs_) {
    neighbours_[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.i)]++)] = {
        s.j, s.k, s.rest, s.damping};
    neighbours_[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.j)]++)] = {
        s.i, s.k, s.rest, s.damping};
  }

  // The fixed pattern of K and D: every point's diagonal block and one block per ordered pair
  // of spring ends (pinned rows included, as explicit zeros).
  // Built column by column (the pattern is structurally symmetric: column block q holds the
  // row blocks of q and of its neighbours), no triplet list.
  const Index d = dim_;
  {
    std::vector<int> outer(static_cast<std::size_t>(n) + 1, 0), inner;
    inner.reserve(static_cast<std::size_t>(d * d * (np + static_cast<Index>(neighbours_.size()))));
    std::vector<Index> rows;
    for (Index q = 0; q < np; ++q) {
      rows.clear();
      rows.push_back(q);
      for (Index e = start_[static_cast<std::size_t>(q)];
           e < start_[static_cast<std::size_t>(q) + 1]; ++e)
        rows.push_back(neighbours_[static_cast<std::size_t>(e)].other);
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      for (Index b = 0; b < d; ++b) {
        for (Index p : rows)
          for (Index a = 0; a < d; ++a) inner.push_back(static_cast<int>(d * p + a));
        outer[static_cast<std::size_t>(d * q + b) + 1] = static_cast<int>(inner.size());
      }
    }
    const std::vector<double> zeros(inner.size(), 0.0);
    pattern_ = Eigen::Map<const SparseMat>(n, n, static_cast<Index>(inner.size()), outer.data(),
                                           inner.data(), zeros.data());
    pattern_.makeCompressed();
  }
  diag_pattern_.resize(n, n);
  diag_pattern_.setIdentity();
  diag_pattern_.makeCompressed();
  std::fill(diag_pattern_.valuePtr(), diag_pattern_.valuePtr() + n, 0.0);
  auto position = [&](Index row, Index col) {
    using StorageIndex = SparseMat::StorageIndex;
    const StorageIndex* inner = pattern_.innerIndexPtr();
    const StorageIndex* begin = inner + pattern_.outerIndexPtr()[col];
    const StorageIndex* end = inner + pattern_.outerIndexPtr()[col + 1];
    const StorageIndex* it = std::lower_bound(begin, end, static_cast<StorageIndex>(row));
    if (it == end || *it != row) throw std::logic_error("mass-spring pattern lookup failed");
    return static_cast<Index>(it - inner);
  };
  // Every column of block q has the same row list, each row block contiguous: entry (a, b) of
  // block (p, q) sits at position(d p, d q) + a + b · (column length). One search per block.
  const auto block = [&](Index p, Index q, std::vector<Index>& out, std::size_t at) {
    const Index base = position(d * p, d * q);
    const Index len = pattern_.outerIndexPtr()[d * q + 1] - pattern_.outerIndexPtr()[d * q];
    for (Index a = 0; a < d; ++a)
      for (Index b = 0; b < d; ++b)
        out[at + static_cast<std::size_t>(a * d + b)] = base + a + b * len;
  };
  diag_pos_.resize(static_cast<std::size_t>(np * d * d));
  adj_pos_.resize(neighbours_.size() * static_cast<std::size_t>(d * d));
  adj_pos_t_.resize(adj_pos_.size());
  for (Index p = 0; p < np; ++p) {
    block(p, p, diag_pos_, static_cast<std::size_t>(p * d * d));
    for (Index e = start_[static_cast<std::size_t>(p)]; e < start_[static_cast<std::size_t>(p) + 1];
         ++e) {
      const Index q = neighbours_[static_cast<std::size_t>(e)].other;
      block(p, q, adj_pos_, static_cast<std::size_t>(e * d * d));
      // The transposed block (rows of q, columns of p), element [a][b] at (q a, p b).
      block(q, p, adj_pos_t_, static_cast<std::size_t>(e * d * d));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Forces.

template <int D>
void MassSpringNetwork::acceleration_impl(const double* x, const double* v, double* a) const {
  const double gamma = opt_.point_damping;
  const MassPoint* pts = points_.data();
  const PackedSpring* sp = packed_.data();
  const double* damp = packed_damping_.data();
  const bool dashpots = has_dashpots_;
  const Index np = num_points();
  const Index parts = static_cast<Index>(part_start_.size()) - 1;
  // a first holds the force sums. Each spring once: coef = k (l - L)/l (+ c (u·r)/l²), f_i +=
  // coef r, f_j -= coef r (exactly opposite).
  const auto spring = [&](Index e) {
    const PackedSpring& s = sp[e];
    const double* xi = x + D * static_cast<Index>(s.i);
    const double* xj = x + D * static_cast<Index>(s.j);
    double r[D], l2 = 0.0;
    for (int c = 0; c < D; ++c) {
      r[c] = xj[c] - xi[c];
      l2 += r[c] * r[c];
    }
    const double l = std::sqrt(l2);
    double coef = s.k * (l - s.rest) / l;
    if (dashpots && damp[e] != 0.0) {
      const double* vi = v + D * static_cast<Index>(s.i);
      const double* vj = v + D * static_cast<Index>(s.j);
      double ur = 0.0;
      for (int c = 0; c < D; ++c) ur += (vj[c] - vi[c]) * r[c];
      coef += damp[e] * ur / l2;
    }
    double* fi = a + D * static_cast<Index>(s.i);
    double* fj = a + D * static_cast<Index>(s.j);
    for (int c = 0; c < D; ++c) {
      fi[c] += coef * r[c];
      fj[c] -= coef * r[c];
    }
  };
  // 1. Each partition of points (contiguous index ranges, a count fixed by the network's size,
  //    not by the threads) clears its points and adds its interior springs.
  const auto partition = [&](Index q) {
    const Index p0 = np * q / parts, p1 = np * (q + 1) / parts;
    std::fill(a + D * p0, a + D * p1, 0.0);
    for (Index e = part_start_[static_cast<std::size_t>(q)];
         e < part_start_[static_cast<std::size_t>(q) + 1]; ++e)
      spring(e);
  };
  if (parts > 1 && parallel()) {
#pragma omp parallel for schedule(static)
    for (Index q = 0; q < parts; ++q) partition(q);
  } else {
    for (Index q = 0; q < parts; ++q) partition(q);
  }
  // 2. Springs between partitions, in a fixed order.
  for (Index e = part_start_.back(); e < static_cast<Index>(packed_.size()); ++e) spring(e);
  // 3. a = g + (f - γ v)/m; pinned points do not move.
  for_points(np, parallel(), [&](Index p) {
    double* ap = a + D * p;
    const MassPoint& pt = pts[p];
    if (pt.pinned) {
      for (int c = 0; c < D; ++c) ap[c] = 0.0;
      return;
    }
    const double* vp = v + D * p;
    for (int c = 0; c < D; ++c)
      ap[c] = opt_.gravity[static_cast<std::size_t>(c)] + (ap[c] - gamma * vp[c]) / pt.mass;
  });
}

void MassSpringNetwork::eval_acceleration(double, CVecRef x, CVecRef v, VecRef a) const {
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    acceleration_impl<decltype(dim)::value>(x.data(), v.data(), a.data());
  });
}

// ---------------------------------------------------------------------------------------------
// Jacobian blocks.
//
// Derivation of the dashpot's position derivative: f_i = c s d with s = u·d, u = v_j - v_i,
// d = (x_j - x_i)/l. Then ∂f_i/∂d = c (d uᵀ + s I) and ∂d/∂x_j = (I - d dᵀ)/l, so
//   ∂f_i/∂x_j = (c/l)(d uᵀ + s I)(I - d dᵀ) = (c/l)[d (u - s d)ᵀ + s (I - d dᵀ)] = J_c,
// and ∂f_i/∂x_i = -J_c because d depends on x_j - x_i only. ∂f_i/∂v_j = c d dᵀ = -∂f_i/∂v_i.

template <int D>
void MassSpringNetwork::blocks_impl(const double* x, const double* v, double* k_values,
                                    double* d_values) const {
  const double gamma = opt_.point_damping;
  const bool dd_only = opt_.compressed_dd_only;
  const Index* start = start_.data();
  const Neighbour* nb = neighbours_.data();
  const MassPoint* pts = points_.data();
  const Index* dpos = diag_pos_.data();
  const Index* apos = adj_pos_.data();
  // Without dashpots each spring's block J_s is symmetric and the same from both ends, so point
  // p can fill its own column block instead of its row block: K_qp = J_s / m_q (0 for a pinned
  // q), a contiguous range of the column-major storage. With dashpots (J_c is not symmetric)
  // point p fills its rows.
  const bool by_column = !has_dashpots_ && !d_values;
  const Index* tpos = adj_pos_t_.data();
  const double* inv_mass = inv_mass_.data();
  if (by_column && k_values) {
    for_points(num_points(), parallel(), [&](Index p) {
      const double* xp = x + D * p;
      for (Index e = start[p]; e < start[p + 1]; ++e)
        for (int q = 0; q < D * D; ++q) k_values[tpos[e * D * D + q]] = 0.0;
      double kd[D][D] = {};
      for (Index e = start[p]; e < start[p + 1]; ++e) {
        const Neighbour& s = nb[e];
        const double* xq = x + D * s.other;
        double dir[D], l2 = 0.0;
        for (int c = 0; c < D; ++c) {
          dir[c] = xq[c] - xp[c];
          l2 += dir[c] * dir[c];
        }
        const double l = std::sqrt(l2);
        for (int c = 0; c < D; ++c) dir[c] /= l;
        const double across = (dd_only && l < s.rest) ? 0.0 : s.k * (1.0 - s.rest / l);
        const double along = s.k - across;
        const double wq = inv_mass[s.other];
        const Index* pos = tpos + e * D * D;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            const double j = along * dir[a] * dir[b] + (a == b ? across : 0.0);
            k_values[pos[a * D + b]] += j * wq;
            kd[a][b] -= j;
          }
      }
      const Index* pos = dpos + p * D * D;
      const double wp = inv_mass[p];  // 0 for a pinned point: zero rows
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) k_values[pos[a * D + b]] = kd[a][b] * wp;
    });
    return;
  }
  for_points(num_points(), parallel(), [&](Index p) {
    const MassPoint& pt = pts[p];
    // This point's rows: cleared here (in parallel, no pass over the whole matrix), then summed.
    for (Index e = start[p]; e < start[p + 1]; ++e)
      for (int q = 0; q < D * D; ++q) {
        if (k_values) k_values[apos[e * D * D + q]] = 0.0;
        if (d_values) d_values[apos[e * D * D + q]] = 0.0;
      }
    if (pt.pinned) {  // zero rows
      for (int q = 0; q < D * D; ++q) {
        if (k_values) k_values[dpos[p * D * D + q]] = 0.0;
        if (d_values) d_values[dpos[p * D * D + q]] = 0.0;
      }
      return;
    }
    const double inv_m = 1.0 / pt.mass;
    const double* xp = x + D * p;
    const double* vp = v + D * p;
    double kd[D][D] = {}, dd[D][D] = {};  // diagonal blocks, accumulated
    for (Index e = start[p]; e < start[p + 1]; ++e) {
      const Neighbour& s = nb[e];
      const double* xq = x + D * s.other;
      double dir[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        dir[c] = xq[c] - xp[c];
        l2 += dir[c] * dir[c];
      }
      const double l = std::sqrt(l2);
      for (int c = 0; c < D; ++c) dir[c] /= l;
      // J_s = k [d dᵀ + (1 - L/l)(I - d dᵀ)] = k (L/l) d dᵀ + k (1 - L/l) I.
      const double across = (dd_only && l < s.rest) ? 0.0 : s.k * (1.0 - s.rest / l);
      const double along = s.k - across;  // coefficient of d dᵀ: k·L/l, or k when dropped
      double jk[D][D], jd[D][D];
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
          jk[a][b] = along * dir[a] * dir[b] + (a == b ? across : 0.0);
          jd[a][b] = 0.0;
        }
      if (s.damping != 0.0) {
        const double* vq = v + D * s.other;
        double u[D], sd = 0.0;
        for (int c = 0; c < D; ++c) {
          u[c] = vq[c] - vp[c];
          sd += u[c] * dir[c];
        }
        const double cl = s.damping / l;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            // J_c = (c/l)[d (u - s d)ᵀ + s (I - d dᵀ)];  D_c = c d dᵀ.
            jk[a][b] += cl * (dir[a] * (u[b] - sd * dir[b]) +
                              sd * ((a == b ? 1.0 : 0.0) - dir[a] * dir[b]));
            jd[a][b] = s.damping * dir[a] * dir[b];
          }
      }
      const Index* pos = apos + e * D * D;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
          if (k_values) k_values[pos[a * D + b]] += jk[a][b] * inv_m;
          if (d_values) d_values[pos[a * D + b]] += jd[a][b] * inv_m;
          kd[a][b] -= jk[a][b];
          dd[a][b] -= jd[a][b];
        }
    }
    const Index* pos = dpos + p * D * D;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) {
        if (k_values) k_values[pos[a * D + b]] = kd[a][b] * inv_m;
        if (d_values) d_values[pos[a * D + b]] = (dd[a][b] - (a == b ? gamma : 0.0)) * inv_m;
      }
  });
}

void MassSpringNetwork::fill_blocks(CVecRef x, CVecRef v, SparseMat* k, SparseMat* d) const {
  ensure_structure();
  // A matrix that already has this pattern (same size and number of nonzeros, compressed: a
  // previous result of this network) keeps its storage; only the values are written. Without
  // dashpots D = -(γ/m) I is diagonal and gets a diagonal pattern.
  const auto ensure = [](SparseMat* m, const SparseMat& pattern) {
    if (!m) return;
    if (m->rows() != pattern.rows() || m->cols() != pattern.cols() ||
        m->nonZeros() != pattern.nonZeros() || !m->isCompressed())
      *m = pattern;
  };
  ensure(k, pattern_);
  ensure(d, has_dashpots_ ? pattern_ : diag_pattern_);
  double* kv = k ? k->valuePtr() : nullptr;
  double* dv = d && has_dashpots_ ? d->valuePtr() : nullptr;
  if (kv || dv)
    detail::with_dim<1, 3>(
        dim_, [&](auto dim) { blocks_impl<decltype(dim)::value>(x.data(), v.data(), kv, dv); });
  if (d && !has_dashpots_) {
    double* dd = d->valuePtr();
    for (Index p = 0; p < num_points(); ++p)
      for (int c = 0; c < dim_; ++c)
        dd[dim_ * p + c] = -opt_.point_damping * inv_mass_[static_cast<std::size_t>(p)];
  }
}

void MassSpringNetwork::stiffness_block(double, CVecRef x, CVecRef v, SparseMat& k) const {
  fill_blocks(x, v, &k, nullptr);
}

void MassSpringNetwork::damping_block(double, CVecRef x, CVecRef v, SparseMat& d) const {
  fill_blocks(x, v, nullptr, &d);
}

void MassSpringNetwork::force_jacobians(double, CVecRef x, CVecRef v, SparseMat& k,
                                        SparseMat& d) const {
  fill_blocks(x, v, &k, &d);
}

std::vector<Index> MassSpringNetwork::fixed_dofs() const {
  std::vector<Index> out;
  for (Index p = 0; p < num_points(); ++p)
    if (points_[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < dim_; ++c) out.push_back(dim_ * p + c);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Observables.

double MassSpringNetwork::energy(CVecRef y) const {
  const Index n = dofs();
  double kinetic = 0.0, potential = 0.0;
  for (Index p = 0; p < num_points(); ++p) {
    const double m = points_[static_cast<std::size_t>(p)].mass;
    for (int c = 0; c < dim_; ++c) {
      const double vc = y[n + dim_ * p + c];
      kinetic += 0.5 * m * vc * vc;
      potential -= m * opt_.gravity[static_cast<std::size_t>(c)] * y[dim_ * p + c];
    }
  }
  for (const Spring& s : springs_) {
    double l2 = 0.0;
    for (int c = 0; c < dim_; ++c) {
      const double r = y[dim_ * s.j + c] - y[dim_ * s.i + c];
      l2 += r * r;
    }
    const double stretch = std::sqrt(l2) - s.rest;
    potential += 0.5 * s.k * stretch * stretch;
  }
  return kinetic + potential;
}

Vec MassSpringNetwork::linear_momentum(CVecRef y) const {
  const Index n = dofs();
  Vec p = Vec::Zero(dim_);
  for (Index q = 0; q < num_points(); ++q)
    for (int c = 0; c < dim_; ++c)
      p[c] += points_[static_cast<std::size_t>(q)].mass * y[n + dim_ * q + c];
  return p;
}

Vec MassSpringNetwork::angular_momentum(CVecRef y) const {
  const Index n = dofs();
  if (dim_ == 1) return Vec(0);
  Vec l = Vec::Zero(dim_ == 2 ? 1 : 3);
  for (Index q = 0; q < num_points(); ++q) {
    const double m = points_[static_cast<std::size_t>(q)].mass;
    const double* x = y.data() + dim_ * q;
    const double* v = y.data() + n + dim_ * q;
    if (dim_ == 2) {
      l[0] += m * (x[0] * v[1] - x[1] * v[0]);
    } else {
      l[0] += m * (x[1] * v[2] - x[2] * v[1]);
      l[1] += m * (x[2] * v[0] - x[0] * v[2]);
      l[2] += m * (x[0] * v[1] - x[1] * v[0]);
    }
  }
  return l;
}

std::vector<Invariant> MassSpringNetwork::invariants() const {
  std::vector<Invariant> out;
  out.push_back({"energy", [this](double, CVecRef y) { return energy(y); }});
  bool pinned = false;
  for (const MassPoint& pt : points_) pinned = pinned || pt.pinned;
  if (pinned || opt_.point_damping != 0.0) return out;
  static const char* const axis[] = {"x", "y", "z"};
  const auto& g = opt_.gravity;
  for (int c = 0; c < dim_; ++c) {
    if (g[static_cast<std::size_t>(c)] != 0.0) continue;
    out.push_back({std::string("momentum_") + axis[c],
                   [this, c](double, CVecRef y) { return linear_momentum(y)[c]; }});
  }
  const bool no_gravity = g[0] == 0.0 && g[1] == 0.0 && g[2] == 0.0;
  if (dim_ == 2 && no_gravity) {
    out.push_back(
        {"angular_momentum", [this](double, CVecRef y) { return angular_momentum(y)[0]; }});
  } else if (dim_ == 3) {
    for (int c = 0; c < 3; ++c) {
      // Gravity's torque M x_cm × g has no component along g: L_c is conserved when g ∥ e_c.
      bool parallel_to_axis = true;
      for (int o = 0; o < 3; ++o)
        if (o != c && g[static_cast<std::size_t>(o)] != 0.0) parallel_to_axis = false;
      if (!parallel_to_axis) continue;
      out.push_back({std::string("angular_momentum_") + axis[c],
                     [this, c](double, CVecRef y) { return angular_momentum(y)[c]; }});
    }
  }
  return out;
}

void MassSpringNetwork::exact(double t, VecRef y) const {
  if (!exact_) {
    OdeSystem::exact(t, y);
    return;
  }
  exact_(t, y);
}

// ---------------------------------------------------------------------------------------------
// Stiffness.

double MassSpringNetwork::omega_max_bound(CVecRef x) const {
  ensure_structure();
  double w2 = 0.0;
  for (Index p = 0; p < num_points(); ++p) {
    const MassPoint& pt = points_[static_cast<std::size_t>(p)];
    if (pt.pinned) continue;
    double sum = 0.0;
    for (Index e = start_[static_cast<std::size_t>(p)]; e < start_[static_cast<std::size_t>(p) + 1];
         ++e) {
      const Neighbour& s = neighbours_[static_cast<std::size_t>(e)];
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

// out = H z with H = -∂f_s/∂x (springs only, exact J_s): (H z)_p = Σ_e J_s,e (z_p - z_q).
template <int D>
void MassSpringNetwork::stiffness_matvec(const double* x, const double* z, double* out) const {
  for (Index p = 0; p < num_points(); ++p) {
    double acc[D] = {};
    const double* xp = x + D * p;
    const double* zp = z + D * p;
    for (Index e = start_[static_cast<std::size_t>(p)]; e < start_[static_cast<std::size_t>(p) + 1];
         ++e) {
      const Neighbour& s = neighbours_[static_cast<std::size_t>(e)];
      const double* xq = x + D * s.other;
      const double* zq = z + D * s.other;
      double dir[D], dz[D], l2 = 0.0, ddz = 0.0;
      for (int c = 0; c < D; ++c) {
        dir[c] = xq[c] - xp[c];
        l2 += dir[c] * dir[c];
      }
      const double l = std::sqrt(l2);
      for (int c = 0; c < D; ++c) {
        dir[c] /= l;
        dz[c] = zp[c] - zq[c];
        ddz += dir[c] * dz[c];
      }
      const double across = s.k * (1.0 - s.rest / l);
      const double along = s.k - across;
      for (int c = 0; c < D; ++c) acc[c] += along * dir[c] * ddz + across * dz[c];
    }
    for (int c = 0; c < D; ++c) out[D * p + c] = acc[c];
  }
}

std::pair<double, double> MassSpringNetwork::stiffness_eigen_range(CVecRef x) const {
  ensure_structure();
  std::vector<Index> free_dofs;
  for (Index p = 0; p < num_points(); ++p)
    if (!points_[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < dim_; ++c) free_dofs.push_back(dim_ * p + c);
  const Index nf = static_cast<Index>(free_dofs.size());
  if (nf == 0 || springs_.empty()) return {0.0, 0.0};

  // S u = M^{-1/2} H M^{-1/2} u on free dofs (pinned entries of z are zero).
  Vec z = Vec::Zero(dofs()), hz(dofs()), inv_sqrt_m(nf);
  for (Index i = 0; i < nf; ++i) inv_sqrt_m[i] = 1.0 / std::sqrt(dof_mass_[free_dofs[i]]);
  auto apply = [&](const Vec& u, Vec& out) {
    for (Index i = 0; i < nf; ++i) z[free_dofs[i]] = inv_sqrt_m[i] * u[i];
    detail::with_dim<1, 3>(dim_, [&](auto dim) {
      stiffness_matvec<decltype(dim)::value>(x.data(), z.data(), hz.data());
    });
    for (Index i = 0; i < nf; ++i) out[i] = inv_sqrt_m[i] * hz[free_dofs[i]];
  };

  // Lanczos with full reorthogonalisation (classical Gram–Schmidt, twice).
  const Index max_iter = std::min(nf, kLanczosMaxIter);
  Mat q(nf, max_iter);
  Vec alpha(max_iter), beta(max_iter), w(nf);
  std::mt19937_64 rng(20240521);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (Index i = 0; i < nf; ++i) q(i, 0) = uniform(rng);
  q.col(0).normalize();
  double lo = 0.0, hi = 0.0;
  Eigen::SelfAdjointEigenSolver<Mat> tri;
  for (Index j = 0; j < max_iter; ++j) {
    apply(q.col(j), w);
    alpha[j] = q.col(j).dot(w);
    for (int pass = 0; pass < 2; ++pass) {
      const Vec coeff = q.leftCols(j + 1).transpose() * w;
      w.noalias() -= q.leftCols(j + 1) * coeff;
    }
    beta[j] = w.norm();
    const double tiny = 1e-14 * std::max({std::abs(alpha[j]), beta[j], 1e-300});
    // The tridiagonal eigenproblem costs O(j²) or more: solve it every step while the basis is
    // small, then every fifth step.
    if (j >= 50 && j % 5 != 4 && j + 1 < max_iter && beta[j] > tiny) {
      q.col(j + 1) = w / beta[j];
      continue;
    }
    tri.computeFromTridiagonal(alpha.head(j + 1), beta.head(j), Eigen::ComputeEigenvectors);
    const Vec& theta = tri.eigenvalues();
    lo = theta[0];
    hi = theta[j];
    const double scale = std::max(std::abs(lo), std::abs(hi));
    // Residual ‖S y - θ y‖ of the Ritz pair = β_j |last component of the eigenvector of T|.
    const double res_lo = beta[j] * std::abs(tri.eigenvectors()(j, 0));
    const double res_hi = beta[j] * std::abs(tri.eigenvectors()(j, j));
    const bool invariant_subspace = beta[j] <= 1e-14 * std::max(scale, 1e-300);
    if (invariant_subspace || j + 1 == max_iter || std::max(res_lo, res_hi) <= kLanczosTol * scale)
      break;
    q.col(j + 1) = w / beta[j];
  }
  return {lo, hi};
}

double MassSpringNetwork::omega_max_estimate(CVecRef x) const {
  const auto [lo, hi] = stiffness_eigen_range(x);
  return std::sqrt(std::max(std::abs(lo), std::abs(hi)));
}

std::optional<double> MassSpringNetwork::stiffness(double, CVecRef y) const {
  if (has_constraints()) return std::nullopt;
  return omega_max_estimate(y.head(dofs()));
}

// ---------------------------------------------------------------------------------------------
// Constraints.

bool MassSpringNetwork::constraint_geometry(const double* x, std::vector<double>& normals,
                                            std::vector<double>& violation, bool& satisfied) const {
  const int d = dim_;
  satisfied = true;
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    const DistanceConstraint& dc = constraints_[c];
    const double* xi = x + d * dc.i;
    const double* xj = x + d * dc.j;
    double l2 = 0.0, scale = 0.0;
    for (int k = 0; k < d; ++k) {
      const double r = xj[k] - xi[k];
      normals[c * 3 + static_cast<std::size_t>(k)] = r;
      l2 += r * r;
      scale = std::max({scale, std::abs(xi[k]), std::abs(xj[k])});
    }
    const double l = std::sqrt(l2);
    if (!(l > 0) || !std::isfinite(l)) return false;
    for (int k = 0; k < d; ++k) normals[c * 3 + static_cast<std::size_t>(k)] /= l;
    violation[c] = l - dc.length;
    if (active_[c] && std::abs(violation[c]) > kConstraintRelTol * dc.length + 8 * kEps * scale)
      satisfied = false;
  }
  return true;
}

// A = G M⁻¹ Gᵀ at the given normals: A_cc = w_i + w_j; constraints c, d sharing point p couple
// through s_cp s_dp w_p (n_c·n_d). Inactive constraints (both ends pinned) get a unit row.
bool MassSpringNetwork::factor_constraint_matrix(const std::vector<double>& normals,
                                                 ConstraintSolver& solver) const {
  const Index nc = static_cast<Index>(constraints_.size());
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(constraints_.size() + constraint_couplings_.size());
  for (Index c = 0; c < nc; ++c) {
    const DistanceConstraint& dc = constraints_[static_cast<std::size_t>(c)];
    const double w =
        inv_mass_[static_cast<std::size_t>(dc.i)] + inv_mass_[static_cast<std::size_t>(dc.j)];
    trips.emplace_back(c, c, active_[static_cast<std::size_t>(c)] ? w : 1.0);
  }
  for (const Coupling& cp : constraint_couplings_) {
    double dot = 0.0;
    for (int k = 0; k < dim_; ++k)
      dot += normals[static_cast<std::size_t>(cp.c) * 3 + static_cast<std::size_t>(k)] *
             normals[static_cast<std::size_t>(cp.d) * 3 + static_cast<std::size_t>(k)];
    trips.emplace_back(cp.c, cp.d, cp.sign * inv_mass_[static_cast<std::size_t>(cp.p)] * dot);
  }
  SparseMat a(nc, nc);
  a.setFromTriplets(trips.begin(), trips.end());
  solver.compute(a);
  if (solver.info() != Eigen::Success) return false;
  // A singular A (redundant constraints) can factor with a zero pivot: refuse it.
  const Vec diag = solver.vectorD();
  return diag.size() == nc && diag.minCoeff() > 1e-12 * diag.cwiseAbs().maxCoeff();
}

// x += -M⁻¹ Gᵀ λ (positions) or v += -M⁻¹ Gᵀ μ (velocities), constraint by constraint.
void MassSpringNetwork::apply_constraint_impulses(const std::vector<double>& normals,
                                                  const Vec& lambda, double* z) const {
  const int d = dim_;
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    if (!active_[c]) continue;
    const DistanceConstraint& dc = constraints_[c];
    const double wi = inv_mass_[static_cast<std::size_t>(dc.i)];
    const double wj = inv_mass_[static_cast<std::size_t>(dc.j)];
    const double l = lambda[static_cast<Index>(c)];
    for (int k = 0; k < d; ++k) {
      const double nk = normals[c * 3 + static_cast<std::size_t>(k)];
      z[d * dc.i + k] += wi * l * nk;  // -w_i (∂C/∂x_i) λ with ∂C/∂x_i = -n
      z[d * dc.j + k] -= wj * l * nk;
    }
  }
}

void MassSpringNetwork::project(double, VecRef y) const {
  if (constraints_.empty()) return;
  const Index n = dofs();
  const std::size_t nc = constraints_.size();
  double* x = y.data();
  double* v = y.data() + n;
  std::vector<double> normals(3 * nc), violation(nc);
  ConstraintSolver solver;

  // 1. Positions: x ← x - M⁻¹ G(x)ᵀ λ with G(x) M⁻¹ G(x)ᵀ λ = C(x), repeated (Newton).
  bool satisfied = false, direct = true;
  for (int iter = 0; iter < kMaxNewtonIterations; ++iter) {
    if (!constraint_geometry(x, normals, violation, satisfied)) return;  // l = 0: give up
    if (satisfied) break;
    if (!factor_constraint_matrix(normals, solver)) {
      direct = false;
      break;
    }
    Vec c(static_cast<Index>(nc));
    for (std::size_t k = 0; k < nc; ++k) c[static_cast<Index>(k)] = active_[k] ? violation[k] : 0;
    const Vec lambda = solver.solve(c);
    if (!lambda.allFinite()) {
      direct = false;
      break;
    }
    apply_constraint_impulses(normals, lambda, x);
  }
  if (!direct) project_positions_gauss_seidel(x);

  // 2. Velocities: v ← v - M⁻¹ Gᵀ μ with G M⁻¹ Gᵀ μ = G v at the projected positions.
  double vscale = 0.0;
  for (Index k = 0; k < n; ++k) vscale = std::max(vscale, std::abs(v[k]));
  if (vscale == 0.0) return;
  if (!constraint_geometry(x, normals, violation, satisfied)) return;
  direct = direct && factor_constraint_matrix(normals, solver);
  for (int pass = 0; direct && pass < 3; ++pass) {
    Vec gv(static_cast<Index>(nc));
    double worst = 0.0;
    for (std::size_t c = 0; c < nc; ++c) {
      const DistanceConstraint& dc = constraints_[c];
      double s = 0.0;
      for (int k = 0; k < dim_; ++k)
        s += (v[dim_ * dc.j + k] - v[dim_ * dc.i + k]) *
             normals[c * 3 + static_cast<std::size_t>(k)];
      gv[static_cast<Index>(c)] = active_[c] ? s : 0.0;
      worst = std::max(worst, std::abs(gv[static_cast<Index>(c)]));
    }
    if (worst <= kConstraintRelTol * vscale) return;
    const Vec mu = solver.solve(gv);
    if (!mu.allFinite()) break;
    apply_constraint_impulses(normals, mu, v);
  }
  if (!direct) project_velocities_gauss_seidel(x, v, vscale);
}

void MassSpringNetwork::project_positions_gauss_seidel(double* x) const {
  const int d = dim_;
  for (int sweep = 0; sweep < kMaxProjectionSweeps; ++sweep) {
    bool converged = true;
    for (const DistanceConstraint& c : constraints_) {
      const double wi = inv_mass_[static_cast<std::size_t>(c.i)];
      const double wj = inv_mass_[static_cast<std::size_t>(c.j)];
      if (wi + wj == 0.0) continue;
      double* xi = x + d * c.i;
      double* xj = x + d * c.j;
      double r[3], l2 = 0.0, scale = 0.0;
      for (int k = 0; k < d; ++k) {
        r[k] = xj[k] - xi[k];
        l2 += r[k] * r[k];
        scale = std::max({scale, std::abs(xi[k]), std::abs(xj[k])});
      }
      const double l = std::sqrt(l2);
      const double violation = l - c.length;
      if (std::abs(violation) > kConstraintRelTol * c.length + 8 * kEps * scale) converged = false;
      // Moving both ends along n by Δ = C/(w_i + w_j), mass-weighted, makes this one exact.
      const double delta = violation / (wi + wj);
      for (int k = 0; k < d; ++k) {
        const double nk = r[k] / l;
        xi[k] += wi * delta * nk;
        xj[k] -= wj * delta * nk;
      }
    }
    if (converged) break;
  }
}

void MassSpringNetwork::project_velocities_gauss_seidel(const double* x, double* v,
                                                        double vscale) const {
  const int d = dim_;
  for (int sweep = 0; sweep < kMaxProjectionSweeps; ++sweep) {
    bool converged = true;
    for (const DistanceConstraint& c : constraints_) {
      const double wi = inv_mass_[static_cast<std::size_t>(c.i)];
      const double wj = inv_mass_[static_cast<std::size_t>(c.j)];
      if (wi + wj == 0.0) continue;
      const double* xi = x + d * c.i;
      const double* xj = x + d * c.j;
      double* vi = v + d * c.i;
      double* vj = v + d * c.j;
      double r[3], l2 = 0.0;
      for (int k = 0; k < d; ++k) {
        r[k] = xj[k] - xi[k];
        l2 += r[k] * r[k];
      }
      const double l = std::sqrt(l2);
      double s = 0.0;
      for (int k = 0; k < d; ++k) s += (vj[k] - vi[k]) * r[k] / l;
      if (std::abs(s) > kConstraintRelTol * vscale) converged = false;
      const double delta = s / (wi + wj);
      for (int k = 0; k < d; ++k) {
        const double nk = r[k] / l;
        vi[k] += wi * delta * nk;
        vj[k] -= wj * delta * nk;
      }
    }
    if (converged) break;
  }
}

// g_r = l - L for active constraint r = (i, j), l = |x_j - x_i|.
void MassSpringNetwork::constraint_values(CVecRef x, VecRef g) const {
  for (std::size_t r = 0; r < active_list_.size(); ++r) {
    const DistanceConstraint& dc = constraints_[static_cast<std::size_t>(active_list_[r])];
    double l2 = 0.0;
    for (int k = 0; k < dim_; ++k) {
      const double d = x[dim_ * dc.j + k] - x[dim_ * dc.i + k];
      l2 += d * d;
    }
    g[static_cast<Index>(r)] = std::sqrt(l2) - dc.length;
  }
}

// Row r of G: ∂l/∂x_i = -n, ∂l/∂x_j = +n with n = (x_j - x_i)/l (NaN at l = 0, where the
// direction is undefined; the caller's solve then fails). The pattern (2·dim entries per row) is
// built once; later calls with that pattern write the values in place.
void MassSpringNetwork::constraint_jacobian(CVecRef x, SparseMat& jac) const {
  const Index m = constraint_count();
  const Index per_row = 2 * dim_;
  if (jac.rows() != m || jac.cols() != dofs() || jac.nonZeros() != m * per_row ||
      !jac.isCompressed()) {
    std::vector<Eigen::Triplet<double>> trips;
    trips.reserve(static_cast<std::size_t>(m * per_row));
    for (Index r = 0; r < m; ++r) {
      const DistanceConstraint& dc = constraints_[static_cast<std::size_t>(active_list_[r])];
      for (int k = 0; k < dim_; ++k) {
        trips.emplace_back(r, dim_ * dc.i + k, 0.0);
        trips.emplace_back(r, dim_ * dc.j + k, 0.0);
      }
    }
    jac.resize(m, dofs());
    jac.setFromTriplets(trips.begin(), trips.end());
    jac.makeCompressed();
  }
  for (Index r = 0; r < m; ++r) {
    const DistanceConstraint& dc = constraints_[static_cast<std::size_t>(active_list_[r])];
    double d[3] = {0.0, 0.0, 0.0}, l2 = 0.0;
    for (int k = 0; k < dim_; ++k) {
      d[k] = x[dim_ * dc.j + k] - x[dim_ * dc.i + k];
      l2 += d[k] * d[k];
    }
    const double l = std::sqrt(l2);
    for (int k = 0; k < dim_; ++k) {
      jac.coeffRef(r, dim_ * dc.i + k) = -d[k] / l;
      jac.coeffRef(r, dim_ * dc.j + k) = d[k] / l;
    }
  }
}

double MassSpringNetwork::constraint_residual(CVecRef y) const {
  double worst = 0.0;
  for (const DistanceConstraint& c : constraints_) {
    double l2 = 0.0;
    for (int k = 0; k < dim_; ++k) {
      const double r = y[dim_ * c.j + k] - y[dim_ * c.i + k];
      l2 += r * r;
    }
    worst = std::max(worst, std::abs(std::sqrt(l2) - c.length));
  }
  return worst;
}

}  // namespace stiffbench
