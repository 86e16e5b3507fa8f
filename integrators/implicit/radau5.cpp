#include "integrators/implicit/radau5.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "integrators/method_entry.hpp"
#include "integrators/method_file.hpp"

namespace stiffbench {

const ButcherTableau& radau5_tableau() { return built_in_method("radau5").tableau; }

namespace {

std::string num(double x) {
  std::ostringstream os;
  os.precision(3);
  os << x;
  return os.str();
}

// The checks of radau5.hpp that need no eigen-decomposition; BadInput naming the tableau.
ButcherTableau validated_radau5(ButcherTableau t) {
  t.validate(ButcherTableau::Shape::any);
  const std::string who =
      "tableau '" + (t.name.empty() ? std::string("(unnamed)") : t.name) + "': RADAU5 needs ";
  require_input(t.stages() == 3, who + "3 stages (it has " + std::to_string(t.stages()) + ")");
  require_input(std::abs(t.c[2] - 1.0) <= 1e-14, who + "c_3 = 1 (it is " + num(t.c[2]) + ")");
  const double sa = (t.a.row(2).transpose() - t.b).cwiseAbs().maxCoeff();
  require_input(sa <= 1e-14, who +
                                 "a stiffly accurate tableau, b equal to the last row of A (they "
                                 "differ by " +
                                 num(sa) + ")");
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < i; ++j)
      require_input(std::abs(t.c[i] - t.c[j]) > 1e-12,
                    who + "distinct nodes (c_" + std::to_string(j + 1) + " = c_" +
                        std::to_string(i + 1) + " = " + num(t.c[i]) + ")");
  const Eigen::JacobiSVD<Mat> svd(t.a);
  const double rcond = svd.singularValues()[2] / svd.singularValues()[0];
  require_input(rcond > 1e-12,
                who + "an invertible A (smallest/largest singular value " + num(rcond) + ")");
  return t;
}

}  // namespace

Radau5Constants radau5_constants(const ButcherTableau& tableau) {
  const ButcherTableau tab = validated_radau5(tableau);
  const Eigen::Matrix3d a = tab.a;
  const Eigen::Matrix3d ainv = a.inverse();
  Eigen::EigenSolver<Eigen::Matrix3d> es(ainv);
  int real_idx = 0, pair_idx = 0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(es.eigenvalues()[i].imag()) < std::abs(es.eigenvalues()[real_idx].imag()))
      real_idx = i;
    if (es.eigenvalues()[i].imag() > es.eigenvalues()[pair_idx].imag()) pair_idx = i;
  }
  const std::string who =
      "tableau '" + (tab.name.empty() ? std::string("(unnamed)") : tab.name) + "': RADAU5 needs ";
  const double scale = es.eigenvalues().cwiseAbs().maxCoeff();
  require_input(es.info() == Eigen::Success &&
                    std::abs(es.eigenvalues()[real_idx].imag()) <= 1e-12 * scale &&
                    es.eigenvalues()[pair_idx].imag() > 1e-12 * scale,
                who + "A^-1 with one real eigenvalue and one complex-conjugate pair");
  // A⁻¹(u + iw) = (a' + ib')(u + iw) gives A⁻¹u = a'u - b'w, A⁻¹w = b'u + a'w: with
  // T = [t1, u, w] the lower block of T⁻¹A⁻¹T is [[a', b'], [-b', a']].
  Radau5Constants c;
  c.t.col(0) = es.eigenvectors().col(real_idx).real();
  c.t.col(1) = es.eigenvectors().col(pair_idx).real();
  c.t.col(2) = es.eigenvectors().col(pair_idx).imag();
  // As for ImplicitRungeKutta (gauss.cpp): the transformation must not amplify round-off.
  const Eigen::JacobiSVD<Mat> svd_t(Mat(c.t));
  const double cond_t = svd_t.singularValues()[0] / svd_t.singularValues()[2];
  require_input(cond_t <= 1e4, who +
                                   "A^-1 diagonalisable with well-separated eigenvalues (its "
                                   "eigenvector basis has condition number " +
                                   num(cond_t) + ")");
  c.t_inv = c.t.inverse();
  const Eigen::Matrix3d lambda = c.t_inv * ainv * c.t;
  c.gamma_hat = lambda(0, 0);
  c.a = lambda(1, 1);
  c.b = lambda(1, 2);
  // The blocks must be A⁻¹ itself (T Λ_blocks⁻¹ T⁻¹ = A to round-off), else the iteration
  // solves another method.
  Eigen::Matrix3d blocks = Eigen::Matrix3d::Zero();
  blocks(0, 0) = c.gamma_hat;
  blocks(1, 1) = blocks(2, 2) = c.a;
  blocks(1, 2) = c.b;
  blocks(2, 1) = -c.b;
  const double defect = (c.t * blocks.inverse() * c.t_inv - a).cwiseAbs().maxCoeff() /
                        std::max(1.0, a.cwiseAbs().maxCoeff());
  require_input(defect <= 1e-12, who +
                                     "A^-1 diagonalisable to round-off (A rebuilt from its "
                                     "eigenvectors differs by " +
                                     num(defect) + ")");
  // Embedded weights of order 3 with b̂_0 = γ_0 = 1/γ̂ on f(t_n, y_n):
  // γ_0 δ_{q0} + Σ_i b̂_i c_i^q = 1/(q+1), q = 0, 1, 2.
  Eigen::Matrix3d v;
  Eigen::Vector3d rhs;
  for (int q = 0; q < 3; ++q) {
    for (int i = 0; i < 3; ++i) v(q, i) = std::pow(tab.c[i], q);
    rhs[q] = 1.0 / (q + 1) - (q == 0 ? 1.0 / c.gamma_hat : 0.0);
  }
  const Eigen::Vector3d bhat = v.partialPivLu().solve(rhs);
  c.e = ainv.transpose() * (bhat - Eigen::Vector3d(tab.b));
  return c;
}

