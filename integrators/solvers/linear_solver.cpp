#include "integrators/solvers/linear_solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <vector>

namespace stiffbench {

const std::vector<std::string>& linear_solver_names() {
  static const std::vector<std::string> names = {"auto", "dense_lu", "sparse_lu", "ldlt",
                                                 "cg",   "bicgstab", "gmres"};
  return names;
}

LinearSolverKind parse_linear_solver(const std::string& s) {
  if (s == "auto") return LinearSolverKind::automatic;
  if (s == "dense_lu") return LinearSolverKind::dense_lu;
  if (s == "sparse_lu") return LinearSolverKind::sparse_lu;
  if (s == "ldlt") return LinearSolverKind::ldlt;
  if (s == "cg") return LinearSolverKind::cg;
  if (s == "bicgstab") return LinearSolverKind::bicgstab;
  if (s == "gmres") return LinearSolverKind::gmres;
  throw BadInput("parameter 'linear_solver': unknown solver '" + s + "'");
}

std::string to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::automatic:
      return "auto";
    case LinearSolverKind::dense_lu:
      return "dense_lu";
    case LinearSolverKind::sparse_lu:
      return "sparse_lu";
    case LinearSolverKind::ldlt:
      return "ldlt";
    case LinearSolverKind::cg:
      return "cg";
    case LinearSolverKind::bicgstab:
      return "bicgstab";
    case LinearSolverKind::gmres:
      return "gmres";
  }
  return "?";
}

bool is_krylov(LinearSolverKind k) {
  return k == LinearSolverKind::cg || k == LinearSolverKind::bicgstab ||
         k == LinearSolverKind::gmres;
}

namespace {

// --- Krylov methods -----------------------------------------------------------------------
// Templates on the operator so that an assembled matrix is applied without std::function; the
// work vectors live in a KrylovWorkspace (resize() is a no-op once the size is right).

// out = M⁻¹ in for the Jacobi preconditioner M = diag(W); identity when diag is empty.
void apply_jacobi(const Vec& diag, CVecRef in, VecRef out) {
  if (diag.size())
    out = in.cwiseQuotient(diag);
  else
    out = in;
}

struct Jacobi {
  const Vec& diag;
  void operator()(CVecRef in, VecRef out) const { apply_jacobi(diag, in, out); }
};

// Preconditioned conjugate gradients (Saad, Iterative Methods, Alg. 9.1).
template <class Op, class Prec>
LinearSolveResult pcg(const Op& op, const Prec& prec, CVecRef b, VecRef x,
                      const LinearSolverOptions& opt, KrylovWorkspace& ws) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  ws.r.resize(n);
  ws.z.resize(n);
  ws.p.resize(n);
  ws.v.resize(n);
  Vec &r = ws.r, &z = ws.z, &p = ws.p, &ap = ws.v;
  op(x, ap);
  r = b - ap;
  prec(r, z);
  p = z;
  double rz = r.dot(z);
  for (int it = 0; it < opt.krylov_max_iter; ++it) {
    res.residual = r.norm() / bnorm;
    if (res.residual <= opt.krylov_tol) return res;
    op(p, ap);
    const double pap = p.dot(ap);
    if (!(pap > 0)) {  // not SPD (or breakdown): CG does not apply
      res.ok = false;
      res.residual = -1;  // marks the breakdown for the caller
      return res;
    }
    const double alpha = rz / pap;
    x += alpha * p;
    r -= alpha * ap;
    prec(r, z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
    ++res.iterations;
  }
  res.residual = r.norm() / bnorm;
  res.ok = res.residual <= opt.krylov_tol;
  return res;
}

// Right-preconditioned BiCGSTAB (van der Vorst 1992; Saad Alg. 7.7).
template <class Op>
LinearSolveResult bicgstab(const Op& op, const Vec& diag, CVecRef b, VecRef x,
                           const LinearSolverOptions& opt, KrylovWorkspace& ws) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  for (Vec* w : {&ws.r, &ws.r0, &ws.p, &ws.v, &ws.s, &ws.t, &ws.ph, &ws.sh}) w->resize(n);
  Vec &r = ws.r, &r0 = ws.r0, &p = ws.p, &v = ws.v, &s = ws.s, &t = ws.t, &ph = ws.ph, &sh = ws.sh;
  op(x, v);
  r = b - v;
  r0 = r;
  p.setZero();
  v.setZero();
  double rho = 1, alpha = 1, omega = 1;
  for (int it = 0; it < opt.krylov_max_iter; ++it) {
    res.residual = r.norm() / bnorm;
    if (res.residual <= opt.krylov_tol) return res;
    const double rho_new = r0.dot(r);
    if (rho_new == 0 || omega == 0) break;  // breakdown
    const double beta = (rho_new / rho) * (alpha / omega);
    rho = rho_new;
    p = r + beta * (p - omega * v);
    apply_jacobi(diag, p, ph);
    op(ph, v);
    const double r0v = r0.dot(v);
    if (r0v == 0) break;
    alpha = rho / r0v;
    s = r - alpha * v;
    if (s.norm() / bnorm <= opt.krylov_tol) {
      x += alpha * ph;
      r = s;
      ++res.iterations;
      continue;
    }
    apply_jacobi(diag, s, sh);
    op(sh, t);
    const double tt = t.dot(t);
    if (tt == 0) break;
    omega = t.dot(s) / tt;
    x += alpha * ph + omega * sh;
    r = s - omega * t;
    ++res.iterations;
  }
  // Confirm with the true residual.
  op(x, v);
  v = b - v;
  res.residual = v.norm() / bnorm;
  res.ok = res.residual <= std::max(opt.krylov_tol, 10 * opt.krylov_tol);
  return res;
}

