#include "integrators/symplectic/verlet.hpp"

namespace stiffbench {

namespace {
constexpr Requirements kVerletNeeds{true, true, false};
}

PositionVerlet::PositionVerlet()
    : Integrator({"verlet", Family::symplectic, 2, 1, kVerletNeeds,
                  "two-step position Verlet x+ = 2x - x- + h^2 a(x); Taylor start-up; "
                  "central-difference velocities"}) {}

void PositionVerlet::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  const Index n = mech_->dofs();
  x_prev_.resize(n);
  x_last_.resize(n);
  acc_.resize(n);
  x_next_.resize(n);
  started_ = false;
}

Status PositionVerlet::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_) throw std::logic_error("PositionVerlet::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  if (!started_ || h != h_last_ || x != x_last_) {
    // Start-up: one Taylor step from (x0, v0).
    mech_->acceleration(t, x, v, acc_);
    x_next_ = x + h * v + (0.5 * h * h) * acc_;
    started_ = true;
  } else {
    // acc_ holds a(t, x_n) from the previous step's look-ahead.
    x_next_ = 2.0 * x - x_prev_ + (h * h) * acc_;
  }
  x_prev_ = x;
  x = x_next_;
  mech_->acceleration(t + h, x, v, acc_);  // a(x_{n+1}); v is ignored (velocity-independent)
  v = (x - x_prev_) / h + (0.5 * h) * acc_;
  x_last_ = x;
  h_last_ = h;
  return Status::ok;
}

Leapfrog::Leapfrog()
    : Integrator({"leapfrog", Family::symplectic, 2, 1, kVerletNeeds,
                  "kick-drift leapfrog with half-step velocities; half-step start-up; reports the "
                  "synchronised velocity"}) {}

void Leapfrog::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  const Index n = mech_->dofs();
  v_half_.resize(n);
  x_last_.resize(n);
  acc_.resize(n);
  started_ = false;
}

Status Leapfrog::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_) throw std::logic_error("Leapfrog::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  if (!started_ || h != h_last_ || x != x_last_) {
    mech_->acceleration(t, x, v, acc_);
    v_half_ = v + (0.5 * h) * acc_;  // start-up half kick
    started_ = true;
  } else {
    v_half_ += h * acc_;  // acc_ = a(x_n) from the previous step
  }
  x += h * v_half_;
  mech_->acceleration(t + h, x, v_half_, acc_);
  v = v_half_ + (0.5 * h) * acc_;
  x_last_ = x;
  h_last_ = h;
  return Status::ok;
}

}  // namespace stiffbench
