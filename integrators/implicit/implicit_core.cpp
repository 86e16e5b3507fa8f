#include "integrators/implicit/implicit_core.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace stiffbench {

namespace {

constexpr double kSqrtEps = 1.4901161193847656e-08;
constexpr double kMatrixFreeKrylovTol = 1e-7;

double weighted_norm(CVecRef v, CVecRef z) {
  double m = 0;
  for (Index i = 0; i < v.size(); ++i) m = std::max(m, std::abs(v[i]) / (1.0 + std::abs(z[i])));
  return m;
}

}  // namespace

std::vector<ParamSpec> implicit_param_specs(bool with_newton) {
  using P = ParamType;
  std::vector<ParamSpec> specs;
  if (with_newton) {
    specs.push_back({"newton",
                     P::text,
                     "modified",
                     "Jacobian reuse in Newton: full (every iterate), modified (once per step), "
                     "frozen (across steps until a failure)",
                     {"full", "modified", "frozen"}});
    specs.push_back({"newton_tol", P::real, "1e-12",
                     "Newton tolerance on residual or update (weighted max-norm); each step may "
                     "carry an error of this order"});
    specs.push_back({"newton_max_iter", P::integer, "10", "Newton iterations per stage"});
  }
  specs.push_back({"jacobian",
                   P::text,
                   "auto",
                   "analytic, fd_dense, fd_colored (column-grouped over the model's pattern) or "
                   "matrix_free (Krylov solvers only); auto: analytic where provided, else "
                   "fd_colored over the model's pattern, else fd_dense up to 200 unknowns and "
                   "matrix_free with gmres above",
                   {"auto", "analytic", "fd_dense", "fd_colored", "matrix_free"}});
  specs.push_back(
      {"linear_solver", P::text, "auto",
       "auto (dense_lu up to 200 unknowns, sparse_lu above), dense_lu, sparse_lu, ldlt, "
       "cg, bicgstab, gmres",
       linear_solver_names()});
  specs.push_back({"preconditioner",
                   P::text,
                   "auto",
                   "Krylov preconditioner: jacobi, none; auto: jacobi (none when matrix-free)",
                   {"auto", "jacobi", "none"}});
  specs.push_back({"krylov_tol", P::real, "1e-12",
                   "relative residual of Krylov solves (at least 1e-7 when matrix-free)"});
  specs.push_back({"krylov_max_iter", P::integer, "1000", "Krylov iterations per solve"});
  specs.push_back({"gmres_restart", P::integer, "50", "GMRES restart length"});
  return specs;
}

ImplicitOptions read_implicit_options(const Params& p, bool with_newton) {
  ImplicitOptions o;
  if (with_newton) {
    const std::string& n = p.text("newton");
    o.newton = n == "full"     ? NewtonMode::full
               : n == "frozen" ? NewtonMode::frozen
                               : NewtonMode::modified;
    o.newton_tol = p.real("newton_tol");
    require_input(o.newton_tol > 0, "parameter 'newton_tol' must be > 0");
    o.newton_max_iter = static_cast<int>(p.integer("newton_max_iter"));
    require_input(o.newton_max_iter >= 1, "parameter 'newton_max_iter' must be >= 1");
  }
  const std::string& j = p.text("jacobian");
  o.jacobian = j == "analytic"      ? JacobianSource::analytic
               : j == "fd_dense"    ? JacobianSource::fd_dense
               : j == "fd_colored"  ? JacobianSource::fd_colored
               : j == "matrix_free" ? JacobianSource::matrix_free
                                    : JacobianSource::automatic;
  o.linear.kind = parse_linear_solver(p.text("linear_solver"));
  const std::string& pc = p.text("preconditioner");
  o.preconditioner_given = pc != "auto";
  o.linear.preconditioner = pc == "none" ? PreconditionerKind::none : PreconditionerKind::jacobi;
  o.linear.krylov_tol = p.real("krylov_tol");
  require_input(o.linear.krylov_tol > 0, "parameter 'krylov_tol' must be > 0");
  o.linear.krylov_max_iter = static_cast<int>(p.integer("krylov_max_iter"));
  require_input(o.linear.krylov_max_iter >= 1, "parameter 'krylov_max_iter' must be >= 1");
  o.linear.gmres_restart = static_cast<int>(p.integer("gmres_restart"));
  require_input(o.linear.gmres_restart >= 1, "parameter 'gmres_restart' must be >= 1");
  return o;
}