// Restarted GMRES(m) with right preconditioning and Givens rotations (Saad Alg. 6.11 / 9.5).
template <class Op>
LinearSolveResult gmres(const Op& op, const Vec& diag, CVecRef b, VecRef x,
                        const LinearSolverOptions& opt, KrylovWorkspace& ws) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  const int m = std::max(1, std::min<int>(opt.gmres_restart, static_cast<int>(n)));
  ws.basis.resize(n, m + 1);
  ws.hess.resize(m + 1, m);
  ws.hess.setZero();
  for (Vec* w : {&ws.w, &ws.z, &ws.r, &ws.update}) w->resize(n);
  ws.cs.resize(m);
  ws.sn.resize(m);
  ws.g.resize(m + 1);
  Mat &v = ws.basis, &h = ws.hess;
  Vec &cs = ws.cs, &sn = ws.sn, &g = ws.g, &w = ws.w, &z = ws.z, &r = ws.r;
  bool converged = false;
  while (res.iterations < opt.krylov_max_iter) {
    op(x, w);
    r = b - w;
    const double beta = r.norm();
    res.residual = beta / bnorm;
    if (res.residual <= opt.krylov_tol) return res;
    v.col(0) = r / beta;
    g.setZero();
    g[0] = beta;
    int k = 0;
    for (; k < m && res.iterations < opt.krylov_max_iter; ++k) {
      apply_jacobi(diag, v.col(k), z);
      op(z, w);
      for (int i = 0; i <= k; ++i) {  // modified Gram–Schmidt
        h(i, k) = w.dot(v.col(i));
        w -= h(i, k) * v.col(i);
      }
      h(k + 1, k) = w.norm();
      if (h(k + 1, k) != 0) v.col(k + 1) = w / h(k + 1, k);
      for (int i = 0; i < k; ++i) {  // apply previous rotations
        const double tmp = cs[i] * h(i, k) + sn[i] * h(i + 1, k);
        h(i + 1, k) = -sn[i] * h(i, k) + cs[i] * h(i + 1, k);
        h(i, k) = tmp;
      }
      const double denom = std::hypot(h(k, k), h(k + 1, k));
      cs[k] = h(k, k) / denom;
      sn[k] = h(k + 1, k) / denom;
      h(k, k) = denom;
      h(k + 1, k) = 0;
      g[k + 1] = -sn[k] * g[k];
      g[k] = cs[k] * g[k];
      ++res.iterations;
      if (std::abs(g[k + 1]) / bnorm <= opt.krylov_tol) {
        converged = true;
        ++k;
        break;
      }
    }
    // Solve the k×k upper-triangular system and update x = x + M⁻¹ V y.
    ws.y = g.head(k);
    h.topLeftCorner(k, k).triangularView<Eigen::Upper>().solveInPlace(ws.y);
    ws.update.noalias() = v.leftCols(k) * ws.y;
    apply_jacobi(diag, ws.update, z);
    x += z;
    if (converged) {
      // The recursive residual estimate is the convergence test (as in CG): with a matrix-free
      // finite-difference operator the true residual cannot go below the products' ~√eps
      // relative accuracy, and the outer Newton iteration absorbs that.
      res.residual = std::abs(g[k]) / bnorm;
      return res;
    }
  }
  op(x, w);
  w = b - w;
  res.residual = w.norm() / bnorm;
  res.ok = res.residual <= opt.krylov_tol;
  return res;
}

