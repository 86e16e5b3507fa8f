// MassSpringNetwork's Jacobian blocks K and D (the springs' and dashpots'), and air drag: its
// force in the right-hand side and its blocks (network.hpp's header comment).
#include "models/mass_spring/network_parts.hpp"

#include "models/detail/with_dim.hpp"

#include <algorithm>
#include <cmath>

namespace stiffbench {

using detail::face_drag;
using detail::FaceDrag;
using detail::for_points;

// ---------------------------------------------------------------------------------------------
// Jacobian blocks.
//
// Derivation of the dashpot's position derivative: f_i = c s d with s = u·d, u = v_j - v_i,
// d = (x_j - x_i)/l. Then ∂f_i/∂d = c (d uᵀ + s I) and ∂d/∂x_j = (I - d dᵀ)/l, so
//   ∂f_i/∂x_j = (c/l)(d uᵀ + s I)(I - d dᵀ) = (c/l)[d (u - s d)ᵀ + s (I - d dᵀ)] = J_c,
// and ∂f_i/∂x_i = -J_c because d depends on x_j - x_i only. ∂f_i/∂v_j = c d dᵀ = -∂f_i/∂v_i.

template <int D>
void MassSpringNetwork::blocks_impl(const Structure& st, double gamma, const double* x,
                                    const double* v, double* k_values, double* d_values) const {
  const bool dd_only = opt_.compressed_dd_only;
  const Index* start = st.adjacency->start.data();
  const SpringNeighbour* nb = st.adjacency->neighbours.data();
  const MassPoint* pts = points_.data();
  const Index* dpos = st.diag_pos.data();
  const Index* apos = st.adj_pos.data();
  // Without dashpots each spring's block J_s is symmetric and the same from both ends, so point
  // p can fill its own column block instead of its row block: K_qp = J_s / m_q (0 for a pinned
  // q), a contiguous range of the column-major storage. With dashpots (J_c is not symmetric)
  // point p fills its rows.
  const bool by_column = !st.dashpots && !d_values;
  const Index* tpos = st.adj_pos_t.data();
  const double* inv_mass = inv_mass_.data();
  if (by_column && k_values) {
    for_points(num_points(), parallel(), [&](Index p) {
      const double* xp = x + D * p;
      for (Index e = start[p]; e < start[p + 1]; ++e)
        for (int q = 0; q < D * D; ++q) k_values[tpos[e * D * D + q]] = 0.0;
      double kd[D][D] = {};
      for (Index e = start[p]; e < start[p + 1]; ++e) {
        const SpringNeighbour& s = nb[e];
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
      const SpringNeighbour& s = nb[e];
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

void MassSpringNetwork::fill_blocks(const Structure& st, double gamma, bool with_drag, CVecRef x,
                                    CVecRef v, SparseMat* k, SparseMat* d) const {
  // A matrix that already has this pattern (same size and number of nonzeros, compressed: a
  // previous result of this network) keeps its storage; only the values are written. Without
  // dashpots D = -(γ/m) I is diagonal and gets a diagonal pattern.
  const auto ensure = [](SparseMat* m, const SparseMat& pattern) {
    if (!m) return;
    if (m->rows() != pattern.rows() || m->cols() != pattern.cols() ||
        m->nonZeros() != pattern.nonZeros() || !m->isCompressed())
      *m = pattern;
  };
  with_drag = with_drag && drag();
  const bool full_d = st.dashpots || with_drag;  // D on K's pattern
  ensure(k, st.pattern);
  ensure(d, full_d ? st.pattern : st.diag_pattern);
  double* kv = k ? k->valuePtr() : nullptr;
  double* dv = d && full_d ? d->valuePtr() : nullptr;
  if (kv || dv)
    detail::with_dim<1, 3>(dim_, [&](auto dim) {
      blocks_impl<decltype(dim)::value>(st, gamma, x.data(), v.data(), kv, dv);
    });
  if (with_drag) add_drag_blocks(st, x.data(), v.data(), kv, dv);
  if (d && !full_d) {
    double* dd = d->valuePtr();
    for (Index p = 0; p < num_points(); ++p)
      for (int c = 0; c < dim_; ++c)
        dd[dim_ * p + c] = -gamma * inv_mass_[static_cast<std::size_t>(p)];
  }
}

void MassSpringNetwork::stiffness_block(double, CVecRef x, CVecRef v, SparseMat& k) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, &k, nullptr);
}

void MassSpringNetwork::damping_block(double, CVecRef x, CVecRef v, SparseMat& d) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, nullptr, &d);
}

void MassSpringNetwork::force_jacobians(double, CVecRef x, CVecRef v, SparseMat& k,
                                        SparseMat& d) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, &k, &d);
}

