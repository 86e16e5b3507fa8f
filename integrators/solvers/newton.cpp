#include "integrators/solvers/newton.hpp"

#include <algorithm>
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
  using B = Bounds;
  std::vector<ParamSpec> specs;
  if (with_newton) {
    specs.push_back({"newton",
                     P::text,
                     "modified",
                     "Jacobian reuse in Newton: full (every iterate), modified (once per step), "
                     "frozen (across steps until a failure)",
                     {"full", "modified", "frozen"}});
    specs.push_back({"newton_tol", P::real, "1e-15",
                     "Newton stops when its predicted error theta/(1-theta) |dz| is below this "
                     "(weighted max-norm, relative to 1 + |z|; theta the measured contraction "
                     "rate), or when an update is at round-off; the default iterates to round-off",
                     B::positive()});
    specs.push_back(
        {"newton_max_iter", P::integer, "10", "Newton iterations per stage", B::at_least(1)});
  }
  specs.push_back({"jacobian",
                   P::text,
                   "auto",
                   "analytic, fd_dense, fd_colored (column-grouped over the model's pattern) or "
                   "matrix_free (Krylov solvers only); auto: analytic where provided, else "
                   "fd_colored over the model's pattern, else fd_dense up to 200 unknowns and "
                   "matrix_free with gmres above",
                   {"auto", "analytic", "fd_dense", "fd_colored", "matrix_free"}});
  specs.push_back({"system_form",
                   P::text,
                   "auto",
                   "system the linear solves work on: velocity (mechanical systems with force "
                   "Jacobians: (M - c M D - c^2 M K) dv of the dofs' size, pinned dofs "
                   "eliminated), first_order (I - c J of size 2n); auto: velocity where it applies",
                   {"auto", "velocity", "first_order"}});
  specs.push_back(
      {"linear_solver", P::text, "auto",
       "auto (velocity form: ldlt up to 2000 dofs, cg above for symmetric force Jacobians, "
       "dense_lu/sparse_lu otherwise; first-order form: dense_lu up to 50 unknowns, and up to "
       "200 unless the Jacobian's pattern fills under 10%, sparse_lu otherwise), dense_lu, "
       "sparse_lu, ldlt, cg, bicgstab, gmres",
       linear_solver_names()});
  specs.push_back({"preconditioner",
                   P::text,
                   "auto",
                   "Krylov preconditioner: jacobi, ichol (incomplete Cholesky, cg only), none; "
                   "auto: jacobi (none when matrix-free)",
                   {"auto", "jacobi", "ichol", "none"}});
  specs.push_back({"krylov_tol", P::real, "1e-12",
                   with_newton ? "relative residual of Krylov solves; with "
                                 "krylov_forcing=eisenstat_walker the floor of the forcing terms "
                                 "(at least 1e-7 when matrix-free)"
                               : "relative residual of Krylov solves (at least 1e-7 when "
                                 "matrix-free)",
                   B::positive()});
  if (with_newton)
    specs.push_back({"krylov_forcing",
                     P::text,
                     "eisenstat_walker",
                     "Krylov tolerance per Newton iteration: eisenstat_walker (forcing terms "
                     "that tighten as Newton converges) or fixed (krylov_tol every time)",
                     {"eisenstat_walker", "fixed"}});
  specs.push_back(
      {"krylov_max_iter", P::integer, "1000", "Krylov iterations per solve", B::at_least(1)});
  specs.push_back({"gmres_restart", P::integer, "50", "GMRES restart length", B::at_least(1)});
  return specs;
}

NewtonOptions read_newton_options(const Params& p, bool with_iteration) {
  NewtonOptions o;
  if (with_iteration) {
    o.tol = p.real("newton_tol");
    require_input(o.tol > 0, "parameter 'newton_tol' must be > 0");
    o.max_iter = static_cast<int>(p.integer("newton_max_iter"));
    require_input(o.max_iter >= 1, "parameter 'newton_max_iter' must be >= 1");
  }
  const std::string& j = p.text("jacobian");
  o.jacobian = j == "analytic"      ? JacobianSource::analytic
               : j == "fd_dense"    ? JacobianSource::fd_dense
               : j == "fd_colored"  ? JacobianSource::fd_colored
               : j == "matrix_free" ? JacobianSource::matrix_free
                                    : JacobianSource::automatic;
  o.linear = parse_linear_solver(p.text("linear_solver"));
  return o;
}