template <class Op>
LinearSolveResult krylov_dispatch(LinearSolverKind kind, const Op& op, const Vec& diag, CVecRef b,
                                  VecRef x, const LinearSolverOptions& opt, KrylovWorkspace& ws) {
  switch (kind) {
    case LinearSolverKind::cg:
      return pcg(op, Jacobi{diag}, b, x, opt, ws);
    case LinearSolverKind::bicgstab:
      return bicgstab(op, diag, b, x, opt, ws);
    case LinearSolverKind::gmres:
      return gmres(op, diag, b, x, opt, ws);
    default:
      throw std::logic_error("krylov_solve: not a Krylov solver");
  }
}

// ‖W - Wᵀ‖ > 1e-12 ‖W‖ (an O(nnz) check with a transposed copy: only when the caller does not
// know that W is symmetric).
bool asymmetric(const SparseMat& w) {
  const double asym = (w - SparseMat(w.transpose())).norm();
  return asym > 1e-12 * w.norm();
}

// --- Solver objects ------------------------------------------------------------------------

class DenseLu final : public LinearSolver {
 public:
  void analyze(const SparseMat& p) override { dense_.resize(p.rows(), p.cols()); }
  bool factor(const SparseMat& w) override {
    dense_ = w;
    lu_.compute(dense_);
    // PartialPivLU does not report singularity: look for a zero or non-finite pivot (the
    // determinant itself overflows for large well-conditioned matrices).
    const auto pivots = lu_.matrixLU().diagonal();
    const bool ok = pivots.allFinite() && (pivots.array() != 0.0).all();
    if (!ok) error_ = "dense_lu: matrix singular (zero or non-finite pivot)";
    return ok;
  }
  LinearSolveResult solve(CVecRef b, VecRef x) override {
    x = lu_.solve(b);
    return {};
  }
  LinearSolverKind kind() const override { return LinearSolverKind::dense_lu; }

 private:
  Mat dense_;
  Eigen::PartialPivLU<Mat> lu_;
};

class SparseLu final : public LinearSolver {
 public:
  void analyze(const SparseMat& p) override {
    SparseMat c = p;
    c.makeCompressed();
    lu_.analyzePattern(c);
  }
  bool factor(const SparseMat& w) override {
    lu_.factorize(w);
    if (lu_.info() != Eigen::Success) error_ = "sparse_lu: " + lu_.lastErrorMessage();
    return lu_.info() == Eigen::Success;
  }
  LinearSolveResult solve(CVecRef b, VecRef x) override {
    x = lu_.solve(b);
    return {lu_.info() == Eigen::Success, 0, 0};
  }
  LinearSolverKind kind() const override { return LinearSolverKind::sparse_lu; }

 private:
  Eigen::SparseLU<SparseMat, Eigen::COLAMDOrdering<int>> lu_;
};

// Sparse LDLᵀ of a symmetric matrix: approximate minimum degree ordering (Eigen's AMD) and the
// elimination tree once per pattern (analyze), then an up-looking numeric factorisation row by
// row (the LDL algorithm of Davis, ACM TOMS 31, 2005) into storage sized by the symbolic pass,
// so factor() and solve() never allocate. No pivoting: fine for the SPD and quasi-definite
// matrices of the implicit methods; a zero pivot is reported.
class Ldlt final : public LinearSolver {
 public:
  explicit Ldlt(bool symmetric) : symmetric_(symmetric) {}

