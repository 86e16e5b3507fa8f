#include "integrators/solvers/sparse_refactor_lu.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cmath>
#include <complex>

namespace stiffbench {

template <class Scalar>
void SparseRefactorLu<Scalar>::analyze(const SparseM& pattern) {
  n_ = static_cast<int>(pattern.cols());
  const auto nu = static_cast<std::size_t>(n_);
  a_outer_.assign(pattern.outerIndexPtr(), pattern.outerIndexPtr() + n_ + 1);
  a_inner_.assign(pattern.innerIndexPtr(), pattern.innerIndexPtr() + pattern.nonZeros());
  // COLAMD on the pattern (Eigen's ordering takes a real matrix): column i of A is factored
  // at step perm[i].
  Eigen::SparseMatrix<double> p(pattern.rows(), pattern.cols());
  p.reserve(pattern.nonZeros());
  {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(a_inner_.size());
    for (int c = 0; c < n_; ++c)
      for (int k = a_outer_[static_cast<std::size_t>(c)];
           k < a_outer_[static_cast<std::size_t>(c) + 1]; ++k)
        t.emplace_back(a_inner_[static_cast<std::size_t>(k)], c, 1.0);
    p.setFromTriplets(t.begin(), t.end());
  }
  p.makeCompressed();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::COLAMDOrdering<int>()(p, perm);
  q_.assign(nu, 0);
  for (int i = 0; i < n_; ++i) q_[static_cast<std::size_t>(perm.indices()[i])] = i;
  pinv_.assign(nu, -1);
  lp_.assign(nu + 1, 0);
  up_.assign(nu + 1, 0);
  xi_.assign(nu, 0);
  pstack_.assign(nu, 0);
  mark_.assign(nu, 0);
  stamp_ = 0;
  x_.assign(nu, Scalar(0));
  li_.clear();
  ui_.clear();
  lx_.clear();
  ux_.clear();
  factored_ = false;
  repivots_ = 0;
}

template <class Scalar>
bool SparseRefactorLu<Scalar>::factor(const SparseM& a) {
  if (factored_ && refactor(a)) return true;
  if (factored_) ++repivots_;
  factored_ = pivoting_factor(a);
  return factored_;
}

// xi_[top..n) = the nodes (rows of A, in the original numbering) reachable from A(:, col) in the
// graph of the columns of L found so far (row j leads to the rows of L(:, pinv_[j])), in
// topological order (non-recursive depth-first search; cs_reach / cs_dfs).
template <class Scalar>
int SparseRefactorLu<Scalar>::reach(const SparseM& a, int col) {
  ++stamp_;
  int top = n_;
  const int* ai = a.innerIndexPtr();
  for (int p = a.outerIndexPtr()[col]; p < a.outerIndexPtr()[col + 1]; ++p) {
    if (mark_[static_cast<std::size_t>(ai[p])] == stamp_) continue;
    int head = 0;
    xi_[0] = ai[p];
    while (head >= 0) {
      const int j = xi_[static_cast<std::size_t>(head)];
      const int jnew = pinv_[static_cast<std::size_t>(j)];
      if (mark_[static_cast<std::size_t>(j)] != stamp_) {
        mark_[static_cast<std::size_t>(j)] = stamp_;
        pstack_[static_cast<std::size_t>(head)] =
            jnew < 0 ? 0 : lp_[static_cast<std::size_t>(jnew)];
      }
      bool done = true;
      const int p2 = jnew < 0 ? 0 : lp_[static_cast<std::size_t>(jnew) + 1];
      for (int q = pstack_[static_cast<std::size_t>(head)]; q < p2; ++q) {
        const int i = li_[static_cast<std::size_t>(q)];
        if (mark_[static_cast<std::size_t>(i)] == stamp_) continue;
        pstack_[static_cast<std::size_t>(head)] = q;
        xi_[static_cast<std::size_t>(++head)] = i;
        done = false;
        break;
      }
      if (done) {
        --head;
        xi_[static_cast<std::size_t>(--top)] = j;
      }
    }
  }
  return top;
}

// cs_lu (Davis 2006) with L's rows in the original numbering while it is built, renumbered by
// pinv_ at the end.
template <class Scalar>
bool SparseRefactorLu<Scalar>::pivoting_factor(const SparseM& a) {
  const auto nu = static_cast<std::size_t>(n_);
  std::fill(pinv_.begin(), pinv_.end(), -1);
  std::fill(x_.begin(), x_.end(), Scalar(0));
  li_.clear();
  lx_.clear();
  ui_.clear();
  ux_.clear();
  const int* ai = a.innerIndexPtr();
  const Scalar* av = a.valuePtr();
  for (int k = 0; k < n_; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    lp_[ku] = static_cast<int>(li_.size());
    up_[ku] = static_cast<int>(ui_.size());
    const int col = q_[ku];
    // x = L \ A(:, col) over the reach.
    const int top = reach(a, col);
    for (int p = top; p < n_; ++p)
      x_[static_cast<std::size_t>(xi_[static_cast<std::size_t>(p)])] = 0;
    for (int p = a.outerIndexPtr()[col]; p < a.outerIndexPtr()[col + 1]; ++p)
      x_[static_cast<std::size_t>(ai[p])] = av[p];
    for (int px = top; px < n_; ++px) {
      const auto j = static_cast<std::size_t>(xi_[static_cast<std::size_t>(px)]);
      const int jj = pinv_[j];
      if (jj < 0) continue;
      const Scalar xj = x_[j];
      for (int q = lp_[static_cast<std::size_t>(jj)] + 1; q < lp_[static_cast<std::size_t>(jj) + 1];
           ++q)
        x_[static_cast<std::size_t>(li_[static_cast<std::size_t>(q)])] -=
            lx_[static_cast<std::size_t>(q)] * xj;
    }
    // Pivot: the largest candidate, or the diagonal if it is at least diag_tol of that.
    int ipiv = -1;
    double amax = -1;
    for (int p = top; p < n_; ++p) {
      const int i = xi_[static_cast<std::size_t>(p)];
      const auto iu = static_cast<std::size_t>(i);
      if (pinv_[iu] < 0) {
        const double t = std::abs(x_[iu]);
        if (t > amax) {
          amax = t;
          ipiv = i;
        }
      } else {
        ui_.push_back(pinv_[iu]);
        ux_.push_back(x_[iu]);
      }
    }
    if (ipiv < 0 || !(amax > 0) || !std::isfinite(amax)) return false;
    const auto cu = static_cast<std::size_t>(col);
    if (pinv_[cu] < 0 && std::abs(x_[cu]) >= amax * diag_tol) ipiv = col;
    const Scalar pivot = x_[static_cast<std::size_t>(ipiv)];
    ui_.push_back(k);
    ux_.push_back(pivot);
    pinv_[static_cast<std::size_t>(ipiv)] = k;
    li_.push_back(ipiv);
    lx_.push_back(Scalar(1));
    for (int p = top; p < n_; ++p) {
      const auto i = static_cast<std::size_t>(xi_[static_cast<std::size_t>(p)]);
      if (pinv_[i] < 0) {
        li_.push_back(static_cast<int>(i));
        lx_.push_back(x_[i] / pivot);
      }
      x_[i] = 0;
    }
  }
  lp_[nu] = static_cast<int>(li_.size());
  up_[nu] = static_cast<int>(ui_.size());
  for (int& i : li_) i = pinv_[static_cast<std::size_t>(i)];
  a_step_row_.resize(a_inner_.size());
  for (std::size_t p = 0; p < a_inner_.size(); ++p)
    a_step_row_[p] = pinv_[static_cast<std::size_t>(a_inner_[p])];
  return true;
}

// The elimination of the last pivoting factorisation replayed on new values, in P A Q's row
// numbering: U(:, k)'s entries are stored in the topological order in which the triangular solve
// met them, so the same order of operations gives the same result as a search would.
template <class Scalar>
bool SparseRefactorLu<Scalar>::refactor(const SparseM& a) {
  const Scalar* av = a.valuePtr();
  Scalar* __restrict x = x_.data();
  const int* __restrict li = li_.data();
  Scalar* __restrict lx = lx_.data();
  const int* __restrict ui = ui_.data();
  Scalar* __restrict ux = ux_.data();
  const int* lp = lp_.data();
  const int* up = up_.data();
  const int* arow = a_step_row_.data();
  const double tol2 = refactor_tol * refactor_tol;
  for (int k = 0; k < n_; ++k) {
    const int col = q_[static_cast<std::size_t>(k)];
    for (int p = a_outer_[static_cast<std::size_t>(col)];
         p < a_outer_[static_cast<std::size_t>(col) + 1]; ++p)
      x[arow[p]] = av[p];
    const int uend = up[k + 1] - 1;  // U(k, k) is last
    for (int p = up[k]; p < uend; ++p) {
      const int j = ui[p];
      const Scalar u = x[j];
      x[j] = 0;
      ux[p] = u;
      if (u == Scalar(0)) continue;  // x -= L(:, j)·0 changes nothing
      for (int q = lp[j] + 1; q < lp[j + 1]; ++q) x[li[q]] -= lx[q] * u;
    }
    const Scalar pivot = x[k];
    x[k] = 0;
    ux[uend] = pivot;
    double below = 0;  // squared magnitudes
    for (int q = lp[k] + 1; q < lp[k + 1]; ++q) below = std::max(below, std::norm(x[li[q]]));
    const double ap = std::norm(pivot);
    if (!(ap > 0) || !std::isfinite(ap) || ap < tol2 * below) {
      std::fill(x_.begin(), x_.end(), Scalar(0));
      return false;
    }
    const Scalar inv = Scalar(1) / pivot;
    for (int q = lp[k] + 1; q < lp[k + 1]; ++q) {
      const int r = li[q];
      lx[q] = x[r] * inv;
      x[r] = 0;
    }
  }
  return true;
}

template <class Scalar>
void SparseRefactorLu<Scalar>::solve(const CVector& b, CVector& out) {
  Scalar* y = x_.data();
  for (int i = 0; i < n_; ++i) y[pinv_[static_cast<std::size_t>(i)]] = b[i];
  for (int k = 0; k < n_; ++k) {  // L y = P b
    const Scalar yk = y[k];
    for (int q = lp_[static_cast<std::size_t>(k)] + 1; q < lp_[static_cast<std::size_t>(k) + 1];
         ++q)
      y[li_[static_cast<std::size_t>(q)]] -= lx_[static_cast<std::size_t>(q)] * yk;
  }
  for (int k = n_ - 1; k >= 0; --k) {  // U z = y
    const int uend = up_[static_cast<std::size_t>(k) + 1] - 1;
    const Scalar zk = y[k] / ux_[static_cast<std::size_t>(uend)];
    y[k] = zk;
    for (int p = up_[static_cast<std::size_t>(k)]; p < uend; ++p)
      y[ui_[static_cast<std::size_t>(p)]] -= ux_[static_cast<std::size_t>(p)] * zk;
  }
  out.resize(n_);
  for (int k = 0; k < n_; ++k) {
    out[q_[static_cast<std::size_t>(k)]] = y[k];
    y[k] = 0;
  }
}

template class SparseRefactorLu<double>;
template class SparseRefactorLu<std::complex<double>>;

}  // namespace stiffbench
