#include "models/mass_spring/distance_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stiffbench {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Position-projection stop: |C| <= 1e-13 L, or the round-off floor of computing l from
// coordinates of size |x|.
constexpr double kConstraintRelTol = 1e-13;
constexpr int kMaxProjectionSweeps = 1000;  // Gauss–Seidel fallback
constexpr int kMaxNewtonIterations = 20;

// Gradient sign of constraint c = (i, j) with respect to point p: ∂C/∂x_p = sign · n,
// n = (x_j - x_i)/l (-1 at i, +1 at j).
double end_sign(const DistanceConstraint& c, Index p) { return p == c.i ? -1.0 : 1.0; }

}  // namespace

DistanceConstraints::DistanceConstraints(int dim, const std::vector<MassPoint>& points,
                                         std::vector<DistanceConstraint> constraints)
    : dim_(dim),
      dofs_(dim * static_cast<Index>(points.size())),
      constraints_(std::move(constraints)) {
  inv_mass_.resize(points.size());
  for (std::size_t p = 0; p < points.size(); ++p)
    inv_mass_[p] = points[p].pinned ? 0.0 : 1.0 / points[p].mass;

  // Couplings: constraints c != d sharing a point p couple in G M⁻¹ Gᵀ.
  active_.resize(constraints_.size());
  std::vector<std::vector<Index>> touching(points.size());
  for (std::size_t c = 0; c < constraints_.size(); ++c) {
    const DistanceConstraint& dc = constraints_[c];
    active_[c] = !(points[static_cast<std::size_t>(dc.i)].pinned &&
                   points[static_cast<std::size_t>(dc.j)].pinned);
    if (!active_[c]) continue;
    active_list_.push_back(static_cast<Index>(c));
    touching[static_cast<std::size_t>(dc.i)].push_back(static_cast<Index>(c));
    touching[static_cast<std::size_t>(dc.j)].push_back(static_cast<Index>(c));
  }
  for (std::size_t p = 0; p < touching.size(); ++p) {
    if (points[p].pinned) continue;  // w_p = 0: no coupling
    for (Index c : touching[p])
      for (Index e : touching[p]) {
        if (c == e) continue;
        const double sign =
            end_sign(constraints_[static_cast<std::size_t>(c)], static_cast<Index>(p)) *
            end_sign(constraints_[static_cast<std::size_t>(e)], static_cast<Index>(p));
        couplings_.push_back({c, e, static_cast<Index>(p), sign});
      }
  }
}

bool DistanceConstraints::geometry(const double* x, std::vector<double>& normals,
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
bool DistanceConstraints::factor(const std::vector<double>& normals, Solver& solver) const {
  const Index nc = static_cast<Index>(constraints_.size());
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(constraints_.size() + couplings_.size());
  for (Index c = 0; c < nc; ++c) {
    const DistanceConstraint& dc = constraints_[static_cast<std::size_t>(c)];
    const double w =
        inv_mass_[static_cast<std::size_t>(dc.i)] + inv_mass_[static_cast<std::size_t>(dc.j)];
    trips.emplace_back(c, c, active_[static_cast<std::size_t>(c)] ? w : 1.0);
  }
  for (const Coupling& cp : couplings_) {
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
void DistanceConstraints::apply_impulses(const std::vector<double>& normals, const Vec& lambda,
                                         double* z) const {
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

void DistanceConstraints::project(VecRef y) const {
  if (constraints_.empty()) return;
  const Index n = dofs_;
  const std::size_t nc = constraints_.size();
  double* x = y.data();
  double* v = y.data() + n;
  std::vector<double> normals(3 * nc), violation(nc);
  Solver solver;

  // 1. Positions: x ← x - M⁻¹ G(x)ᵀ λ with G(x) M⁻¹ G(x)ᵀ λ = C(x), repeated (Newton).
  bool satisfied = false, direct = true;
  for (int iter = 0; iter < kMaxNewtonIterations; ++iter) {
    if (!geometry(x, normals, violation, satisfied)) return;  // l = 0: give up
    if (satisfied) break;
    if (!factor(normals, solver)) {
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
    apply_impulses(normals, lambda, x);
  }
  if (!direct) project_positions_gauss_seidel(x);

  // 2. Velocities: v ← v - M⁻¹ Gᵀ μ with G M⁻¹ Gᵀ μ = G v at the projected positions.
  double vscale = 0.0;
  for (Index k = 0; k < n; ++k) vscale = std::max(vscale, std::abs(v[k]));
  if (vscale == 0.0) return;
  if (!geometry(x, normals, violation, satisfied)) return;
  direct = direct && factor(normals, solver);
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
    apply_impulses(normals, mu, v);
  }
  if (!direct) project_velocities_gauss_seidel(x, v, vscale);
}

void DistanceConstraints::project_positions_gauss_seidel(double* x) const {
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

void DistanceConstraints::project_velocities_gauss_seidel(const double* x, double* v,
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
void DistanceConstraints::constraint_values(CVecRef x, VecRef g) const {
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
void DistanceConstraints::constraint_jacobian(CVecRef x, SparseMat& jac) const {
  const Index m = constraint_count();
  const Index per_row = 2 * dim_;
  if (jac.rows() != m || jac.cols() != dofs_ || jac.nonZeros() != m * per_row ||
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
    jac.resize(m, dofs_);
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

double DistanceConstraints::residual(CVecRef y) const {
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