  void analyze(const SparseMat& p) override {
    const Index n = p.cols();
    n_ = n;
    // Ordering on the pattern of A + Aᵀ; new index of row/column i: perm_[i].
    SparseMat sym = p;
    for (Index k = 0; k < sym.nonZeros(); ++k) sym.valuePtr()[k] = 1.0;
    sym = SparseMat(sym.transpose()) + sym;
    Eigen::AMDOrdering<int> amd;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
    amd(sym, pinv);
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm = pinv.inverse();
    perm_.assign(perm.indices().data(), perm.indices().data() + n);
    // Upper triangle of P A Pᵀ (column-major) and where each entry of A goes in it (-1: the
    // mirror entry below the diagonal, not used).
    std::vector<Eigen::Triplet<double>> trips;
    for (Index c = 0; c < n; ++c)
      for (SparseMat::InnerIterator it(p, c); it; ++it) {
        const int i = perm_[static_cast<std::size_t>(it.row())];
        const int j = perm_[static_cast<std::size_t>(c)];
        if (i <= j) trips.emplace_back(i, j, 0.0);
      }
    for (Index i = 0; i < n; ++i) trips.emplace_back(i, i, 0.0);
    upper_.resize(n, n);
    upper_.setFromTriplets(trips.begin(), trips.end());
    upper_.makeCompressed();
    map_.assign(static_cast<std::size_t>(p.nonZeros()), -1);
    pattern_outer_.assign(p.outerIndexPtr(), p.outerIndexPtr() + p.outerSize() + 1);
    for (Index c = 0; c < n; ++c)
      for (int k = p.outerIndexPtr()[c]; k < p.outerIndexPtr()[c + 1]; ++k) {
        const int i = perm_[static_cast<std::size_t>(p.innerIndexPtr()[k])];
        const int j = perm_[static_cast<std::size_t>(c)];
        if (i > j) continue;
        const int* b = upper_.innerIndexPtr() + upper_.outerIndexPtr()[j];
        const int* e = upper_.innerIndexPtr() + upper_.outerIndexPtr()[j + 1];
        map_[static_cast<std::size_t>(k)] =
            static_cast<int>(std::lower_bound(b, e, i) - upper_.innerIndexPtr());
      }
    // Elimination tree and column counts of L.
    const std::size_t nu = static_cast<std::size_t>(n);
    parent_.assign(nu, -1);
    lnz_.assign(nu, 0);
    flag_.assign(nu, -1);
    for (int k = 0; k < n; ++k) {
      flag_[static_cast<std::size_t>(k)] = k;
      for (int q = upper_.outerIndexPtr()[k]; q < upper_.outerIndexPtr()[k + 1]; ++q) {
        for (int i = upper_.innerIndexPtr()[q]; i < k && flag_[static_cast<std::size_t>(i)] != k;
             i = parent_[static_cast<std::size_t>(i)]) {
          if (parent_[static_cast<std::size_t>(i)] == -1) parent_[static_cast<std::size_t>(i)] = k;
          ++lnz_[static_cast<std::size_t>(i)];
          flag_[static_cast<std::size_t>(i)] = k;
        }
      }
    }
    lp_.assign(nu + 1, 0);
    for (std::size_t k = 0; k < nu; ++k) lp_[k + 1] = lp_[k] + lnz_[k];
    li_.assign(static_cast<std::size_t>(lp_[nu]), 0);
    lx_.assign(static_cast<std::size_t>(lp_[nu]), 0.0);
    d_.assign(nu, 0.0);
    y_.assign(nu, 0.0);
    stack_.assign(nu, 0);
    work_.resize(n);
  }