const Radau5Constants& radau5_constants() {
  static const Radau5Constants k = radau5_constants(radau5_tableau());
  return k;
}

// --- linear systems shift·I - J ------------------------------------------------------------

template <class Scalar>
void ShiftedSolver<Scalar>::reset(Index n, bool dense) {
  n_ = n;
  dense_ = dense;
  jac_inner_.clear();
  analyzed_ = false;
  if (dense_) {
    m_.resize(n, n);
    lu_ = Eigen::PartialPivLU<DenseM>(n);
  } else {
    m_.resize(0, 0);
  }
}

template <class Scalar>
bool ShiftedSolver<Scalar>::factor(Scalar shift, const SparseMat& jac) {
  if (dense_) {
    m_.setZero();
    for (Index c = 0; c < jac.outerSize(); ++c)
      for (SparseMat::InnerIterator it(jac, c); it; ++it) m_(it.row(), it.col()) = -it.value();
    m_.diagonal().array() += shift;
    lu_.compute(m_);
    return (lu_.matrixLU().diagonal().array().abs() > 0.0).all();
  }
  const auto nnz = static_cast<std::size_t>(jac.nonZeros());
  const bool same = nnz == jac_inner_.size() &&
                    std::equal(jac_inner_.begin(), jac_inner_.end(), jac.innerIndexPtr()) &&
                    analyzed_;
  if (!same) {
    // Pattern of J ∪ diagonal, the value positions of both, and the symbolic analysis (once per
    // run unless the model's pattern changes).
    std::vector<Eigen::Triplet<Scalar>> trip;
    trip.reserve(nnz + static_cast<std::size_t>(n_));
    for (Index c = 0; c < jac.outerSize(); ++c)
      for (SparseMat::InnerIterator it(jac, c); it; ++it)
        trip.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), Scalar(0));
    for (Index i = 0; i < n_; ++i)
      trip.emplace_back(static_cast<int>(i), static_cast<int>(i), Scalar(0));
    sm_.resize(n_, n_);
    sm_.setFromTriplets(trip.begin(), trip.end());
    sm_.makeCompressed();
    const auto position = [&](Index row, Index col) {
      const auto* begin = sm_.innerIndexPtr() + sm_.outerIndexPtr()[col];
      const auto* end = sm_.innerIndexPtr() + sm_.outerIndexPtr()[col + 1];
      const auto* p = std::lower_bound(begin, end, static_cast<int>(row));
      return static_cast<int>(p - sm_.innerIndexPtr());
    };
    jac_pos_.clear();
    for (Index c = 0; c < jac.outerSize(); ++c)
      for (SparseMat::InnerIterator it(jac, c); it; ++it)
        jac_pos_.push_back(position(it.row(), it.col()));
    diag_pos_.resize(static_cast<std::size_t>(n_));
    for (Index i = 0; i < n_; ++i) diag_pos_[static_cast<std::size_t>(i)] = position(i, i);
    jac_inner_.assign(jac.innerIndexPtr(), jac.innerIndexPtr() + nnz);
    slu_.analyze(sm_);
    analyzed_ = true;
  }
  Scalar* v = sm_.valuePtr();
  std::fill(v, v + sm_.nonZeros(), Scalar(0));
  const double* jv = jac.valuePtr();
  for (std::size_t k = 0; k < nnz; ++k) v[jac_pos_[k]] = -jv[k];
  for (const int p : diag_pos_) v[p] += shift;
  return slu_.factor(sm_);
}

