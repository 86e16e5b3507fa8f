#include "integrators/implicit/baraff_witkin.hpp"

namespace stiffbench {

BaraffWitkin::BaraffWitkin(ImplicitOptions opt)
    : Integrator({"baraff_witkin", Family::implicit, 1, 1, Requirements{true, false, true},
                  "Baraff-Witkin semi-implicit Euler in velocity form (M - hD - h^2 K) dv = "
                  "h (f + h K v)"}),
      opt_(std::move(opt)) {}

std::vector<SparseTerm> BaraffWitkin::terms(double h) const {
  return {{1.0, &mass_, nullptr}, {-h, &d_, &m_}, {-h * h, &k_, &m_}};
}

void BaraffWitkin::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  require_input(
      opt_.jacobian == JacobianSource::automatic || opt_.jacobian == JacobianSource::analytic,
      "baraff_witkin uses the model's K and D blocks: parameter 'jacobian' must be auto or "
      "analytic");
  mech_ = sys.as_mechanical();
  const Index n = mech_->dofs();
  m_ = mech_->masses();
  mass_.resize(n, n);
  std::vector<Eigen::Triplet<double>> diag;
  for (Index i = 0; i < n; ++i) diag.emplace_back(i, i, m_[i]);
  mass_.setFromTriplets(diag.begin(), diag.end());
  mass_.makeCompressed();
  mech_->stiffness_block(t0, y0.head(n), y0.tail(n), k_);
  mech_->damping_block(t0, y0.head(n), y0.tail(n), d_);
  k_.makeCompressed();
  d_.makeCompressed();
  solver_ = make_linear_solver(opt_.linear, n);
  a_.build(terms(0.0));
  solver_->analyze(a_.matrix());
  acc_.resize(n);
  rhs_.resize(n);
  dv_.resize(n);
}

Status BaraffWitkin::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (&sys != mech_) throw std::logic_error("BaraffWitkin::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  mech_->acceleration(t, x, v, acc_);
  mech_->stiffness_block(t, x, v, k_);
  mech_->damping_block(t, x, v, d_);
  k_.makeCompressed();
  d_.makeCompressed();
  ++stats.jac_evals;
  const auto tr = terms(h);
  if (!a_.same_patterns(tr)) {
    a_.build(tr);
    solver_->analyze(a_.matrix());
  }
  a_.assemble(tr);
  ++stats.lin_setups;
  if (!solver_->factor(a_.matrix())) {
    stats.message = "baraff_witkin: matrix M - hD - h^2 K singular (or not symmetric for " +
                    to_string(solver_->kind()) + ") at t = " + std::to_string(t);
    return Status::solver_error;
  }
  // rhs = h M (a + h K v)
  rhs_.noalias() = k_ * v;
  rhs_ = h * m_.cwiseProduct(acc_ + h * rhs_);
  dv_.setZero();
  ++stats.lin_solves;
  const LinearSolveResult r = solver_->solve(rhs_, dv_);
  stats.krylov_iters += r.iterations;
  if (!r.ok || !dv_.allFinite()) {
    stats.message = "baraff_witkin: linear solve failed at t = " + std::to_string(t);
    return Status::solver_error;
  }
  v += dv_;
  x += h * v;
  return Status::ok;
}

}  // namespace stiffbench