  bool factor(const SparseMat& w) override {
    // LDLᵀ reads one triangle: refuse a non-symmetric W instead of solving a different system.
    if (!symmetric_ && asymmetric(w)) {
      error_ = "ldlt: the matrix is not symmetric (use sparse_lu, bicgstab or gmres)";
      return false;
    }
    double* u = upper_.valuePtr();
    std::fill(u, u + upper_.nonZeros(), 0.0);
    const double* wv = w.valuePtr();
    for (std::size_t k = 0; k < map_.size(); ++k)
      if (map_[k] >= 0) u[map_[k]] = wv[k];
    const int* uo = upper_.outerIndexPtr();
    const int* ui = upper_.innerIndexPtr();
    const int n = static_cast<int>(n_);
    for (int k = 0; k < n; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      y_[ku] = 0.0;
      int top = n;
      flag_[ku] = k;
      lnz_[ku] = 0;
      for (int q = uo[k]; q < uo[k + 1]; ++q) {
        int i = ui[q];
        y_[static_cast<std::size_t>(i)] += u[q];
        int len = 0;
        for (; flag_[static_cast<std::size_t>(i)] != k; i = parent_[static_cast<std::size_t>(i)]) {
          stack_[static_cast<std::size_t>(len++)] = i;
          flag_[static_cast<std::size_t>(i)] = k;
        }
        while (len > 0)
          stack_[static_cast<std::size_t>(--top)] = stack_[static_cast<std::size_t>(--len)];
      }
      d_[ku] = y_[ku];
      y_[ku] = 0.0;
      for (; top < n; ++top) {
        const auto i = static_cast<std::size_t>(stack_[static_cast<std::size_t>(top)]);
        const double yi = y_[i];
        y_[i] = 0.0;
        const int end = lp_[i] + lnz_[i];
        for (int q = lp_[i]; q < end; ++q)
          y_[static_cast<std::size_t>(li_[static_cast<std::size_t>(q)])] -=
              lx_[static_cast<std::size_t>(q)] * yi;
        const double l = yi / d_[i];
        d_[ku] -= l * yi;
        li_[static_cast<std::size_t>(end)] = k;
        lx_[static_cast<std::size_t>(end)] = l;
        ++lnz_[i];
      }
      if (!(d_[ku] != 0.0) || !std::isfinite(d_[ku])) {
        error_ = "ldlt: zero or non-finite pivot (matrix singular)";
        return false;
      }
    }
    return true;
  }

  LinearSolveResult solve(CVecRef b, VecRef x) override {
    const std::size_t n = static_cast<std::size_t>(n_);
    double* z = work_.data();
    for (std::size_t i = 0; i < n; ++i) z[perm_[i]] = b[static_cast<Index>(i)];
    for (std::size_t j = 0; j < n; ++j)  // L z = Pb
      for (int q = lp_[j]; q < lp_[j] + lnz_[j]; ++q)
        z[li_[static_cast<std::size_t>(q)]] -= lx_[static_cast<std::size_t>(q)] * z[j];
    for (std::size_t j = 0; j < n; ++j) z[j] /= d_[j];
    for (std::size_t j = n; j-- > 0;)  // Lᵀ
      for (int q = lp_[j]; q < lp_[j] + lnz_[j]; ++q)
        z[j] -= lx_[static_cast<std::size_t>(q)] * z[li_[static_cast<std::size_t>(q)]];
    for (std::size_t i = 0; i < n; ++i) x[static_cast<Index>(i)] = z[perm_[i]];
    return {};
  }
  LinearSolverKind kind() const override { return LinearSolverKind::ldlt; }

 private:
  bool symmetric_;
  Index n_ = 0;
  std::vector<int> perm_, map_, pattern_outer_, parent_, lnz_, flag_, lp_, li_, stack_;
  std::vector<double> lx_, d_, y_;
  SparseMat upper_;
  Vec work_;
};

