#include "integrators/implicit/bdf2.hpp"

#include "integrators/method_entry.hpp"

namespace stiffbench {

constexpr MethodText kBdf2Text{
    .description = "two-step backward differentiation formula; sdirk2 start-up step",
    .kind = "multistep (BDF)",
    .reference = cite(kHairerWanner, "Sect. V.1 (Curtiss & Hirschfelder 1952)")};

Bdf2Integrator::Bdf2Integrator(ImplicitOptions opt)
    : Integrator(method_info("bdf2", Family::implicit, 2, 1, {}, kBdf2Text)),
      core_(std::move(opt)),
      startup_(implicit_tableau("sdirk2")) {}

void Bdf2Integrator::restart(const OdeSystem& sys, double t, CVecRef y) {
  if (core_.system() != &sys) return reset(sys, t, y);
  core_.restart();
  started_ = false;  // the next step starts with sdirk2 again
}

void Bdf2Integrator::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  core_.reset(sys, t0, y0);
  const Index n = sys.dimension();
  startup_.reset(n);
  y_prev_.resize(n);
  y_last_.resize(n);
  psi_.resize(n);
  z_.resize(n);
  fz_.resize(n);
  started_ = false;
}

Status Bdf2Integrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (!started_ || h != h_last_ || y != y_last_) {
    y_prev_ = y;
    const Status st = startup_.step(core_, sys, t, y, h, stats);
    if (st != Status::ok) return st;
  } else {
    core_.new_step();
    psi_ = (4.0 / 3.0) * y - (1.0 / 3.0) * y_prev_;
    z_ = 2.0 * y - y_prev_;
    const Status st = core_.solve_stage(sys, t + h, psi_, (2.0 / 3.0) * h, z_, fz_, stats);
    if (st != Status::ok) return st;
    y_prev_ = y;
    y = z_;
  }
  y_last_ = y;
  h_last_ = h;
  started_ = true;
  return Status::ok;
}

}  // namespace stiffbench
