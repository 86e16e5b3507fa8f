#include "integrators/implicit/gauss.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "integrators/method_file.hpp"

namespace stiffbench {

namespace {

std::string tableau_who(const ButcherTableau& t) {
  return "tableau '" + (t.name.empty() ? std::string("(unnamed)") : t.name) + "': ";
}

std::string num(double x) {
  std::ostringstream os;
  os.precision(3);
  os << x;
  return os.str();
}

// Smallest over largest singular value of m.
double inverse_condition(const Mat& m) {
  const Eigen::JacobiSVD<Mat> svd(m);
  const Vec& sv = svd.singularValues();
  return sv.size() == 0 || sv[0] == 0.0 ? 0.0 : sv[sv.size() - 1] / sv[0];
}

}  // namespace

IrkConstants irk_constants(const ButcherTableau& tab) {
  const std::string who = tableau_who(tab);
  const Index s = tab.a.rows();
  require_input(s >= 1 && tab.a.cols() == s && tab.b.size() == s && tab.a.allFinite(),
                who + "a fully implicit method needs A s x s and b with s entries, all finite");
  // A must be invertible: the stage equations are written in A⁻¹'s eigenbasis and dᵀ = bᵀA⁻¹.
  const double rcond_a = inverse_condition(tab.a);
  if (!(rcond_a > 1e-12)) {
    std::string row;
    for (Index i = 0; i < s && row.empty(); ++i)
      if (tab.a.row(i).isZero(0.0)) row = " (row " + std::to_string(i) + " of A is zero)";
    throw BadInput(who + "A is singular" + row + ": smallest/largest singular value " +
                   num(rcond_a) + "; a fully implicit method needs an invertible A");
  }
  const Mat ainv = tab.a.inverse();
  Eigen::EigenSolver<Mat> es(ainv);
  require_input(es.info() == Eigen::Success, who + "the eigenvalues of A^-1 could not be computed");
  IrkConstants k;
  k.t.resize(s, s);
  int col = 0;
  // Real eigenvalues first (|Im| below 1e-12 of the spectral radius; A⁻¹ of a Gauss method has
  // at most one), then one column pair per eigenvalue with positive imaginary part:
  // A⁻¹(u + iw) = (a + ib)(u + iw) gives A⁻¹u = a u - b w, A⁻¹w = b u + a w, so with columns
  // (u, w) the block of T⁻¹A⁻¹T is [[a, b], [-b, a]].
  const double scale = es.eigenvalues().cwiseAbs().maxCoeff();
  for (Index i = 0; i < s; ++i)
    if (std::abs(es.eigenvalues()[i].imag()) <= 1e-12 * scale) {
      k.t.col(col++) = es.eigenvectors().col(i).real();
      k.real.push_back(es.eigenvalues()[i].real());
    }
  for (Index i = 0; i < s; ++i)
    if (es.eigenvalues()[i].imag() > 1e-12 * scale && col + 2 <= s) {
      k.t.col(col++) = es.eigenvectors().col(i).real();
      k.t.col(col++) = es.eigenvectors().col(i).imag();
      k.a.push_back(es.eigenvalues()[i].real());
      k.b.push_back(es.eigenvalues()[i].imag());
    }
  require_input(col == s, who +
                              "the eigenvalues of A^-1 do not split into real ones and "
                              "complex-conjugate pairs");
  // Round-off in the transformed variables W = T⁻¹Z (where the Newton norm is measured) is
  // amplified up to cond(T): gauss4 3.7, gauss6 12.3, Radau IIA 8.6, Lobatto IIIC 3.6; an
  // SDIRK's A⁻¹, one Jordan block, comes out of the eigensolver as a pair split by about √ε
  // with cond(T) ~ 1e8.
  const double rcond_t = inverse_condition(k.t);
  if (!(rcond_t >= 1e-4))
    throw BadInput(who +
                   "A^-1 has a repeated eigenvalue without a full set of eigenvectors, or nearly "
                   "so: its eigenvector basis has condition number " +
                   num(1.0 / rcond_t) +
                   " (above 1e4 the transformed Newton iteration would amplify round-off by "
                   "that much); it needs A^-1 diagonalisable with well-separated eigenvalues");
  k.t_inv = k.t.inverse();
  k.lambda = k.t_inv * ainv * k.t;
  // The blocks must describe A⁻¹ itself (T Λ_blocks⁻¹ T⁻¹ = A to round-off), else the Newton
  // iteration would solve another method.
  Mat blocks = Mat::Zero(s, s);
  Index j = 0;
  for (const double g : k.real) blocks(j, j) = g, ++j;
  for (std::size_t p = 0; p < k.a.size(); ++p, j += 2) {
    blocks(j, j) = blocks(j + 1, j + 1) = k.a[p];
    blocks(j, j + 1) = k.b[p];
    blocks(j + 1, j) = -k.b[p];
  }
  const double defect = (k.t * blocks.inverse() * k.t_inv - tab.a).cwiseAbs().maxCoeff() /
                        std::max(1.0, tab.a.cwiseAbs().maxCoeff());
  if (!(defect <= 1e-12))
    throw BadInput(who +
                   "A^-1 is not diagonalisable to round-off (A rebuilt from its "
                   "eigenvectors differs by " +
                   num(defect) + ")");
  k.d = ainv.transpose() * tab.b;
  return k;
}

namespace {

// dst.col(i) = Σ_j coef(i, j) src.col(j) (dst = src coefᵀ), column by column: no temporaries.
void combine_columns(const Mat& src, const Mat& coef, Mat& dst) {
  for (Index i = 0; i < dst.cols(); ++i) {
    dst.col(i) = coef(i, 0) * src.col(0);
    for (Index j = 1; j < src.cols(); ++j) dst.col(i) += coef(i, j) * src.col(j);
  }
}

}  // namespace

const ButcherTableau& gauss_tableau(int stages) {
  if (stages == 2) return built_in_method("gauss4").tableau;
  if (stages == 3) return built_in_method("gauss6").tableau;
  throw std::logic_error("gauss_tableau: 2 or 3 stages");
}

const GaussConstants& gauss_constants(int stages) {
  static const GaussConstants k2 = irk_constants(gauss_tableau(2)),
                              k3 = irk_constants(gauss_tableau(3));
  if (stages == 2) return k2;
  if (stages == 3) return k3;
  throw std::logic_error("gauss_constants: 2 or 3 stages");
}

std::vector<ParamSpec> gauss_param_specs() {
  using P = ParamType;
  using B = Bounds;
  return {
      {"newton_tol", P::real, "1e-15",
       "Newton stops when its predicted error is below newton_tol (1 + |y|) in the RMS norm, or "
       "when the update stagnates below it (round-off); looser values perturb the symplectic map",
       B::positive()},
      {"newton_max_iter", P::integer, "20", "simplified Newton iterations per step",
       B::at_least(1)},
      {"jacobian",
       P::text,
       "auto",
       "analytic, fd_dense, fd_colored (over the model's pattern); auto: analytic where "
       "provided, else fd_colored over a pattern, else fd_dense",
       {"auto", "analytic", "fd_dense", "fd_colored"}},
      {"linear_solver",
       P::text,
       "auto",
       "dense_lu or sparse_lu for the transformed n x n systems; auto: dense_lu up to 50 "
       "unknowns, and up to 200 unless the Jacobian's pattern fills under 10%; sparse_lu "
       "otherwise",
       {"auto", "dense_lu", "sparse_lu"}},
  };
}

GaussOptions read_gauss_options(const Params& p) {
  const NewtonOptions n = read_newton_options(p);
  GaussOptions o;
  o.newton_tol = n.tol;
  o.newton_max_iter = n.max_iter;
  o.jacobian = n.jacobian;
  o.linear = n.linear;
  return o;
}

namespace {

// The tableau checked against its claims (sizes, c completed from the row sums or checked,
// claimed order) before the constants are derived from it.
ButcherTableau validated_irk(ButcherTableau t) {
  t.validate(ButcherTableau::Shape::any);
  return t;
}

}  // namespace

ImplicitRungeKutta::ImplicitRungeKutta(ButcherTableau tableau, std::string description,
                                       GaussOptions opt)
    : Integrator({tableau.name,
                  Family::implicit,
                  tableau.order,
                  tableau.stages(),
                  {},
                  std::move(description)}),
      tableau_(validated_irk(std::move(tableau))),
      k_(irk_constants(tableau_)),
      s_(tableau_.stages()),
      opt_(opt),
      core_(first_order_core_options(opt.jacobian, opt.linear)) {
  const Vec& c = tableau_.c;
  interpolate_ = true;
  for (int i = 0; i < s_; ++i) {
    zero_node_ = zero_node_ || c[i] == 0.0;
    for (int j = 0; j < i; ++j) interpolate_ = interpolate_ && c[i] != c[j];
  }
  real_.resize(k_.real.size());
  complex_.resize(k_.a.size());
}

void ImplicitRungeKutta::reset(const OdeSystem& sys, double t0, CVecRef y0) {
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
  for (auto& r : real_) r.reset(n_, dense);
  for (auto& c : complex_) c.reset(n_, dense);
  restart_state();
}

void ImplicitRungeKutta::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();
  restart_state();
}

