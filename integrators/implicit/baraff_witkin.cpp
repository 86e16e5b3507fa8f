#include "integrators/implicit/baraff_witkin.hpp"

#include <sstream>

#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {
constexpr MethodText kBaraffWitkinText{
    .description =
        "Baraff-Witkin semi-implicit Euler in velocity form (M - hD - h^2 K) dv = "
        "h (f + h K v)",
    .kind = "linearly implicit (velocity form)",
    .reference = "D. Baraff & A. Witkin, Large steps in cloth simulation, SIGGRAPH 1998, 43-54"};
}  // namespace

BaraffWitkin::BaraffWitkin(ImplicitOptions opt)
    : Integrator(method_info("baraff_witkin", Family::implicit, 1, 1,
                             Requirements{true, false, true}, kBaraffWitkinText)),
      opt_(std::move(opt)) {}

void BaraffWitkin::reset(const OdeSystem& sys, double t0, CVecRef y0) {
  check_compatible(info(), sys);
  require_input(
      opt_.jacobian == JacobianSource::automatic || opt_.jacobian == JacobianSource::analytic,
      "baraff_witkin uses the model's K and D blocks: parameter 'jacobian' must be auto or "
      "analytic");
  mech_ = sys.as_mechanical();
  solver_.reset(*mech_, opt_.linear, t0, y0);
  r_.resize(sys.dimension());
  k_ = Vec::Zero(sys.dimension());  // k_'s velocity half: the previous Δv (Krylov warm start)
}

Status BaraffWitkin::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (&sys != mech_) throw std::logic_error("BaraffWitkin::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  // r = h f(t, y) = [h v; h a]: the velocity-form solve then gives Δv = k_v and h v⁺ = k_x.
  mech_->acceleration(t, x, v, r_.tail(n));
  r_.tail(n) *= h;
  r_.head(n) = h * v;
  solver_.update(t, y);
  ++stats.jac_evals;
  ++stats.linear_setups;
  const auto fail = [&](const char* what) {
    std::ostringstream msg;
    msg << "baraff_witkin: " << what << " at t = " << t << ": " << solver_.error();
    stats.message = msg.str();
    return Status::solver_error;
  };
  if (!solver_.factor(h)) return fail("matrix M - hD - h^2 K refused");
  ++stats.lin_solves;
  const LinearSolveResult r = solver_.solve(r_, k_);
  stats.linear_iters += r.iterations;
  if (!r.ok) return fail("linear solve failed");
  if (!k_.allFinite()) return fail("non-finite solution");
  v += k_.tail(n);
  x += k_.head(n);
  return Status::ok;
}

}  // namespace stiffbench