// ---------------------------------------------------------------------------------------------
// Air drag (see the header comment for the force and its derivatives).

// The triangles' forces into face_force_, then each free point adds its triangles' shares in
// ascending triangle order: the additions of one serial pass over the triangles, for any thread
// count.
void MassSpringNetwork::add_drag(const double* x, const double* v, double* a) const {
  const double beta = 0.5 * opt_.air_drag;
  double* force = face_force_.data();
  const auto nt = static_cast<Index>(triangles_.size());
  for_points(nt, parallel(), [&](Index t) {
    const FaceDrag fd = face_drag(x, v, triangles_[static_cast<std::size_t>(t)], beta);
    for (int c = 0; c < 3; ++c) force[3 * t + c] = fd.f[c];
  });
  const Index* start = point_face_start_.data();
  const Index* faces = point_faces_.data();
  for_points(num_points(), parallel(), [&](Index p) {
    if (pinned_[static_cast<std::size_t>(p)]) return;
    const double s = inv_mass_[static_cast<std::size_t>(p)] / 3.0;
    for (Index e = start[p]; e < start[p + 1]; ++e)
      for (int c = 0; c < 3; ++c) a[3 * p + c] += s * force[3 * faces[e] + c];
  });
}

void MassSpringNetwork::add_drag_blocks(const Structure& st, const double* x, const double* v,
                                        double* k_values, double* d_values) const {
  const double beta = 0.5 * opt_.air_drag;
  const auto* outer = st.pattern.outerIndexPtr();
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Triangle& tr = triangles_[t];
    const Index pts[3] = {tr.a, tr.b, tr.c};
    const FaceDrag fd = face_drag(x, v, tr, beta);
    const double* n = fd.n;
    const double au = std::abs(fd.u), uau = fd.u * au, w = fd.w;
    // ∂F/∂v_q (the same for every q) and G = ∂F/∂N.
    double dv[3][3], g[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        dv[r][c] = -(2.0 * beta * au * w / 3.0) * n[r] * n[c];
        g[r][c] = -beta * (2.0 * au * w * n[r] * fd.vbar[c] + (r == c ? uau * w : 0.0) -
                           2.0 * uau * w * w * n[r] * n[c]);
      }
    // S_q = [s_q]× with s_a = e2 - e1 = x_c - x_b, s_b = -e2 = x_a - x_c, s_c = e1 = x_b - x_a.
    double side[3][3];
    for (int c = 0; c < 3; ++c) {
      side[0][c] = x[3 * tr.c + c] - x[3 * tr.b + c];
      side[1][c] = x[3 * tr.a + c] - x[3 * tr.c + c];
      side[2][c] = x[3 * tr.b + c] - x[3 * tr.a + c];
    }
    for (int qi = 0; qi < 3; ++qi) {
      const double* sq = side[qi];
      const double cross[3][3] = {{0.0, -sq[2], sq[1]}, {sq[2], 0.0, -sq[0]}, {-sq[1], sq[0], 0.0}};
      double kx[3][3];  // ∂F/∂x_q = G S_q
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          kx[r][c] = g[r][0] * cross[0][c] + g[r][1] * cross[1][c] + g[r][2] * cross[2][c];
      const Index q = pts[qi];
      const Index len = outer[3 * q + 1] - outer[3 * q];
      for (int pi = 0; pi < 3; ++pi) {
        const Index p = pts[pi];
        if (pinned_[static_cast<std::size_t>(p)]) continue;  // zero rows
        const double s = inv_mass_[static_cast<std::size_t>(p)] / 3.0;
        const Index base = st.face_pos[9 * t + static_cast<std::size_t>(3 * pi + qi)];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            if (k_values) k_values[base + r + c * len] += s * kx[r][c];
            if (d_values) d_values[base + r + c * len] += s * dv[r][c];
          }
      }
    }
  }
}

}  // namespace stiffbench