class Krylov final : public LinearSolver {
 public:
  Krylov(LinearSolverKind kind, LinearSolverOptions opt) : kind_(kind), opt_(opt) {
    if (opt_.preconditioner == PreconditionerKind::ichol && kind_ != LinearSolverKind::cg)
      throw BadInput("preconditioner=ichol needs linear_solver=cg");
  }
  void analyze(const SparseMat& p) override {
    if (opt_.preconditioner == PreconditionerKind::ichol) ichol_.analyzePattern(p);
  }
  bool factor(const SparseMat& w) override {
    w_ = &w;
    if (kind_ == LinearSolverKind::cg && !opt_.symmetric && asymmetric(w)) {
      error_ = "cg: the matrix is not symmetric (use bicgstab, gmres or sparse_lu)";
      return false;
    }
    if (opt_.preconditioner == PreconditionerKind::jacobi) {
      diag_ = w.diagonal();
      for (Index i = 0; i < diag_.size(); ++i)
        if (diag_[i] == 0) diag_[i] = 1;  // no scaling where the diagonal vanishes
    } else {
      diag_.resize(0);
    }
    if (opt_.preconditioner == PreconditionerKind::ichol) {
      ichol_.factorize(w);
      if (ichol_.info() != Eigen::Success) {
        error_ = "cg: incomplete Cholesky failed (matrix not positive definite?)";
        return false;
      }
    }
    return true;
  }
  LinearSolveResult solve(CVecRef b, VecRef x) override {
    const SparseMat& w = *w_;
    LinearSolveResult r;
    if (product_) {
      r = run(product_, b, x);
    } else if (opt_.symmetric) {
      const auto op = [&w](CVecRef in, VecRef out) { symmetric_product(w, in, out); };
      r = run(op, b, x);
    } else {
      const auto op = [&w](CVecRef in, VecRef out) { out.noalias() = w * in; };
      r = run(op, b, x);
    }
    if (!r.ok)
      error_ = r.residual < 0
                   ? to_string(kind_) +
                         ": the matrix is not positive definite (a direction of "
                         "non-positive curvature); use ldlt or sparse_lu"
                   : to_string(kind_) + ": no convergence to " + std::to_string(opt_.krylov_tol) +
                         " in " + std::to_string(opt_.krylov_max_iter) + " iterations";
    return r;
  }
  LinearSolverKind kind() const override { return kind_; }
  void set_tolerance(double tol) override { opt_.krylov_tol = tol; }
  void use_product(LinearOperator product) override { product_ = std::move(product); }

 private:
  template <class Op>
  LinearSolveResult run(const Op& op, CVecRef b, VecRef x) {
    if (opt_.preconditioner == PreconditionerKind::ichol) {
      const auto prec = [this](CVecRef in, VecRef out) { out = ichol_.solve(in); };
      return pcg(op, prec, b, x, opt_, ws_);
    }
    return krylov_dispatch(kind_, op, diag_, b, x, opt_, ws_);
  }

  LinearSolverKind kind_;
  LinearSolverOptions opt_;
  const SparseMat* w_ = nullptr;
  Vec diag_;
  KrylovWorkspace ws_;
  LinearOperator product_;
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> ichol_;
};

}  // namespace

void symmetric_product(const SparseMat& w, CVecRef in, VecRef out) {
  const Index n = w.outerSize();
  const int* outer = w.outerIndexPtr();
  const int* inner = w.innerIndexPtr();
  const double* val = w.valuePtr();
  const double* x = in.data();
  double* y = out.data();
  const auto row = [&](Index i) {
    double acc = 0.0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) acc += val[k] * x[inner[k]];
    y[i] = acc;
  };
  if (w.nonZeros() >= 200000) {
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) row(i);
  } else {
    for (Index i = 0; i < n; ++i) row(i);
  }
}

LinearSolveResult krylov_solve(LinearSolverKind kind, const LinearOperator& op, const Vec& diag,
                               CVecRef b, VecRef x, const LinearSolverOptions& opt,
                               KrylovWorkspace& ws) {
  return krylov_dispatch(kind, op, diag, b, x, opt, ws);
}

bool automatic_is_dense(const LinearSolverOptions& opt, Index n) {
  return n <= opt.dense_small ||
         (n <= opt.dense_max && opt.pattern_density >= kSparsePatternDensity);
}

std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& opt, Index n) {
  LinearSolverKind k = opt.kind;
  if (k == LinearSolverKind::automatic)
    k = automatic_is_dense(opt, n) ? LinearSolverKind::dense_lu : LinearSolverKind::sparse_lu;
  switch (k) {
    case LinearSolverKind::dense_lu:
      return std::make_unique<DenseLu>();
    case LinearSolverKind::sparse_lu:
      return std::make_unique<SparseLu>();
    case LinearSolverKind::ldlt:
      return std::make_unique<Ldlt>(opt.symmetric);
    default:
      return std::make_unique<Krylov>(k, opt);
  }
}

}  // namespace stiffbench