template <class Scalar>
void ShiftedSolver<Scalar>::solve(const CVector& rhs, CVector& out) {
  if (dense_)
    out.noalias() = lu_.solve(rhs);
  else
    slu_.solve(rhs, out);
}

template class ShiftedSolver<double>;
template class ShiftedSolver<std::complex<double>>;

// --- parameters ----------------------------------------------------------------------------

std::vector<ParamSpec> radau5_param_specs() {
  using P = ParamType;
  using B = Bounds;
  std::vector<ParamSpec> s = controller_param_specs();
  s.push_back({"newton_tol", P::real, "1e-15",
               "fixed-step mode: Newton stops when its predicted error theta/(1-theta) |dW| is "
               "below newton_tol (1 + |y|) in the RMS norm, or an update is at round-off; the "
               "default iterates to round-off (adaptive mode uses RADAU5's rule from rtol)",
               B::positive()});
  s.push_back({"newton",
               P::text,
               "modified",
               "Jacobian reuse: modified (J at every step's start), frozen (J kept across steps "
               "until a Newton failure, then re-evaluated)",
               {"modified", "frozen"}});
  s.push_back({"newton_max_iter", P::integer, "20",
               "Newton iterations per step (RADAU5 uses 7 with its loose adaptive tolerance; "
               "iterating to round-off in fixed-step mode needs more at large steps)",
               B::at_least(1)});
  s.push_back({"jacobian",
               P::text,
               "auto",
               "analytic, fd_dense, fd_colored (over the model's pattern); auto: analytic where "
               "provided, else fd_colored over a pattern, else fd_dense",
               {"auto", "analytic", "fd_dense", "fd_colored"}});
  s.push_back({"linear_solver",
               P::text,
               "auto",
               "dense_lu or sparse_lu for the real and the complex system; auto: dense_lu up to "
               "50 unknowns, and up to 200 unless the Jacobian's pattern fills under 10%; "
               "sparse_lu otherwise",
               {"auto", "dense_lu", "sparse_lu"}});
  return s;
}

Radau5Options read_radau5_options(const Params& p) {
  Radau5Options o;
  o.control = read_controller_options(p);
  const NewtonOptions n = read_newton_options(p);
  o.newton_tol = n.tol;
  o.newton_max_iter = n.max_iter;
  o.frozen = p.text("newton") == "frozen";
  o.jacobian = n.jacobian;
  o.linear = n.linear;
  return o;
}

// --- the integrator ------------------------------------------------------------------------