void ImplicitRungeKutta::restart_state() {
  for (Mat* m : {&z_, &w_, &f_, &z_prev_}) m->setZero(n_, s_);
  for (Vec* v : {&f0_, &scale_, &tmp_, &r1_, &x1_}) v->setZero(n_);
  r2_.setZero(n_);
  x2_.setZero(n_);
  h_prev_ = 0.0;
  have_prev_ = false;
  cached_y_ = nullptr;
}

void ImplicitRungeKutta::starting_values(double h) {
  if (!have_prev_ || !interpolate_) {
    z_.setZero();
    return;
  }
  const Vec& c = tableau_.c;
  if (zero_node_) {
    // A node at 0 (Lobatto): q through the s points (c_j, Z_j^prev) only, continued to the new
    // nodes relative to the new y_n: Z_i = q(1 + c_i h/h_prev) - Σ_j d_j Z_j^prev.
    const auto lagrange = [&](double x, int j) {
      double l = 1.0;
      for (int m = 0; m < s_; ++m)
        if (m != j) l *= (x - c[m]) / (c[j] - c[m]);
      return l;
    };
    for (int i = 0; i < s_; ++i) {
      const double x = 1.0 + c[i] * h / h_prev_;
      z_.col(i).setZero();
      for (int j = 0; j < s_; ++j) z_.col(i) += (lagrange(x, j) - k_.d[j]) * z_prev_.col(j);
    }
    return;
  }
  // The previous step's collocation polynomial q(σ), σ = (t - t_{n-1})/h_prev, through q(0) = 0
  // and q(c_j) = Z_j^prev, continued to the new nodes: Z_i = q(1 + c_i h/h_prev) - q(1).
  const auto basis = [&](double x, int j) {
    double l = x / c[j];
    for (int m = 0; m < s_; ++m)
      if (m != j) l *= (x - c[m]) / (c[j] - c[m]);
    return l;
  };
  for (int i = 0; i < s_; ++i) {
    const double x = 1.0 + c[i] * h / h_prev_;
    z_.col(i).setZero();
    for (int j = 0; j < s_; ++j) z_.col(i) += (basis(x, j) - basis(1.0, j)) * z_prev_.col(j);
  }
}

