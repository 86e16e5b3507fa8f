#include "integrators/solvers/velocity_form.hpp"

#include <algorithm>
#include <stdexcept>

namespace stiffbench {

namespace {

// Below this many nonzeros A is assembled on one thread (thread start-up would dominate).
constexpr Index kParallelNonzeros = 100000;

// Position of (row, col) in the compressed column-major a, or -1.
int position(const SparseMat& a, Index row, Index col) {
  const int* begin = a.innerIndexPtr() + a.outerIndexPtr()[col];
  const int* end = a.innerIndexPtr() + a.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(begin, end, static_cast<int>(row));
  if (it == end || *it != row) return -1;
  return static_cast<int>(it - a.innerIndexPtr());
}

std::vector<int> map_into(const SparseMat& from, const SparseMat& into) {
  std::vector<int> map(static_cast<std::size_t>(from.nonZeros()));
  for (Index c = 0; c < from.outerSize(); ++c)
    for (int k = from.outerIndexPtr()[c]; k < from.outerIndexPtr()[c + 1]; ++k)
      map[static_cast<std::size_t>(k)] = position(into, from.innerIndexPtr()[k], c);
  return map;
}

}  // namespace

LinearSolverKind velocity_form_auto_solver(Index n, bool symmetric) {
  if (symmetric) return n <= kVelocityLdltMax ? LinearSolverKind::ldlt : LinearSolverKind::cg;
  return n <= 200 ? LinearSolverKind::dense_lu : LinearSolverKind::sparse_lu;
}

void VelocityFormSolver::make_solver(LinearSolverKind kind) {
  LinearSolverOptions o = opt_;
  o.kind = kind;
  solver_ = make_linear_solver(o, n_);
  solver_->analyze(a_);
  if (block_ && is_krylov(kind))
    solver_->use_product([this](CVecRef in, VecRef out) { block_product(in, out); });
}

void VelocityFormSolver::detect_blocks() {
  block_ = 0;
  if (!opt_.symmetric) return;
  const int* outer = a_.outerIndexPtr();
  const int* inner = a_.innerIndexPtr();
  for (int b : {3, 2}) {
    if (n_ % b != 0) continue;
    bool ok = true;
    for (Index c0 = 0; ok && c0 < n_; c0 += b) {
      const int len = outer[c0 + 1] - outer[c0];
      if (len % b != 0) ok = false;
      for (int k = outer[c0]; ok && k < outer[c0 + 1]; k += b)
        for (int i = 0; i < b; ++i)
          if (inner[k + i] != inner[k] + i || inner[k] % b != 0) ok = false;
      for (int j = 1; ok && j < b; ++j)
        ok = outer[c0 + j + 1] - outer[c0 + j] == len &&
             std::equal(inner + outer[c0], inner + outer[c0 + 1], inner + outer[c0 + j]);
    }
    if (!ok) continue;
    block_ = b;
    const Index nb = n_ / b;
    bsr_row_.assign(static_cast<std::size_t>(nb) + 1, 0);
    bsr_col_.clear();
    bsr_pos_.assign(static_cast<std::size_t>(a_.nonZeros()), 0);
    for (Index bi = 0; bi < nb; ++bi) {
      const Index c0 = bi * b;
      const int first = static_cast<int>(bsr_col_.size());
      for (int k = outer[c0]; k < outer[c0 + 1]; k += b) bsr_col_.push_back(inner[k] / b);
      bsr_row_[static_cast<std::size_t>(bi) + 1] = static_cast<int>(bsr_col_.size());
      // Entry (row bJ + j, column bI + i) of A is element [i][j] of block (I, J) (symmetry).
      for (int i = 0; i < b; ++i) {
        int blk = first;
        for (int k = outer[c0 + i]; k < outer[c0 + i + 1]; k += b, ++blk)
          for (int j = 0; j < b; ++j)
            bsr_pos_[static_cast<std::size_t>(k + j)] = (blk * b + i) * b + j;
      }
    }
    bsr_val_.assign(bsr_col_.size() * static_cast<std::size_t>(b * b), 0.0);
    return;
  }
}

namespace {

template <int B>
void bsr_multiply(Index nb, const int* row, const int* col, const double* val, const double* x,
                  double* y) {
  const auto block_row = [&](Index bi) {
    double acc[B] = {};
    for (int blk = row[bi]; blk < row[bi + 1]; ++blk) {
      const double* v = val + static_cast<std::ptrdiff_t>(blk) * B * B;
      const double* xj = x + static_cast<std::ptrdiff_t>(col[blk]) * B;
      for (int i = 0; i < B; ++i)
        for (int j = 0; j < B; ++j) acc[i] += v[i * B + j] * xj[j];
    }
    for (int i = 0; i < B; ++i) y[bi * B + i] = acc[i];
  };
  if (static_cast<Index>(row[nb]) * B * B >= kParallelNonzeros) {
#pragma omp parallel for schedule(static)
    for (Index bi = 0; bi < nb; ++bi) block_row(bi);
  } else {
    for (Index bi = 0; bi < nb; ++bi) block_row(bi);
  }
}

}  // namespace

void VelocityFormSolver::block_product(CVecRef in, VecRef out) const {
  const Index nb = n_ / block_;
  if (block_ == 3)
    bsr_multiply<3>(nb, bsr_row_.data(), bsr_col_.data(), bsr_val_.data(), in.data(), out.data());
  else
    bsr_multiply<2>(nb, bsr_row_.data(), bsr_col_.data(), bsr_val_.data(), in.data(), out.data());
}

void VelocityFormSolver::reset(const MechanicalSystem& sys, LinearSolverOptions opt, double t0,
                               CVecRef y0) {
  if (!sys.has_force_jacobians())
    throw std::logic_error("VelocityFormSolver: the model has no force Jacobians");
  sys_ = &sys;
  n_ = sys.dofs();
  opt_ = opt;
  opt_.symmetric = sys.symmetric_force_jacobians();
  velocity_dependent_ = sys.velocity_dependent();
  m_ = sys.masses();
  k_.resize(0, 0);
  d_.resize(0, 0);
  sys.force_jacobians(t0, y0.head(n_), y0.tail(n_), k_, d_);
  k_.makeCompressed();
  d_.makeCompressed();

  build_pattern();

  LinearSolverKind kind = opt_.kind;
  auto_kind_ = kind == LinearSolverKind::automatic;
  if (auto_kind_) kind = velocity_form_auto_solver(n_, opt_.symmetric);
  make_solver(kind);
  rhs_.resize(n_);
  kv_.resize(n_);
  error_.clear();
}

void VelocityFormSolver::build_pattern() {
  k_outer_.assign(k_.outerIndexPtr(), k_.outerIndexPtr() + k_.outerSize() + 1);
  k_inner_.assign(k_.innerIndexPtr(), k_.innerIndexPtr() + k_.nonZeros());
  d_outer_.assign(d_.outerIndexPtr(), d_.outerIndexPtr() + d_.outerSize() + 1);
  d_inner_.assign(d_.innerIndexPtr(), d_.innerIndexPtr() + d_.nonZeros());
  // A's pattern: K ∪ D ∪ diagonal.
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(static_cast<std::size_t>(k_.nonZeros() + d_.nonZeros() + n_));
  for (const SparseMat* b : {&k_, &d_})
    for (Index c = 0; c < b->outerSize(); ++c)
      for (SparseMat::InnerIterator it(*b, c); it; ++it) trips.emplace_back(it.row(), c, 0.0);
  for (Index i = 0; i < n_; ++i) trips.emplace_back(i, i, 0.0);
  a_.resize(n_, n_);
  a_.setFromTriplets(trips.begin(), trips.end());
  a_.makeCompressed();
  k_map_ = map_into(k_, a_);
  d_map_ = map_into(d_, a_);
  diag_pos_.resize(static_cast<std::size_t>(n_));
  for (Index i = 0; i < n_; ++i) diag_pos_[static_cast<std::size_t>(i)] = position(a_, i, i);

  fixed_ = sys_->fixed_dofs();
  is_fixed_.assign(static_cast<std::size_t>(n_), 0);
  for (Index f : fixed_) {
    if (f < 0 || f >= n_) throw std::logic_error("VelocityFormSolver: fixed dof out of range");
    is_fixed_[static_cast<std::size_t>(f)] = 1;
  }
  fixed_entries_.clear();
  couplings_.clear();
  for (Index c = 0; c < n_; ++c)
    for (int k = a_.outerIndexPtr()[c]; k < a_.outerIndexPtr()[c + 1]; ++k) {
      const Index r = a_.innerIndexPtr()[k];
      if (r == c) continue;
      const bool fr = is_fixed_[static_cast<std::size_t>(r)],
                 fc = is_fixed_[static_cast<std::size_t>(c)];
      if (fr || fc) fixed_entries_.push_back(k);
      if (fc && !fr) couplings_.push_back({k, r, c});
    }
  coupling_values_.resize(static_cast<Index>(couplings_.size()));
  k_fixed_cols_.clear();
  for (Index f : fixed_)
    for (int k = k_.outerIndexPtr()[f]; k < k_.outerIndexPtr()[f + 1]; ++k)
      if (!is_fixed_[static_cast<std::size_t>(k_.innerIndexPtr()[k])])
        k_fixed_cols_.push_back({k, k_.innerIndexPtr()[k], f});
  detect_blocks();
}

bool VelocityFormSolver::same_patterns() const {
  const auto same = [](const SparseMat& a, const std::vector<int>& outer,
                       const std::vector<int>& inner) {
    return a.isCompressed() && static_cast<std::size_t>(a.outerSize() + 1) == outer.size() &&
           static_cast<std::size_t>(a.nonZeros()) == inner.size() &&
           std::equal(outer.begin(), outer.end(), a.outerIndexPtr()) &&
           std::equal(inner.begin(), inner.end(), a.innerIndexPtr());
  };
  return same(k_, k_outer_, k_inner_) && same(d_, d_outer_, d_inner_);
}

void VelocityFormSolver::update(double t, CVecRef y) {
  sys_->force_jacobians(t, y.head(n_), y.tail(n_), k_, d_);
  if (same_patterns()) return;
  k_.makeCompressed();
  d_.makeCompressed();
  if (same_patterns()) return;
  build_pattern();  // a model that rebuilds its blocks with another pattern: analyse again
  make_solver(solver_->kind());
}

bool VelocityFormSolver::factor(double c) {
  c_ = c;
  double* a = a_.valuePtr();
  const double* kv = k_.valuePtr();
  const double* dv = d_.valuePtr();
  const int* ki = k_.innerIndexPtr();
  const int* di = d_.innerIndexPtr();
  const int* ko = k_.outerIndexPtr();
  const int* dout = d_.outerIndexPtr();
  const int* ao = a_.outerIndexPtr();
  const double* m = m_.data();
  const int* kmap = k_map_.data();
  const int* dmap = d_map_.data();
  const double ck = -c * c, cd = -c;
  const bool with_d = velocity_dependent_;
  // Column j of K and D lands in column j of A: columns are independent.
  const auto column = [&](Index j) {
    std::fill(a + ao[j], a + ao[j + 1], 0.0);
    for (int k = ko[j]; k < ko[j + 1]; ++k) a[kmap[k]] += ck * m[ki[k]] * kv[k];
    if (with_d)
      for (int k = dout[j]; k < dout[j + 1]; ++k) a[dmap[k]] += cd * m[di[k]] * dv[k];
    a[diag_pos_[static_cast<std::size_t>(j)]] += m[j];
  };
  if (a_.nonZeros() >= kParallelNonzeros) {
#pragma omp parallel for schedule(static)
    for (Index j = 0; j < n_; ++j) column(j);
  } else {
    for (Index j = 0; j < n_; ++j) column(j);
  }
  // Filter the fixed dofs: keep their column entries for the right-hand side, then leave only
  // the diagonal M_ff in their rows and columns.
  for (std::size_t q = 0; q < couplings_.size(); ++q)
    coupling_values_[static_cast<Index>(q)] = a[couplings_[q].pos];
  for (int k : fixed_entries_) a[k] = 0.0;
  for (Index f : fixed_) a[diag_pos_[static_cast<std::size_t>(f)]] = m[f];

  if (block_ && is_krylov(solver_->kind())) {
    // Columns bI..bI+b-1 of A fill block row I: block rows are independent.
    const int b = block_;
    const int* pos = bsr_pos_.data();
    double* bv = bsr_val_.data();
    const auto copy = [&](Index bi) {
      for (int k = ao[bi * b]; k < ao[bi * b + b]; ++k) bv[pos[k]] = a[k];
    };
    const Index nb = n_ / b;
    if (a_.nonZeros() >= kParallelNonzeros) {
#pragma omp parallel for schedule(static)
      for (Index bi = 0; bi < nb; ++bi) copy(bi);
    } else {
      for (Index bi = 0; bi < nb; ++bi) copy(bi);
    }
  }
  if (!solver_->factor(a_)) {
    error_ = solver_->error();
    return false;
  }
  return true;
}

LinearSolveResult VelocityFormSolver::solve(CVecRef r, VecRef k) {
  const auto rx = r.head(n_);
  const auto rv = r.tail(n_);
  // rhs = M (r_v + c K r_x); fixed rows: M_ff k_v,f = M_ff r_v,f.
  if (opt_.symmetric) {
    mk_product(rx, rhs_);
    rhs_ = m_.cwiseProduct(rv) + c_ * rhs_;
  } else {
    rhs_.noalias() = k_ * rx;
    rhs_ = m_.cwiseProduct(rv + c_ * rhs_);
  }
  bool moved = false;
  for (Index f : fixed_) {
    rhs_[f] = m_[f] * rv[f];
    moved = moved || rv[f] != 0.0;
  }
  if (moved)
    for (std::size_t q = 0; q < couplings_.size(); ++q)
      rhs_[couplings_[q].row] -= coupling_values_[static_cast<Index>(q)] * rv[couplings_[q].fixed];
  kv_ = k.tail(n_);
  LinearSolveResult res = solver_->solve(rhs_, kv_);
  if (!res.ok && res.residual < 0 && auto_kind_ && solver_->kind() == LinearSolverKind::cg) {
    // Non-positive curvature: A is indefinite here (compressed springs). LDLᵀ for the rest of
    // the run.
    make_solver(LinearSolverKind::ldlt);
    if (!solver_->factor(a_)) {
      error_ = solver_->error();
      res.ok = false;
      return res;
    }
    kv_ = k.tail(n_);
    const long cg_iters = res.iterations;
    res = solver_->solve(rhs_, kv_);
    res.iterations += cg_iters;
  }
  if (!res.ok) {
    error_ = solver_->error();
    return res;
  }
  k.tail(n_) = kv_;
  k.head(n_) = rx + c_ * kv_;
  return res;
}

void VelocityFormSolver::mk_product(CVecRef r, VecRef out) const {
  const int* ko = k_.outerIndexPtr();
  const int* ki = k_.innerIndexPtr();
  const double* kv = k_.valuePtr();
  const double* m = m_.data();
  const double* x = r.data();
  double* y = out.data();
  const auto row = [&](Index i) {
    double acc = 0.0;
    for (int k = ko[i]; k < ko[i + 1]; ++k) acc += kv[k] * m[ki[k]] * x[ki[k]];
    y[i] = acc;
  };
  if (k_.nonZeros() >= kParallelNonzeros) {
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n_; ++i) row(i);
  } else {
    for (Index i = 0; i < n_; ++i) row(i);
  }
  for (const FixedColumnEntry& e : k_fixed_cols_) y[e.row] += m[e.row] * kv[e.k] * x[e.fixed];
}

void VelocityFormSolver::jacobian_times(CVecRef u, VecRef out) const {
  out.head(n_) = u.tail(n_);
  out.tail(n_).noalias() = k_ * u.head(n_);
  if (velocity_dependent_) out.tail(n_).noalias() += d_ * u.tail(n_);
}

}  // namespace stiffbench
