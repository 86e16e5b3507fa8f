#include "core/ode_system.hpp"

#include <cmath>

namespace stiffbench {

void OdeSystem::exact(double, VecRef) const {
  throw BadInput("model '" + name() + "' has no exact solution");
}

void OdeSystem::eval_jacobian(double, CVecRef, SparseMat&) const {
  throw BadInput("model '" + name() + "' provides no analytic Jacobian");
}

SparseMat OdeSystem::jacobian_pattern() const {
  if (!has_jacobian())
    throw BadInput("model '" + name() + "' provides no Jacobian sparsity pattern");
  SparseMat jac;
  const Vec y0 = initial_state();
  eval_jacobian(initial_time(), y0, jac);  // structure only: not counted as an evaluation
  jac.makeCompressed();
  for (Index k = 0; k < jac.nonZeros(); ++k) jac.valuePtr()[k] = 1.0;
  return jac;
}

void MechanicalSystem::stiffness_block(double, CVecRef, CVecRef, SparseMat&) const {
  throw BadInput("model '" + name() + "' provides no stiffness block K = da/dx");
}

void MechanicalSystem::damping_block(double, CVecRef, CVecRef, SparseMat&) const {
  throw BadInput("model '" + name() + "' provides no damping block D = da/dv");
}

void MechanicalSystem::force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k,
                                       SparseMat& d) const {
  stiffness_block(t, x, v, k);
  damping_block(t, x, v, d);
}

void MechanicalSystem::eval_rhs(double t, CVecRef y, VecRef dydt) const {
  const Index n = dofs();
  // x' = v: a copy, over OpenMP threads for large systems (an explicit Runge-Kutta step makes
  // one per stage; serial, it was the one unthreaded pass of a cloth 512² rk4 stage).
  if (n >= 100000) {
    const double* src = y.data() + n;
    double* dst = dydt.data();
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) dst[i] = src[i];
  } else {
    dydt.head(n) = y.tail(n);
  }
  eval_acceleration(t, y.head(n), y.tail(n), dydt.tail(n));
}

void MechanicalSystem::eval_acceleration_in_ranges(double t, CVecRef x, CVecRef v, VecRef a,
                                                   DofRangeFn done) const {
  eval_acceleration(t, x, v, a);
  const Index n = dofs();
  if (n >= 50000) {  // as the explicit Runge-Kutta passes: 64 contiguous ranges over the threads
    const Index chunks = 64;
#pragma omp parallel for schedule(static)
    for (Index q = 0; q < chunks; ++q) done(n * q / chunks, n * (q + 1) / chunks);
  } else if (n > 0) {
    done(0, n);
  }
}

void OdeSystem::eval_implicit_part_jacobian(double, CVecRef, SparseMat&) const {
  throw BadInput("model '" + name() + "' provides no Jacobian of the implicit part of its split");
}

void MechanicalSystem::implicit_force_jacobians(double, CVecRef, CVecRef, SparseMat&,
                                                SparseMat&) const {
  throw BadInput("model '" + name() + "' provides no force Jacobians of its split's implicit part");
}

void MechanicalSystem::eval_acceleration_explicit_part(double, CVecRef, CVecRef, VecRef) const {
  throw BadInput("model '" + name() + "' has no additive split (no explicit part)");
}

void MechanicalSystem::eval_acceleration_implicit_part(double, CVecRef, CVecRef, VecRef) const {
  throw BadInput("model '" + name() + "' has no additive split (no implicit part)");
}

void MechanicalSystem::eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const {
  const Index n = dofs();
  fe.head(n).setZero();
  eval_acceleration_explicit_part(t, y.head(n), y.tail(n), fe.tail(n));
}

void MechanicalSystem::eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const {
  const Index n = dofs();
  fi.head(n) = y.tail(n);
  eval_acceleration_implicit_part(t, y.head(n), y.tail(n), fi.tail(n));
}

namespace {
// [[0, I], [K, D]] for a mechanical system with n dofs.
void assemble_first_order(Index n, const SparseMat& k, const SparseMat& d, SparseMat& jac) {
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(static_cast<std::size_t>(n + k.nonZeros() + d.nonZeros()));
  for (Index i = 0; i < n; ++i) trips.emplace_back(i, n + i, 1.0);
  for (Index c = 0; c < k.outerSize(); ++c)
    for (SparseMat::InnerIterator it(k, c); it; ++it)
      trips.emplace_back(n + it.row(), it.col(), it.value());
  for (Index c = 0; c < d.outerSize(); ++c)
    for (SparseMat::InnerIterator it(d, c); it; ++it)
      trips.emplace_back(n + it.row(), n + it.col(), it.value());
  jac.resize(2 * n, 2 * n);
  jac.setFromTriplets(trips.begin(), trips.end());
}
}  // namespace

void MechanicalSystem::eval_jacobian(double t, CVecRef y, SparseMat& jac) const {
  // J = [[0, I], [K, D]]: x' = v contributes the identity block.
  const Index n = dofs();
  SparseMat k, d;
  stiffness_block(t, y.head(n), y.tail(n), k);
  damping_block(t, y.head(n), y.tail(n), d);
  assemble_first_order(n, k, d, jac);
}

void MechanicalSystem::eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const {
  const Index n = dofs();
  SparseMat k, d;
  implicit_force_jacobians(t, y.head(n), y.tail(n), k, d);
  assemble_first_order(n, k, d, jac);
}

double fd_increment(double yj, double y_norm) {
  constexpr double kCbrtEps = 6.0554544523933395e-06;  // (2^-52)^(1/3)
  const double scale = std::max(std::abs(yj), 1e-3 * y_norm);
  return kCbrtEps * (scale > 0 ? scale : 1.0);
}

Mat finite_difference_jacobian(const OdeSystem& sys, double t, CVecRef y) {
  const Index n = y.size();
  Mat jac(n, n);
  Vec fp(n), fm(n), yp = y;
  const double y_norm = y.cwiseAbs().maxCoeff();
  for (Index j = 0; j < n; ++j) {
    const double d = fd_increment(y[j], y_norm);
    yp[j] = y[j] + d;
    const double up = yp[j] - y[j];  // representable increments actually applied
    sys.rhs(t, yp, fp);
    yp[j] = y[j] - d;
    const double down = y[j] - yp[j];
    sys.rhs(t, yp, fm);
    jac.col(j) = (fp - fm) / (up + down);
    yp[j] = y[j];
  }
  return jac;
}

double gershgorin_bound(const SparseMat& jac) {
  Vec rows = Vec::Zero(jac.rows()), cols = Vec::Zero(jac.cols());
  for (Index c = 0; c < jac.outerSize(); ++c)
    for (SparseMat::InnerIterator it(jac, c); it; ++it) {
      rows[it.row()] += std::abs(it.value());
      cols[it.col()] += std::abs(it.value());
    }
  return std::min(rows.maxCoeff(), cols.maxCoeff());
}

double max_abs_diff(CVecRef a, CVecRef b) { return (a - b).cwiseAbs().maxCoeff(); }

}  // namespace stiffbench