namespace {

// The MethodInfo of the class: the solver and its tableau. A registered method's description,
// kind and reference come from its method file (methods/radau5.toml for the built-in radau5;
// method_registry_entry, integrators/method_file.hpp).
MethodInfo radau5_info(const ButcherTableau& t) {
  MethodInfo info{t.name,
                  Family::implicit,
                  t.order,
                  3,
                  {},
                  "RADAU5 (Hairer-Wanner IV.8: simplified Newton split into one real and one "
                  "complex system, embedded error estimate) on the 3-stage stiffly accurate "
                  "tableau '" +
                      t.name + "'; adaptive (rtol/atol) or fixed step"};
  info.kind = "Radau IIA (RADAU5)";
  info.reference = std::string(kHairerWanner) + ", Sect. IV.8 (RADAU5)";
  return info;
}

}  // namespace

Radau5::Radau5(ButcherTableau tableau, Radau5Options opt)
    : Integrator(radau5_info(tableau)),
      tableau_(validated_radau5(std::move(tableau))),
      k_(radau5_constants(tableau_)),
      zero_node_(tableau_.c[0] == 0.0 || tableau_.c[1] == 0.0),
      opt_(opt),
      core_(first_order_core_options(opt.jacobian, opt.linear)),
      ctrl_(opt.control, 4) {}

Radau5::Radau5(Radau5Options opt) : Radau5(radau5_tableau(), opt) {}

void Radau5::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  n_ = sys.dimension();
  const bool large = n_ > LinearSolverOptions{}.dense_max;
  require_input(opt_.jacobian != JacobianSource::automatic || !large || sys.has_jacobian() ||
                    sys.has_jacobian_pattern(),
                "integrator '" + info().name + "' needs an assembled Jacobian: model '" +
                    sys.name() +
                    "' has neither an analytic Jacobian nor a sparsity pattern and more than " +
                    std::to_string(LinearSolverOptions{}.dense_max) +
                    " unknowns (give jacobian=fd_dense to use a dense one)");
  core_.reset(sys, t0, y0);
  LinearSolverOptions automatic;
  automatic.pattern_density = jacobian_pattern_density(sys, automatic);
  const bool dense =
      opt_.linear == LinearSolverKind::dense_lu ||
      (opt_.linear == LinearSolverKind::automatic && automatic_is_dense(automatic, n_));
  real_.reset(n_, dense);
  complex_.reset(n_, dense);
  restart_state(t0);
}

void Radau5::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();
  restart_state(t);
}

void Radau5::restart_state(double t0) {
  for (Mat* m : {&z_, &w_, &f_, &z_prev_}) m->setZero(n_, 3);
  for (Vec* v : {&f0_, &ynew_, &scale_, &tmp_, &tmp2_, &err_, &r1_, &x1_}) v->setZero(n_);
  r2_.setZero(n_);
  x2_.setZero(n_);
  eta_old_ = 1.0;
  jac_point_ = JacPoint::start;
  fact_h_ = 0.0;
  fact_valid_ = jac_valid_ = f0_valid_ = have_prev_ = false;
  h_prev_ = 0.0;
  t_ = t0;
  h_ = 0.0;
  first_ = true;
  trial_pending_ = false;
  counts_ = {};
  ctrl_.reset();
  cached_y_ = nullptr;
}

void Radau5::ensure_jacobian(const OdeSystem& sys, double t, CVecRef y, SolveStats& stats) {
  if (jac_valid_) return;
  // Finite-difference Jacobians difference against f(t, y); an analytic one does not need it.
  if (!f0_valid_ && core_.jacobian_source() != JacobianSource::analytic) {
    sys.rhs(t, y, f0_);
    f0_valid_ = true;
  }
  core_.new_step();
  core_.update_jacobian(sys, t, y, f0_, stats);
  jac_valid_ = true;
  jac_point_ = JacPoint::start;
  fact_valid_ = false;
}

bool Radau5::ensure_factors(double h, SolveStats& stats) {
  if (fact_valid_ && h == fact_h_) return true;
  const Radau5Constants& k = k_;
  const SparseMat& jac = core_.jacobian_matrix();
  stats.linear_setups += 2;
  fact_h_ = h;
  fact_valid_ = real_.factor(k.gamma_hat / h, jac) &&
                complex_.factor(std::complex<double>(k.a, -k.b) / h, jac);
  return fact_valid_;
}