ImplicitOptions first_order_core_options(JacobianSource jacobian, LinearSolverKind linear) {
  ImplicitOptions io;
  io.jacobian = jacobian;
  io.linear.kind = linear;
  io.form = SystemForm::first_order;
  return io;
}

ImplicitOptions read_implicit_options(const Params& p, bool with_newton) {
  ImplicitOptions o;
  if (with_newton) {
    const std::string& n = p.text("newton");
    o.newton = n == "full"     ? NewtonMode::full
               : n == "frozen" ? NewtonMode::frozen
                               : NewtonMode::modified;
  }
  const NewtonOptions n = read_newton_options(p, with_newton);
  if (with_newton) {
    o.newton_tol = n.tol;
    o.newton_max_iter = n.max_iter;
  }
  o.jacobian = n.jacobian;
  o.linear.kind = n.linear;
  const std::string& pc = p.text("preconditioner");
  o.preconditioner_given = pc != "auto";
  o.linear.preconditioner = pc == "none"    ? PreconditionerKind::none
                            : pc == "ichol" ? PreconditionerKind::ichol
                                            : PreconditionerKind::jacobi;
  require_input(o.linear.preconditioner != PreconditionerKind::ichol ||
                    o.linear.kind == LinearSolverKind::cg ||
                    o.linear.kind == LinearSolverKind::automatic,
                "preconditioner=ichol needs linear_solver=cg (or auto)");
  const std::string form = p.contains("system_form") ? p.text("system_form") : "auto";
  o.form = form == "velocity"      ? SystemForm::velocity
           : form == "first_order" ? SystemForm::first_order
                                   : SystemForm::automatic;
  if (with_newton) o.eisenstat_walker = p.text("krylov_forcing") != "fixed";
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

void ImplicitCore::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  sys_ = &sys;
  LinearSolverOptions lin = resolve_jacobian_source(sys);
  krylov_tol_ = lin.krylov_tol;
  velocity_.reset();
  solver_.reset();
  mech_inplace_ = nullptr;
  const MechanicalSystem* mech = sys.as_mechanical();
  const bool mech_blocks = mech && mech->has_force_jacobians();
  if (mech_blocks && source_ == JacobianSource::analytic && opt_.form != SystemForm::first_order)
    setup_velocity_form(*mech, lin, t0, y0);
  else
    setup_first_order(sys, lin, t0, y0);
  allocate_workspaces(sys.dimension());
  have_jac_ = jac_fresh_in_step_ = w_current_ = false;
  error_.clear();
}

LinearSolverOptions ImplicitCore::resolve_jacobian_source(const OdeSystem& sys) {
  const Index n = sys.dimension();
  source_ = opt_.jacobian;
  LinearSolverOptions lin = user_linear_;
  const MechanicalSystem* mech = sys.as_mechanical();
  const bool mech_blocks = mech && mech->has_force_jacobians();
  if (opt_.form == SystemForm::velocity)
    require_input(mech_blocks,
                  "parameter 'system_form': velocity needs a mechanical model with force "
                  "Jacobians K and D; model '" +
                      sys.name() + "' has none (use system_form=first_order)");
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
  if (opt_.form == SystemForm::velocity)
    require_input(
        source_ == JacobianSource::analytic,
        "parameter 'system_form': velocity uses the model's K and D (jacobian=auto or analytic)");
  if (source_ == JacobianSource::matrix_free) restrict_to_matrix_free(lin);
  return lin;
}

void ImplicitCore::restrict_to_matrix_free(LinearSolverOptions& lin) const {
  require_input(is_krylov(lin.kind),
                "jacobian=matrix_free needs a Krylov linear_solver (cg, bicgstab or gmres)");
  require_input(
      !(opt_.preconditioner_given && lin.preconditioner != PreconditionerKind::none),
      "preconditioner=" +
          std::string(lin.preconditioner == PreconditionerKind::ichol ? "ichol" : "jacobi") +
          " needs an assembled matrix; jacobian=matrix_free has none");
  lin.preconditioner = PreconditionerKind::none;
  // Finite-difference products are accurate to ~√eps relative, so a restarted Krylov method
  // cannot push the true residual much below that: solve to 1e-7 and let Newton iterate
  // (inexact Newton; SUNDIALS likewise ties its linear tolerance to the nonlinear one).
  lin.krylov_tol = std::max(lin.krylov_tol, kMatrixFreeKrylovTol);
}