std::vector<int> color_columns(const SparseMat& pattern, int* n_colors) {
  const Index n = pattern.cols();
  // Rows of each column (column-major pattern) and columns of each row.
  std::vector<std::vector<Index>> cols_of_row(static_cast<std::size_t>(pattern.rows()));
  for (Index c = 0; c < n; ++c)
    for (SparseMat::InnerIterator it(pattern, c); it; ++it)
      cols_of_row[static_cast<std::size_t>(it.row())].push_back(c);
  std::vector<int> color(static_cast<std::size_t>(n), -1);
  std::vector<Index> mark;  // mark[color] == c: colour used by a neighbour of column c
  int count = 0;
  for (Index c = 0; c < n; ++c) {
    for (SparseMat::InnerIterator it(pattern, c); it; ++it)
      for (Index other : cols_of_row[static_cast<std::size_t>(it.row())]) {
        const int oc = color[static_cast<std::size_t>(other)];
        if (oc >= 0) {
          if (static_cast<std::size_t>(oc) >= mark.size())
            mark.resize(static_cast<std::size_t>(oc) + 1, -1);
          mark[static_cast<std::size_t>(oc)] = c;
        }
      }
    int k = 0;
    while (static_cast<std::size_t>(k) < mark.size() && mark[static_cast<std::size_t>(k)] == c) ++k;
    color[static_cast<std::size_t>(c)] = k;
    count = std::max(count, k + 1);
  }
  if (n_colors) *n_colors = count;
  return color;
}

void ImplicitCore::reset(const OdeSystem& sys) {
  sys_ = &sys;
  const Index n = sys.dimension();
  source_ = opt_.jacobian;
  LinearSolverOptions lin = user_linear_;
  if (source_ == JacobianSource::automatic) {
    // Without an analytic Jacobian or a pattern, a dense finite-difference Jacobian costs 2n f
    // evaluations and n² memory: above the dense limit (e.g. an SPH fluid of 2,000 particles,
    // n = 8,192), auto takes matrix-free products with GMRES instead.
    const bool large = n > lin.dense_max && lin.kind == LinearSolverKind::automatic;
    source_ = sys.has_jacobian()           ? JacobianSource::analytic
              : sys.has_jacobian_pattern() ? JacobianSource::fd_colored
              : large                      ? JacobianSource::matrix_free
                                           : JacobianSource::fd_dense;
    if (source_ == JacobianSource::matrix_free) lin.kind = LinearSolverKind::gmres;
  }
  if (source_ == JacobianSource::analytic)
    require_input(sys.has_jacobian(),
                  "parameter 'jacobian': model '" + sys.name() + "' has no analytic Jacobian");
  if (source_ == JacobianSource::fd_colored)
    require_input(sys.has_jacobian_pattern(), "parameter 'jacobian': model '" + sys.name() +
                                                  "' gives no sparsity pattern for fd_colored");
  if (source_ == JacobianSource::matrix_free) {
    require_input(is_krylov(lin.kind),
                  "jacobian=matrix_free needs a Krylov linear_solver (cg, bicgstab or gmres)");
    require_input(!(opt_.preconditioner_given && lin.preconditioner == PreconditionerKind::jacobi),
                  "preconditioner=jacobi needs an assembled matrix; jacobian=matrix_free has none");
    lin.preconditioner = PreconditionerKind::none;
    // Finite-difference products are accurate to ~√eps relative, so a restarted Krylov method
    // cannot push the true residual much below that: solve to 1e-7 and let Newton iterate
    // (inexact Newton; SUNDIALS likewise ties its linear tolerance to the nonlinear one).
    lin.krylov_tol = std::max(lin.krylov_tol, kMatrixFreeKrylovTol);
  }
  solver_ = make_linear_solver(lin, n);
  opt_.linear = lin;

  identity_.resize(n, n);
  identity_.setIdentity();
  identity_.makeCompressed();
  // The pattern of J: analytic or declared structure, or dense for fd_dense.
  if (source_ == JacobianSource::fd_dense) {
    jac_ = Mat::Ones(n, n).sparseView();
  } else if (source_ != JacobianSource::matrix_free) {
    jac_ = sys.jacobian_pattern();
  } else {
    jac_.resize(n, n);
  }
  jac_.makeCompressed();
  if (source_ == JacobianSource::fd_colored) colors_ = color_columns(jac_, &n_colors_);
  if (source_ == JacobianSource::fd_dense) {
    colors_.resize(static_cast<std::size_t>(n));
    for (Index j = 0; j < n; ++j) colors_[static_cast<std::size_t>(j)] = static_cast<int>(j);
    n_colors_ = static_cast<int>(n);
  }
  if (source_ != JacobianSource::matrix_free) rebuild_w_pattern();
  lin_y_.resize(n);
  lin_f_.resize(n);
  tmp_.resize(n);
  tmp2_.resize(n);
  g_.resize(n);
  delta_.resize(n);
  z0_.resize(n);
  have_jac_ = jac_fresh_in_step_ = w_current_ = false;
}

