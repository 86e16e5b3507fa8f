#include "integrators/implicit/linear_solver.hpp"

#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <cmath>

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

// out = M⁻¹ in for the Jacobi preconditioner M = diag(W); identity when diag is empty.
void apply_jacobi(const Vec& diag, CVecRef in, Vec& out) {
  if (diag.size())
    out = in.cwiseQuotient(diag);
  else
    out = in;
}

// Preconditioned conjugate gradients (Saad, Iterative Methods, Alg. 9.1).
LinearSolveResult pcg(const LinearOperator& op, const Vec& diag, CVecRef b, VecRef x,
                      const LinearSolverOptions& opt) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  Vec r(n), z(n), p(n), ap(n);
  op(x, ap);
  r = b - ap;
  apply_jacobi(diag, r, z);
  p = z;
  double rz = r.dot(z);
  for (int it = 0; it < opt.krylov_max_iter; ++it) {
    res.residual = r.norm() / bnorm;
    if (res.residual <= opt.krylov_tol) return res;
    op(p, ap);
    const double pap = p.dot(ap);
    if (!(pap > 0)) {  // not SPD (or breakdown): CG does not apply
      res.ok = false;
      return res;
    }
    const double alpha = rz / pap;
    x += alpha * p;
    r -= alpha * ap;
    apply_jacobi(diag, r, z);
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
LinearSolveResult bicgstab(const LinearOperator& op, const Vec& diag, CVecRef b, VecRef x,
                           const LinearSolverOptions& opt) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  Vec r(n), r0(n), p(n), v(n), s(n), t(n), ph(n), sh(n);
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
  res.residual = (b - v).norm() / bnorm;
  res.ok = res.residual <= std::max(opt.krylov_tol, 10 * opt.krylov_tol);
  return res;
}

// Restarted GMRES(m) with right preconditioning and Givens rotations (Saad Alg. 6.11 / 9.5).
LinearSolveResult gmres(const LinearOperator& op, const Vec& diag, CVecRef b, VecRef x,
                        const LinearSolverOptions& opt) {
  const Index n = b.size();
  const double bnorm = b.norm();
  LinearSolveResult res;
  if (bnorm == 0) {
    x.setZero();
    return res;
  }
  const int m = std::max(1, std::min<int>(opt.gmres_restart, static_cast<int>(n)));
  Mat v(n, m + 1), h = Mat::Zero(m + 1, m);
  Vec cs(m), sn(m), g(m + 1), w(n), z(n), r(n);
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
    const Vec y = h.topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(g.head(k));
    Vec update = v.leftCols(k) * y;
    apply_jacobi(diag, update, z);
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
  res.residual = (b - w).norm() / bnorm;
  res.ok = res.residual <= opt.krylov_tol;
  return res;
}

// --- Solver objects ------------------------------------------------------------------------

class DenseLu final : public LinearSolver {
 public:
  void analyze(const SparseMat& p) override { dense_.resize(p.rows(), p.cols()); }
  bool factor(const SparseMat& w) override {
    dense_ = Mat(w);
    lu_.compute(dense_);
    // PartialPivLU does not report singularity: look for a zero or non-finite pivot (the
    // determinant itself overflows for large well-conditioned matrices).
    const auto pivots = lu_.matrixLU().diagonal();
    return pivots.allFinite() && (pivots.array() != 0.0).all();
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

class Ldlt final : public LinearSolver {
 public:
  void analyze(const SparseMat& p) override { ldlt_.analyzePattern(p); }
  bool factor(const SparseMat& w) override {
    // LDLᵀ reads one triangle: refuse a non-symmetric W instead of solving a different system.
    const double asym = (w - SparseMat(w.transpose())).norm();
    if (asym > 1e-12 * w.norm()) return false;
    ldlt_.factorize(w);
    return ldlt_.info() == Eigen::Success;
  }
  LinearSolveResult solve(CVecRef b, VecRef x) override {
    x = ldlt_.solve(b);
    return {ldlt_.info() == Eigen::Success, 0, 0};
  }
  LinearSolverKind kind() const override { return LinearSolverKind::ldlt; }

 private:
  Eigen::SimplicialLDLT<SparseMat> ldlt_;
};

class Krylov final : public LinearSolver {
 public:
  Krylov(LinearSolverKind kind, LinearSolverOptions opt) : kind_(kind), opt_(opt) {}
  void analyze(const SparseMat&) override {}
  bool factor(const SparseMat& w) override {
    w_ = &w;
    if (opt_.preconditioner == PreconditionerKind::jacobi) {
      diag_ = w.diagonal();
      for (Index i = 0; i < diag_.size(); ++i)
        if (diag_[i] == 0) diag_[i] = 1;  // no scaling where the diagonal vanishes
    } else {
      diag_.resize(0);
    }
    if (kind_ == LinearSolverKind::cg) {
      const double asym = (w - SparseMat(w.transpose())).norm();
      if (asym > 1e-12 * w.norm()) return false;  // CG needs a symmetric matrix
    }
    return true;
  }
  LinearSolveResult solve(CVecRef b, VecRef x) override {
    const SparseMat& w = *w_;
    const LinearOperator op = [&w](CVecRef in, VecRef out) { out.noalias() = w * in; };
    return krylov_solve(kind_, op, diag_, b, x, opt_);
  }
  LinearSolverKind kind() const override { return kind_; }

 private:
  LinearSolverKind kind_;
  LinearSolverOptions opt_;
  const SparseMat* w_ = nullptr;
  Vec diag_;
};

}  // namespace

LinearSolveResult krylov_solve(LinearSolverKind kind, const LinearOperator& op, const Vec& diag,
                               CVecRef b, VecRef x, const LinearSolverOptions& opt) {
  switch (kind) {
    case LinearSolverKind::cg:
      return pcg(op, diag, b, x, opt);
    case LinearSolverKind::bicgstab:
      return bicgstab(op, diag, b, x, opt);
    case LinearSolverKind::gmres:
      return gmres(op, diag, b, x, opt);
    default:
      throw std::logic_error("krylov_solve: not a Krylov solver");
  }
}

std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& opt, Index n) {
  LinearSolverKind k = opt.kind;
  if (k == LinearSolverKind::automatic)
    k = n <= opt.dense_max ? LinearSolverKind::dense_lu : LinearSolverKind::sparse_lu;
  switch (k) {
    case LinearSolverKind::dense_lu:
      return std::make_unique<DenseLu>();
    case LinearSolverKind::sparse_lu:
      return std::make_unique<SparseLu>();
    case LinearSolverKind::ldlt:
      return std::make_unique<Ldlt>();
    default:
      return std::make_unique<Krylov>(k, opt);
  }
}

}  // namespace stiffbench