void ImplicitCore::setup_velocity_form(const MechanicalSystem& mech, LinearSolverOptions lin,
                                       double t0, CVecRef y0) {
  velocity_ = std::make_unique<VelocityFormSolver>();
  velocity_->reset(mech, lin, t0, y0);
  lin.kind = velocity_->kind();
  opt_.linear = lin;
}

double jacobian_pattern_density(const OdeSystem& sys, const LinearSolverOptions& opt) {
  const Index n = sys.dimension();
  if (opt.kind != LinearSolverKind::automatic || n <= opt.dense_small || n > opt.dense_max ||
      !sys.has_jacobian_pattern())
    return 1.0;
  const SparseMat pattern = sys.jacobian_pattern();
  return static_cast<double>(pattern.nonZeros()) / (static_cast<double>(n) * n);
}

void ImplicitCore::setup_first_order(const OdeSystem& sys, LinearSolverOptions lin, double t0,
                                     CVecRef y0) {
  const Index n = sys.dimension();
  lin.pattern_density = jacobian_pattern_density(sys, lin);
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
  const MechanicalSystem* mech = sys.as_mechanical();
  if (mech && mech->has_force_jacobians() && source_ == JacobianSource::analytic)
    map_force_jacobians(*mech, t0, y0);
  if (source_ == JacobianSource::fd_colored) colors_ = color_columns(jac_, &n_colors_);
  if (source_ == JacobianSource::fd_dense) {
    colors_.resize(static_cast<std::size_t>(n));
    for (Index j = 0; j < n; ++j) colors_[static_cast<std::size_t>(j)] = static_cast<int>(j);
    n_colors_ = static_cast<int>(n);
  }
  if (source_ != JacobianSource::matrix_free) rebuild_w_pattern();
}

void ImplicitCore::map_force_jacobians(const MechanicalSystem& mech, double t0, CVecRef y0) {
  // J = [[0, I], [K, D]] written in place: the position in J of every entry of K and D.
  const Index nd = mech.dofs();
  mech_inplace_ = &mech;
  k_.resize(0, 0);
  d_.resize(0, 0);
  mech.force_jacobians(t0, y0.head(nd), y0.tail(nd), k_, d_);
  k_.makeCompressed();
  d_.makeCompressed();
  const auto map = [&](const SparseMat& b, Index col0, std::vector<int>& out) {
    out.clear();
    for (Index c = 0; c < b.outerSize(); ++c)
      for (SparseMat::InnerIterator it(b, c); it; ++it) {
        const int* begin = jac_.innerIndexPtr() + jac_.outerIndexPtr()[col0 + c];
        const int* end = jac_.innerIndexPtr() + jac_.outerIndexPtr()[col0 + c + 1];
        const int* pos = std::lower_bound(begin, end, static_cast<int>(nd + it.row()));
        if (pos == end || *pos != nd + it.row())
          throw std::logic_error("ImplicitCore: K/D entry missing from the Jacobian pattern");
        out.push_back(static_cast<int>(pos - jac_.innerIndexPtr()));
      }
  };
  map(k_, 0, k_in_jac_);
  map(d_, nd, d_in_jac_);
}

void ImplicitCore::allocate_workspaces(Index n) {
  lin_y_.resize(n);
  lin_f_.resize(n);
  tmp_.resize(n);
  tmp2_.resize(n);
  g_.resize(n);
  fd_minus_.resize(n);
  delta_.resize(n);
  z0_.resize(n);
}

void ImplicitCore::rebuild_w_pattern() {
  w_terms_ = {{1.0, &identity_, nullptr}, {1.0, &jac_, nullptr}};
  w_.build(w_terms_);
  solver_->analyze(w_.matrix());
}