void ImplicitCore::rebuild_w_pattern() {
  const std::vector<SparseTerm> terms{{1.0, &identity_, nullptr}, {1.0, &jac_, nullptr}};
  w_.build(terms);
  solver_->analyze(w_.matrix());
}

void ImplicitCore::fd_jacobian(const OdeSystem& sys, double t, CVecRef y, CVecRef) {
  // Central differences over column groups (fd_dense: every column its own group), two
  // evaluations per group; increments from core's fd_increment.
  const Index n = y.size();
  const double y_norm = y.cwiseAbs().maxCoeff();
  tmp_ = y;
  for (int color = 0; color < n_colors_; ++color) {
    for (Index j = 0; j < n; ++j)
      if (colors_[static_cast<std::size_t>(j)] == color)
        tmp_[j] = y[j] + fd_increment(y[j], y_norm);
    sys.rhs(t, tmp_, tmp2_);
    for (Index j = 0; j < n; ++j)
      if (colors_[static_cast<std::size_t>(j)] == color) tmp_[j] = 2.0 * y[j] - tmp_[j];
    sys.rhs(t, tmp_, g_);
    for (Index j = 0; j < n; ++j) {
      if (colors_[static_cast<std::size_t>(j)] != color) continue;
      const double span = (2.0 * y[j] - tmp_[j]) - tmp_[j];  // the representable 2δ applied
      for (SparseMat::InnerIterator it(jac_, j); it; ++it)
        it.valueRef() = (tmp2_[it.row()] - g_[it.row()]) / span;
      tmp_[j] = y[j];
    }
  }
}

void ImplicitCore::update_jacobian(const OdeSystem& sys, double t, CVecRef y, CVecRef fy,
                                   SolveStats& stats) {
  switch (source_) {
    case JacobianSource::analytic: {
      sys.jacobian(t, y, jac_);
      jac_.makeCompressed();
      const std::vector<SparseTerm> terms{{1.0, &identity_, nullptr}, {1.0, &jac_, nullptr}};
      // A model whose Jacobian pattern changed (it should not) costs a new symbolic analysis.
      if (!w_.same_patterns(terms)) rebuild_w_pattern();
      break;
    }
    case JacobianSource::fd_dense:
    case JacobianSource::fd_colored:
      fd_jacobian(sys, t, y, fy);
      ++stats.jac_evals;
      break;
    case JacobianSource::matrix_free:
      lin_t_ = t;
      lin_y_ = y;
      lin_f_ = fy;
      break;
    case JacobianSource::automatic:
      break;
  }
  have_jac_ = true;
  jac_fresh_in_step_ = true;
  w_current_ = false;
}

bool ImplicitCore::prepare(double hg, SolveStats& stats) {
  if (w_current_ && hg == w_hg_) return true;
  w_hg_ = hg;
  w_current_ = true;
  if (source_ == JacobianSource::matrix_free) return true;
  const std::vector<SparseTerm> terms{{1.0, &identity_, nullptr}, {-hg, &jac_, nullptr}};
  w_.assemble(terms);
  ++stats.lin_setups;
  return solver_->factor(w_.matrix());
}