void Radau5::starting_values(double h) {
  if (!have_prev_) {
    z_.setZero();
    return;
  }
  // The previous step's collocation polynomial q(s), s = (t - t_{n-1})/h_prev, q(0) = 0,
  // q(c_j) = Z_j^prev, continued to the new stages: Z_i = q(1 + c_i h/h_prev) - Z_3^prev. With a
  // node at 0, q through (c_j, Z_j^prev) only (degree 2; y_{n+1} - y_n = Z_3^prev still).
  const Vec& c = tableau_.c;
  if (zero_node_) {
    for (int i = 0; i < 3; ++i) {
      const double s = 1.0 + c[i] * h / h_prev_;
      double l[3];
      for (int j = 0; j < 3; ++j) {
        l[j] = 1.0;
        for (int m = 0; m < 3; ++m)
          if (m != j) l[j] *= (s - c[m]) / (c[j] - c[m]);
      }
      z_.col(i) =
          l[0] * z_prev_.col(0) + l[1] * z_prev_.col(1) + l[2] * z_prev_.col(2) - z_prev_.col(2);
    }
    return;
  }
  for (int i = 0; i < 3; ++i) {
    const double s = 1.0 + c[i] * h / h_prev_;
    double l[3];
    for (int j = 0; j < 3; ++j) {
      l[j] = s / c[j];
      for (int m = 0; m < 3; ++m)
        if (m != j) l[j] *= (s - c[m]) / (c[j] - c[m]);
    }
    z_.col(i) =
        l[0] * z_prev_.col(0) + l[1] * z_prev_.col(1) + l[2] * z_prev_.col(2) - z_prev_.col(2);
  }
}

NewtonAttempt Radau5::solve_stages(const OdeSystem& sys, double t, CVecRef y, double h,
                                   bool adaptive, bool warm_start, SolveStats& stats) {
  const Radau5Constants& k = k_;
  const Vec& c = tableau_.c;
  const double eps = std::numeric_limits<double>::epsilon();
  double kappa = 1.0;
  if (adaptive) {
    const ControllerOptions& o = opt_.control;
    scale_ = o.atol + o.rtol * y.array().abs();
    kappa = std::max(10 * eps / o.rtol, std::min(0.03, std::sqrt(o.rtol)));
  } else {
    scale_ = 1.0 + y.array().abs();
  }
  if (!warm_start) starting_values(h);
  w_.noalias() = z_ * k.t_inv.transpose();
  double eta = std::pow(std::max(eta_old_, eps), 0.8);
  double norm_old = std::numeric_limits<double>::infinity();
  const int kmax = opt_.newton_max_iter;
  NewtonAttempt a;
  for (int it = 0; it < kmax; ++it) {
    for (int i = 0; i < 3; ++i) {
      tmp_ = y + z_.col(i);
      sys.rhs(t + c[i] * h, tmp_, f_.col(i));
    }
    if (!f_.allFinite()) {
      a.outcome = NewtonOutcome::non_finite;
      return a;
    }
    ++stats.newton_iters;
    a.iters = it + 1;
    // Right-hand sides (T⁻¹ ⊗ I) F - h⁻¹ (Λ ⊗ I) W of the three transformed blocks.
    r1_ = k.t_inv(0, 0) * f_.col(0) + k.t_inv(0, 1) * f_.col(1) + k.t_inv(0, 2) * f_.col(2) -
          (k.gamma_hat / h) * w_.col(0);
    tmp_ = k.t_inv(1, 0) * f_.col(0) + k.t_inv(1, 1) * f_.col(1) + k.t_inv(1, 2) * f_.col(2) -
           (k.a / h) * w_.col(1) - (k.b / h) * w_.col(2);
    tmp2_ = k.t_inv(2, 0) * f_.col(0) + k.t_inv(2, 1) * f_.col(1) + k.t_inv(2, 2) * f_.col(2) +
            (k.b / h) * w_.col(1) - (k.a / h) * w_.col(2);
    r2_.real() = tmp_;
    r2_.imag() = tmp2_;
    real_.solve(r1_, x1_);
    complex_.solve(r2_, x2_);
    stats.lin_solves += 2;
    double sum = 0.0;
    for (Index i = 0; i < n_; ++i) {
      const double s = scale_[i];
      const double q1 = x1_[i] / s, q2 = x2_[i].real() / s, q3 = x2_[i].imag() / s;
      sum += q1 * q1 + q2 * q2 + q3 * q3;
    }
    const double norm = std::sqrt(sum / static_cast<double>(3 * n_));
    a.dnorm = norm;
    if (!std::isfinite(norm)) {
      a.outcome = NewtonOutcome::non_finite;
      return a;
    }
    if (adaptive) {
      // RADAU5's rule: θ ≥ 0.99 fails; too slow to meet κ within the remaining iterations
      // fails; the first iteration may stop on η carried over from the previous step.
      if (it > 0) {
        const double theta = norm / norm_old;
        a.theta = theta;
        if (theta >= 0.99) {
          a.outcome = NewtonOutcome::diverging;
          return a;
        }
        eta = theta / (1.0 - theta);
        if (std::pow(theta, kmax - 1 - it) / (1.0 - theta) * norm > kappa) {
          a.outcome = NewtonOutcome::too_slow;
          return a;
        }
      }
    }
    w_.col(0) += x1_;
    w_.col(1) += x2_.real();
    w_.col(2) += x2_.imag();
    z_.noalias() = w_ * k.t.transpose();
    if (adaptive) {
      if (eta * norm <= kappa || norm == 0.0) {
        eta_old_ = eta;
        a.outcome = NewtonOutcome::converged;
        return a;
      }
    } else if (newton_update_converged(norm, norm_old, it > 0, opt_.newton_tol, it + 1, kmax, true,
                                       &a.outcome, &a.theta)) {
      return a;
    }
    norm_old = norm;
  }
  a.outcome = !adaptive && a.dnorm <= kNewtonNoise ? NewtonOutcome::converged
                                                   : NewtonOutcome::iteration_limit;
  return a;
}