NewtonAttempt ImplicitRungeKutta::solve_stages(const OdeSystem& sys, double t, CVecRef y, double h,
                                               SolveStats& stats) {
  const Vec& c = tableau_.c;
  scale_ = 1.0 + y.array().abs();
  starting_values(h);
  combine_columns(z_, k_.t_inv, w_);
  const std::size_t nr = k_.real.size();
  double norm_old = std::numeric_limits<double>::infinity();
  NewtonAttempt res;
  for (int it = 0; it < opt_.newton_max_iter; ++it) {
    for (int i = 0; i < s_; ++i) {
      tmp_ = y + z_.col(i);
      sys.rhs(t + c[i] * h, tmp_, f_.col(i));
    }
    if (!f_.allFinite()) {
      res.outcome = NewtonOutcome::non_finite;
      return res;
    }
    ++stats.newton_iters;
    res.iters = it + 1;
    double sum = 0.0;
    // Real blocks: (γ/h I - J) ΔW_j = (T⁻¹F)_j - (γ/h) W_j.
    for (std::size_t r = 0; r < nr; ++r) {
      const Index j = static_cast<Index>(r);
      r1_ = (-k_.real[r] / h) * w_.col(j);
      for (int i = 0; i < s_; ++i) r1_ += k_.t_inv(j, i) * f_.col(i);
      real_[r].solve(r1_, x1_);
      ++stats.lin_solves;
      w_.col(j) += x1_;
      sum += (x1_.array() / scale_.array()).square().sum();
    }
    // Complex pairs: ((a - ib)/h I - J)(ΔW_j + iΔW_{j+1}) = r_j + i r_{j+1}.
    for (std::size_t p = 0; p < k_.a.size(); ++p) {
      const Index j = static_cast<Index>(nr + 2 * p);
      const double a = k_.a[p] / h, b = k_.b[p] / h;
      tmp_ = -a * w_.col(j) - b * w_.col(j + 1);
      for (int i = 0; i < s_; ++i) tmp_ += k_.t_inv(j, i) * f_.col(i);
      r2_.real() = tmp_;
      tmp_ = b * w_.col(j) - a * w_.col(j + 1);
      for (int i = 0; i < s_; ++i) tmp_ += k_.t_inv(j + 1, i) * f_.col(i);
      r2_.imag() = tmp_;
      complex_[p].solve(r2_, x2_);
      ++stats.lin_solves;
      w_.col(j) += x2_.real();
      w_.col(j + 1) += x2_.imag();
      sum += (x2_.real().array() / scale_.array()).square().sum() +
             (x2_.imag().array() / scale_.array()).square().sum();
    }
    combine_columns(w_, k_.t, z_);
    const double norm = std::sqrt(sum / static_cast<double>(s_ * n_));
    res.dnorm = norm;
    if (newton_update_converged(norm, norm_old, it > 0, opt_.newton_tol, it + 1,
                                opt_.newton_max_iter, true, &res.outcome, &res.theta))
      return res;
    norm_old = norm;
  }
  res.outcome =
      res.dnorm <= kNewtonNoise ? NewtonOutcome::converged : NewtonOutcome::iteration_limit;
  return res;
}