bool ImplicitCore::solve(CVecRef b, VecRef x, SolveStats& stats) {
  ++stats.lin_solves;
  LinearSolveResult r;
  if (source_ == JacobianSource::matrix_free) {
    const double hg = w_hg_;
    const LinearOperator op = [this, hg, &stats](CVecRef v, VecRef out) {
      jacobian_times(v, out, stats);
      out = v - hg * out;
    };
    r = krylov_solve(solver_->kind(), op, Vec(), b, x, opt_.linear);
  } else {
    r = solver_->solve(b, x);
  }
  stats.krylov_iters += r.iterations;
  return r.ok && x.allFinite();
}

void ImplicitCore::jacobian_times(CVecRef v, VecRef out, SolveStats&) {
  if (source_ != JacobianSource::matrix_free) {
    out.noalias() = jac_ * v;
    return;
  }
  // (f(y + εv) - f(y))/ε with ε = √eps (1 + ‖y‖)/‖v‖ (Brown & Saad 1990; as in SUNDIALS).
  const double vn = v.norm();
  if (vn == 0) {
    out.setZero();
    return;
  }
  const double eps = kSqrtEps * (1.0 + lin_y_.norm()) / vn;
  tmp_ = lin_y_ + eps * v;
  sys_->rhs(lin_t_, tmp_, out);
  out = (out - lin_f_) / eps;
}

Status ImplicitCore::solve_stage(const OdeSystem& sys, double t, CVecRef psi, double hg, VecRef z,
                                 VecRef fz, SolveStats& stats) {
  z0_ = z;
  // Attempt 0 uses the configured Jacobian reuse; when it fails, attempt 1 starts again from
  // the predictor with full Newton (J at every iterate): the fixed-step driver cannot shrink
  // the step, so this is the only remedy before reporting newton_failed.
  for (int attempt = 0; attempt < 2; ++attempt) {
    const bool full =
        attempt == 1 || opt_.newton == NewtonMode::full || source_ == JacobianSource::matrix_free;
    if (attempt == 1) {
      if (opt_.newton == NewtonMode::full || source_ == JacobianSource::matrix_free) break;
      z = z0_;
    }
    double prev_dnorm = std::numeric_limits<double>::infinity();
    double dnorm = prev_dnorm;
    bool refresh = false;  // slow contraction with a reused J: re-evaluate it at the iterate
    for (int it = 0; it <= opt_.newton_max_iter; ++it) {
      sys.rhs(t, z, fz);
      g_ = z - psi - hg * fz;
      if (!g_.allFinite()) break;
      // At least one iteration: a predictor whose residual is already below tol can still be
      // off by ‖W⁻¹‖·tol, and fixed-step studies accumulate such errors over every step.
      if (it > 0 && (weighted_norm(g_, z) <= opt_.newton_tol || dnorm <= opt_.newton_tol))
        return Status::ok;
      if (it == opt_.newton_max_iter) break;
      const bool need_j = full || refresh || !have_jac_ ||
                          (opt_.newton == NewtonMode::modified && !jac_fresh_in_step_);
      if (need_j) update_jacobian(sys, t, z, fz, stats);
      refresh = false;
      if (!prepare(hg, stats)) break;
      delta_.setZero();
      if (!solve(-g_, delta_, stats)) break;
      z += delta_;
      ++stats.newton_iters;
      dnorm = weighted_norm(delta_, z);
      const double theta = dnorm / prev_dnorm;  // contraction estimate (Hairer–Wanner IV.8)
      if (it >= 1 && theta > 2.0) break;        // diverging
      if (it >= 1 && theta > 0.5) refresh = true;
      prev_dnorm = dnorm;
    }
  }
  ++stats.newton_fails;
  std::ostringstream msg;
  msg << "Newton did not converge at t = " << t << " (hγ = " << hg << ", " << opt_.newton_max_iter
      << " iterations max, tol " << opt_.newton_tol << ")";
  stats.message = msg.str();
  return Status::newton_failed;
}

}  // namespace stiffbench