double Radau5::estimate_error(const OdeSystem& sys, double t, CVecRef y, double h, bool refine,
                              SolveStats& stats) {
  const Radau5Constants& k = k_;
  const double g = k.gamma_hat / h;
  // (I - hγ_0 J)⁻¹ [γ_0 h f0 + Σ e_j Z_j] = (γ̂/h I - J)⁻¹ [f0 + (γ̂/h) Σ e_j Z_j].
  tmp2_ = (g * k.e[0]) * z_.col(0) + (g * k.e[1]) * z_.col(1) + (g * k.e[2]) * z_.col(2);
  r1_ = f0_ + tmp2_;
  real_.solve(r1_, err_);
  ++stats.lin_solves;
  double err = ctrl_.norm(err_, y, ynew_);
  if (refine && err >= 1.0) {
    tmp_ = y + err_;
    sys.rhs(t, tmp_, r1_);
    r1_ += tmp2_;
    real_.solve(r1_, err_);
    ++stats.lin_solves;
    err = ctrl_.norm(err_, y, ynew_);
  }
  return err;
}

void Radau5::accept_stages(double h) {
  z_prev_ = z_;
  h_prev_ = h;
  have_prev_ = true;
  f0_valid_ = false;
  if (opt_.frozen && jac_point_ != JacPoint::end) {
    jac_point_ = JacPoint::earlier_step;  // kept for the next step (refreshed on a failure)
  } else {
    jac_valid_ = false;
  }
}