bool ImplicitCore::is_krylov_run() const { return is_krylov(linear_solver()); }

void ImplicitCore::set_krylov_tolerance(double tol) {
  if (velocity_)
    velocity_->set_tolerance(tol);
  else if (source_ == JacobianSource::matrix_free)
    krylov_tol_ = std::max(tol, kMatrixFreeKrylovTol);
  else
    solver_->set_tolerance(tol);
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
    sys.rhs(t, tmp_, fd_minus_);
    for (Index j = 0; j < n; ++j) {
      if (colors_[static_cast<std::size_t>(j)] != color) continue;
      const double span = (2.0 * y[j] - tmp_[j]) - tmp_[j];  // the representable 2δ applied
      for (SparseMat::InnerIterator it(jac_, j); it; ++it)
        it.valueRef() = (tmp2_[it.row()] - fd_minus_[it.row()]) / span;
      tmp_[j] = y[j];
    }
  }
}

void ImplicitCore::update_jacobian(const OdeSystem& sys, double t, CVecRef y, CVecRef fy,
                                   SolveStats& stats) {
  switch (source_) {
    case JacobianSource::analytic: {
      if (velocity_) {
        velocity_->update(t, y);
        ++stats.jac_evals;  // K and D: one Jacobian (not counted by the system)
        break;
      }
      if (mech_inplace_) {
        const Index nd = mech_inplace_->dofs();
        mech_inplace_->force_jacobians(t, y.head(nd), y.tail(nd), k_, d_);
        k_.makeCompressed();
        d_.makeCompressed();
        // The maps hold when the blocks keep the nonzero counts seen at reset() (a model whose
        // blocks change pattern would fail the first-order pattern test below as well).
        if (static_cast<std::size_t>(k_.nonZeros()) != k_in_jac_.size() ||
            static_cast<std::size_t>(d_.nonZeros()) != d_in_jac_.size())
          throw std::logic_error("model '" + sys.name() +
                                 "': the pattern of its force Jacobians changed during a run");
        double* jv = jac_.valuePtr();
        for (std::size_t i = 0; i < k_in_jac_.size(); ++i) jv[k_in_jac_[i]] = k_.valuePtr()[i];
        for (std::size_t i = 0; i < d_in_jac_.size(); ++i) jv[d_in_jac_[i]] = d_.valuePtr()[i];
        ++stats.jac_evals;
        break;
      }
      sys.jacobian(t, y, jac_);
      jac_.makeCompressed();
      // A model whose Jacobian pattern changed (it should not) costs a new symbolic analysis.
      w_terms_[1].coeff = 1.0;
      if (!w_.same_patterns(w_terms_)) rebuild_w_pattern();
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
  ++stats.linear_setups;
  if (velocity_) {
    const bool ok = velocity_->factor(hg);
    if (!ok) {
      error_ = velocity_->error();
      w_current_ = false;
    }
    return ok;
  }
  w_terms_[1].coeff = -hg;
  w_.assemble(w_terms_);
  const bool ok = solver_->factor(w_.matrix());
  if (!ok) {
    error_ = solver_->error();
    w_current_ = false;
  }
  return ok;
}

bool ImplicitCore::solve(CVecRef b, VecRef x, SolveStats& stats) {
  ++stats.lin_solves;
  LinearSolveResult r;
  if (velocity_) {
    r = velocity_->solve(b, x);
    if (!r.ok) error_ = velocity_->error();
  } else if (source_ == JacobianSource::matrix_free) {
    const double hg = w_hg_;
    const LinearOperator op = [this, hg, &stats](CVecRef v, VecRef out) {
      jacobian_times(v, out, stats);
      out = v - hg * out;
    };
    LinearSolverOptions o = opt_.linear;
    o.krylov_tol = krylov_tol_;
    r = krylov_solve(solver_->kind(), op, Vec(), b, x, o, krylov_ws_);
    if (!r.ok) error_ = to_string(solver_->kind()) + " (matrix-free): no convergence";
  } else {
    r = solver_->solve(b, x);
    if (!r.ok) error_ = solver_->error();
  }
  stats.linear_iters += r.iterations;
  if (r.ok && !x.allFinite()) {
    error_ = to_string(linear_solver()) + ": non-finite solution";
    return false;
  }
  return r.ok;
}

void ImplicitCore::jacobian_times(CVecRef v, VecRef out, SolveStats&) {
  if (velocity_) {
    velocity_->jacobian_times(v, out);
    return;
  }
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

Status ImplicitCore::linear_failure(double t, SolveStats& stats) {
  std::ostringstream msg;
  msg << "linear solver failed at t = " << t << ": " << error_;
  stats.message = msg.str();
  return Status::solver_error;
}

namespace {

const char* outcome_name(NewtonOutcome o) {
  switch (o) {
    case NewtonOutcome::converged:
      return "converged";
    case NewtonOutcome::diverging:
      return "diverging";
    case NewtonOutcome::too_slow:
      return "too slow";
    case NewtonOutcome::iteration_limit:
      return "iteration limit";
    case NewtonOutcome::non_finite:
      return "non-finite iterate";
    case NewtonOutcome::linear_failed:
      return "linear solver failed";
  }
  return "?";
}

}  // namespace

bool newton_update_converged(double dnorm, double prev_dnorm, bool have_rate, double tol,
                             int iters_done, int max_iter, bool slow_test, NewtonOutcome* outcome,
                             double* theta) {
  *outcome = NewtonOutcome::converged;
  if (!std::isfinite(dnorm)) {
    *outcome = NewtonOutcome::non_finite;
    return true;
  }
  if (dnorm <= kNewtonRoundoff) return true;  // at round-off: no rate needed
  if (!have_rate) return false;
  *theta = dnorm / prev_dnorm;
  if (*theta >= 1.0) {
    // No contraction: an update at the level of rounding noise means the iterate has converged
    // as far as it can; anything larger is divergence.
    if (dnorm > kNewtonNoise) *outcome = NewtonOutcome::diverging;
    return true;
  }
  if (*theta / (1.0 - *theta) * dnorm <= tol) return true;
  // Predicted error after the remaining iterations (Hairer–Wanner IV.8, (8.13)).
  if (slow_test && dnorm > kNewtonNoise &&
      std::pow(*theta, max_iter - iters_done) / (1.0 - *theta) * dnorm > tol) {
    *outcome = NewtonOutcome::too_slow;
    return true;
  }
  return false;
}

std::string describe_newton_failure(const NewtonAttempt& a, double tol) {
  std::ostringstream m;
  m << outcome_name(a.outcome);
  switch (a.outcome) {
    case NewtonOutcome::diverging:
      m << " (theta = " << a.theta << " >= 1 at iteration " << a.iters << ", |dz| = " << a.dnorm
        << ")";
      break;
    case NewtonOutcome::too_slow:
      m << " (theta = " << a.theta << " at iteration " << a.iters << ", |dz| = " << a.dnorm
        << ": predicted above tol " << tol << " within the iteration limit)";
      break;
    case NewtonOutcome::iteration_limit:
      m << " (" << a.iters << " iterations, |dz| = " << a.dnorm << ", tol " << tol << ")";
      break;
    case NewtonOutcome::non_finite:
      m << " at iteration " << a.iters;
      break;
    default:
      break;
  }
  return m.str();
}

NewtonAttempt ImplicitCore::newton_attempt(const OdeSystem& sys, double t, CVecRef psi, double hg,
                                           VecRef z, VecRef fz, SolveStats& stats,
                                           JacobianUse use) {
  const bool forcing = opt_.eisenstat_walker && is_krylov_run();
  const int kmax = opt_.newton_max_iter;
  NewtonAttempt a;
  double prev_dnorm = std::numeric_limits<double>::infinity();
  double prev_gnorm = 0.0, eta = 0.0;
  for (int k = 0; k < kmax; ++k) {
    sys.rhs(t, z, fz);
    g_ = z - psi - hg * fz;
    if (!g_.allFinite()) {
      a.outcome = NewtonOutcome::non_finite;
      a.iters = k;
      return a;
    }
    const bool need_j = use == JacobianUse::full || !have_jac_ ||
                        (use == JacobianUse::fresh && k == 0) ||
                        (opt_.newton == NewtonMode::modified && !jac_fresh_in_step_);
    if (need_j) {
      update_jacobian(sys, t, z, fz, stats);
      a.fresh_jacobian = true;
    }
    if (!prepare(hg, stats)) {
      a.outcome = NewtonOutcome::linear_failed;
      return a;
    }
    if (forcing) {
      // Eisenstat–Walker forcing term (choice 2, γ = 0.9, α = 2; see the header comment).
      const double gnorm = g_.norm();
      double next = 1e-2;
      if (k > 0 && prev_gnorm > 0) {
        const double ratio = gnorm / prev_gnorm;
        next = 0.9 * ratio * ratio;
        if (0.9 * eta * eta > 0.1) next = std::max(next, 0.9 * eta * eta);
      }
      const double floor =
          std::max(opt_.linear.krylov_tol, gnorm > 0 ? 0.1 * opt_.newton_tol / gnorm : 0.0);
      eta = std::max(std::min(next, 0.1), floor);
      prev_gnorm = gnorm;
      set_krylov_tolerance(eta);
    }
    delta_.setZero();
    g_ = -g_;  // in place: passing the expression -g_ would allocate a temporary
    if (!solve(g_, delta_, stats)) {
      a.outcome = NewtonOutcome::linear_failed;
      return a;
    }
    z += delta_;
    ++stats.newton_iters;
    a.iters = k + 1;
    a.dnorm = weighted_norm(delta_, z);
    // The linear-rate prediction of the too-slow test does not hold for full Newton (J at every
    // iterate converges faster than linearly): there only divergence and the limit end it.
    if (newton_update_converged(a.dnorm, prev_dnorm, k > 0, opt_.newton_tol, a.iters, kmax,
                                use != JacobianUse::full, &a.outcome, &a.theta))
      return a;
    prev_dnorm = a.dnorm;
  }
  a.outcome = a.dnorm <= kNewtonNoise ? NewtonOutcome::converged : NewtonOutcome::iteration_limit;
  return a;
}

Status ImplicitCore::solve_stage(const OdeSystem& sys, double t, CVecRef psi, double hg, VecRef z,
                                 VecRef fz, SolveStats& stats) {
  z0_ = z;
  const bool always_full =
      opt_.newton == NewtonMode::full || source_ == JacobianSource::matrix_free;
  // Attempt 1 uses the configured Jacobian reuse. A failure with a J evaluated before this solve
  // (an earlier stage or step) is retried with J fresh at the solve's start; a failure with a
  // fresh J, with full Newton (J at every iterate). The fixed-step driver cannot shrink the step,
  // so these are the only remedies before reporting newton_failed. Every failed attempt counts
  // in newton_conv_failures.
  JacobianUse use = always_full ? JacobianUse::full : JacobianUse::configured;
  std::string reasons;
  for (int attempt = 0; attempt < 3; ++attempt) {
    const NewtonAttempt a = newton_attempt(sys, t, psi, hg, z, fz, stats, use);
    if (a.outcome == NewtonOutcome::converged) return Status::ok;
    if (a.outcome == NewtonOutcome::linear_failed) return linear_failure(t, stats);
    ++stats.newton_conv_failures;
    if (!reasons.empty()) reasons += "; then ";
    reasons += describe_newton_failure(a, opt_.newton_tol);
    reasons += use == JacobianUse::full    ? " with full Newton"
               : use == JacobianUse::fresh ? " with J fresh at the start"
               : a.fresh_jacobian          ? " with J of this solve"
                                           : " with J of an earlier stage or step";
    // A slow or capped iteration continues from where it got to; a diverging one restarts.
    const bool keep =
        a.outcome == NewtonOutcome::too_slow || a.outcome == NewtonOutcome::iteration_limit;
    if (!keep) z = z0_;
    if (use == JacobianUse::configured && !a.fresh_jacobian)
      use = JacobianUse::fresh;
    else if (use != JacobianUse::full)
      use = JacobianUse::full;
    else
      break;
  }
  std::ostringstream msg;
  msg << "Newton failed at t = " << t << " (hγ = " << hg << "): " << reasons;
  stats.message = msg.str();
  return Status::newton_failed;
}

}  // namespace stiffbench