Status ImplicitRungeKutta::step(const OdeSystem& sys, double t, VecRef y, double h,
                                SolveStats& stats) {
  const bool continuing = have_prev_ && cached_y_ == y.data() &&
                          std::abs(cached_t_ - t) <= 1e-12 * (std::abs(t) + std::abs(h));
  if (!continuing) have_prev_ = false;
  // J at (t_n, y_n); finite differences difference against f(t_n, y_n).
  if (core_.jacobian_source() != JacobianSource::analytic) sys.rhs(t, y, f0_);
  core_.new_step();
  core_.update_jacobian(sys, t, y, f0_, stats);
  const SparseMat& jac = core_.jacobian_matrix();
  bool ok = true;
  for (std::size_t r = 0; r < real_.size(); ++r) {
    ++stats.linear_setups;
    ok = ok && real_[r].factor(k_.real[r] / h, jac);
  }
  for (std::size_t p = 0; p < complex_.size(); ++p) {
    ++stats.linear_setups;
    ok = ok && complex_[p].factor(std::complex<double>(k_.a[p], -k_.b[p]) / h, jac);
  }
  if (!ok) {
    stats.message = info().name + ": singular iteration matrix at t = " + std::to_string(t);
    return Status::solver_error;
  }
  if (const NewtonAttempt a = solve_stages(sys, t, y, h, stats);
      a.outcome != NewtonOutcome::converged) {
    ++stats.newton_conv_failures;
    have_prev_ = false;
    std::ostringstream msg;
    msg << info().name << ": simplified Newton failed at t = " << t << " (h = " << h
        << "): " << describe_newton_failure(a, opt_.newton_tol);
    stats.message = msg.str();
    return Status::newton_failed;
  }
  for (int j = 0; j < s_; ++j) y += k_.d[j] * z_.col(j);
  z_prev_ = z_;
  h_prev_ = h;
  have_prev_ = true;
  cached_y_ = y.data();
  cached_t_ = t + h;
  return Status::ok;
}

}  // namespace stiffbench