Status Radau5::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  const bool continuing = have_prev_ && cached_y_ == y.data() &&
                          std::abs(cached_t_ - t) <= 1e-12 * (std::abs(t) + std::abs(h));
  if (!continuing) {
    have_prev_ = false;
    jac_valid_ = false;
    f0_valid_ = false;
  }
  ensure_jacobian(sys, t, y, stats);
  std::string reasons;
  // Attempt 1: J as configured (this step's (t, y), or frozen from an earlier step). A failure
  // with a J from an earlier step is retried with J fresh at (t, y); a failure with that J, with
  // J at the last finite iterate's end point (t + h, y + Z_3), from that iterate (the
  // linearisation where the stiff solution has moved to within the step). Each retry refactors.
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (!ensure_factors(h, stats)) {
      stats.message = info().name + ": singular iteration matrix at t = " + std::to_string(t) +
                      (reasons.empty() ? "" : " (after Newton failed: " + reasons + ")");
      return Status::solver_error;
    }
    const bool warm = attempt > 0 && jac_point_ == JacPoint::end;
    const NewtonAttempt a = solve_stages(sys, t, y, h, false, warm, stats);
    if (a.outcome == NewtonOutcome::converged) {
      y += z_.col(2);
      accept_stages(h);
      cached_y_ = y.data();
      cached_t_ = t + h;
      return Status::ok;
    }
    ++stats.newton_conv_failures;
    if (!reasons.empty()) reasons += "; then ";
    reasons += describe_newton_failure(a, opt_.newton_tol);
    reasons += jac_point_ == JacPoint::earlier_step ? " with J of an earlier step"
               : jac_point_ == JacPoint::start      ? " with J at the step's start"
                                                    : " with J at the step's end";
    if (jac_point_ == JacPoint::earlier_step) {
      jac_valid_ = false;  // fresh at (t, y)
      ensure_jacobian(sys, t, y, stats);
    } else if (jac_point_ == JacPoint::start) {
      // From a diverged iterate, the starting values' end point instead.
      if (a.outcome == NewtonOutcome::diverging || !z_.allFinite()) starting_values(h);
      if (!z_.allFinite() || z_.col(2).isZero(0.0)) break;  // no point other than (t, y)
      tmp_ = y + z_.col(2);
      if (core_.jacobian_source() != JacobianSource::analytic) sys.rhs(t + h, tmp_, tmp2_);
      core_.new_step();
      core_.update_jacobian(sys, t + h, tmp_, tmp2_, stats);
      jac_point_ = JacPoint::end;
      fact_valid_ = false;
    } else {
      break;
    }
  }
  have_prev_ = false;
  jac_valid_ = false;  // the J of the step's end is not the next step's (t, y)
  std::ostringstream msg;
  msg << info().name << ": Newton failed at t = " << t << " (h = " << h << "): " << reasons;
  stats.message = msg.str();
  return Status::newton_failed;
}

Status Radau5::advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) {
  cached_y_ = nullptr;  // fixed-step continuation does not apply
  if (h_ == 0.0) {
    if (!f0_valid_) {
      sys.rhs(t_, y, f0_);
      f0_valid_ = true;
    }
    // The error estimate is O(h⁴): the heuristic's p = 3.
    h_ = opt_.control.h0 > 0 ? std::min(opt_.control.h0, t_out - t_)
                             : ctrl_.initial_step(sys, t_, y, f0_, 3, t_out - t_, tmp_, tmp2_);
  }
  const auto trial = [&](double t, double h) {
    const bool after_reject = trial_pending_;
    trial_pending_ = true;
    if (!f0_valid_) {
      sys.rhs(t, y, f0_);  // the error estimate needs f(t_n, y_n)
      f0_valid_ = true;
    }
    ensure_jacobian(sys, t, y, stats);
    if (!ensure_factors(h, stats)) return TrialResult{0.0, 0.5};
    if (solve_stages(sys, t, y, h, true, false, stats).outcome != NewtonOutcome::converged) {
      ++stats.newton_conv_failures;
      // RADAU5: a failure with a J from an earlier step gets a fresh one; the step is halved.
      if (jac_point_ == JacPoint::earlier_step) jac_valid_ = false;
      return TrialResult{0.0, 0.5};
    }
    ynew_ = y + z_.col(2);
    return TrialResult{estimate_error(sys, t, y, h, first_ || after_reject, stats), 0.0};
  };
  const auto commit = [&](double, double h) {
    y = ynew_;
    accept_stages(h);
    first_ = false;
    trial_pending_ = false;
  };
  const Status st =
      advance_adaptive(ctrl_, t_, t_out, h_, y, counts_, stats.message, trial, commit);
  stats.steps = counts_.accepted;
  stats.error_test_failures = counts_.rejected;
  return st;
}

}  // namespace stiffbench
