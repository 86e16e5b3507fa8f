#include "integrators/symplectic/verlet.hpp"

#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {
constexpr Requirements kVerletNeeds{true, true, false};

// body(i) for i in [0, n), over OpenMP threads when n is large (entries are independent).
constexpr Index kParallelEntries = 50000;
template <class Body>
void for_entries(Index n, const Body& body) {
  if (n >= kParallelEntries) {
#pragma omp parallel for schedule(static)
    for (Index i = 0; i < n; ++i) body(i);
  } else {
    for (Index i = 0; i < n; ++i) body(i);
  }
}

// Whether a two-step method must start again: first step, new h, another state storage, or
// (constrained systems, whose projection moves x) another position than the one returned.
bool must_restart(bool started, double h, double h_last, const double* y, const double* y_last,
                  const MechanicalSystem& sys, CVecRef x, const Vec& x_last) {
  return !started || h != h_last || y != y_last || (sys.has_constraints() && x != x_last);
}
}  // namespace

constexpr MethodText kPositionVerletText{
    .description =
        "two-step position Verlet x+ = 2x - x- + h^2 a(x); Taylor start-up; "
        "central-difference velocities",
    .kind = "two-step (Stormer-Verlet)",
    .reference = "L. Verlet, Phys. Rev. 159 (1967) 98-103"};

PositionVerlet::PositionVerlet()
    : Integrator(
          method_info("verlet", Family::symplectic, 2, 1, kVerletNeeds, kPositionVerletText)) {}

void PositionVerlet::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  const Index n = mech_->dofs();
  x_prev_.resize(n);
  x_last_.resize(sys.has_constraints() ? n : 0);
  acc_.resize(n);
  y_last_ = nullptr;
  started_ = false;
}

Status PositionVerlet::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_) throw std::logic_error("PositionVerlet::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  double* xp = x.data();
  double* vp = v.data();
  double* prev = x_prev_.data();
  const double* ap = acc_.data();
  if (must_restart(started_, h, h_last_, y.data(), y_last_, *mech_, x, x_last_)) {
    // Start-up: one Taylor step from (x0, v0).
    mech_->acceleration(t, x, v, acc_);
    const double c = 0.5 * h * h;
    for_entries(n, [&](Index i) {
      const double next = xp[i] + h * vp[i] + c * ap[i];
      prev[i] = xp[i];
      xp[i] = next;
    });
    started_ = true;
  } else {
    // acc_ holds a(t, x_n) from the previous step's look-ahead.
    const double hh = h * h;
    for_entries(n, [&](Index i) {
      const double next = 2.0 * xp[i] - prev[i] + hh * ap[i];
      prev[i] = xp[i];
      xp[i] = next;
    });
  }
  mech_->acceleration(t + h, x, v, acc_);  // a(x_{n+1}); v is ignored (velocity-independent)
  const double half_h = 0.5 * h;
  for_entries(n, [&](Index i) { vp[i] = (xp[i] - prev[i]) / h + half_h * ap[i]; });
  if (mech_->has_constraints()) x_last_ = x;
  y_last_ = y.data();
  h_last_ = h;
  return Status::ok;
}

constexpr MethodText kLeapfrogText{
    .description =
        "kick-drift leapfrog with half-step velocities; half-step start-up; reports "
        "the synchronised velocity",
    .kind = "splitting (staggered)",
    .reference =
        "R. W. Hockney & J. W. Eastwood, Computer Simulation Using Particles, McGraw-Hill 1981"};

Leapfrog::Leapfrog()
    : Integrator(method_info("leapfrog", Family::symplectic, 2, 1, kVerletNeeds, kLeapfrogText)) {}

void Leapfrog::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  const Index n = mech_->dofs();
  v_half_.resize(n);
  x_last_.resize(sys.has_constraints() ? n : 0);
  acc_.resize(n);
  y_last_ = nullptr;
  started_ = false;
}

Status Leapfrog::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_) throw std::logic_error("Leapfrog::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  double* xp = x.data();
  double* vp = v.data();
  double* half = v_half_.data();
  const double* ap = acc_.data();
  if (must_restart(started_, h, h_last_, y.data(), y_last_, *mech_, x, x_last_)) {
    mech_->acceleration(t, x, v, acc_);
    const double half_h = 0.5 * h;
    for_entries(n, [&](Index i) {
      half[i] = vp[i] + half_h * ap[i];  // start-up half kick
      xp[i] += h * half[i];
    });
    started_ = true;
  } else {
    for_entries(n, [&](Index i) {
      half[i] += h * ap[i];  // acc_ = a(x_n) from the previous step
      xp[i] += h * half[i];
    });
  }
  mech_->acceleration(t + h, x, v_half_, acc_);
  const double half_h = 0.5 * h;
  for_entries(n, [&](Index i) { vp[i] = half[i] + half_h * ap[i]; });
  if (mech_->has_constraints()) x_last_ = x;
  y_last_ = y.data();
  h_last_ = h;
  return Status::ok;
}

}  // namespace stiffbench
