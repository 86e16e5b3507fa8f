#include "integrators/symplectic/rattle.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "integrators/method_entry.hpp"

namespace stiffbench {

namespace {
// A mechanical system with velocity-independent forces that offers holonomic constraints.
constexpr Requirements kRattleNeeds{true, true, false, true};

double max_abs(CVecRef z) { return z.size() == 0 ? 0.0 : z.cwiseAbs().maxCoeff(); }
}  // namespace

std::vector<ParamSpec> rattle_param_specs() {
  using P = ParamType;
  using B = Bounds;
  return {
      {"constraint_tol", P::real, "1e-14",
       "Newton on the multipliers stops when max|g(x)| <= constraint_tol max(1, |x|inf); the "
       "velocity projection when max|G(x) v| <= constraint_tol max(1, |v|inf)",
       B::positive()},
      {"newton_max_iter", P::integer, "20",
       "Newton iterations per step for the position constraint (typically 2-3 are needed); "
       "without convergence the step fails (newton_failed)",
       B::in(1, 1000)},
  };
}

RattleOptions read_rattle_options(const Params& p) {
  RattleOptions o;
  o.constraint_tol = p.real("constraint_tol");
  require_input(std::isfinite(o.constraint_tol) && o.constraint_tol > 0,
                "parameter 'constraint_tol' must be > 0");
  const long iters = p.integer("newton_max_iter");
  require_input(iters >= 1 && iters <= 1000, "parameter 'newton_max_iter' must be in [1, 1000]");
  o.newton_max_iter = static_cast<int>(iters);
  return o;
}

constexpr MethodText kRattleText{
    .description =
        "RATTLE (Andersen 1983, J. Comput. Phys. 52; Hairer-Lubich-Wanner VII.1): "
        "velocity Verlet with holonomic constraints, Newton on the multipliers for "
        "g(x) = 0 in the drift, velocities projected onto G(x) v = 0 in the closing "
        "kick; symmetric, symplectic",
    .kind = "constrained splitting (RATTLE)",
    .reference =
        join_text("H. C. Andersen, Rattle: a \"velocity\" version of the Shake algorithm for "
                  "molecular dynamics calculations, J. Comput. Phys. 52 (1983) 24-34",
                  "; ", cite(kGeometricIntegration, "Sect. VII.1"))};

struct Rattle::Solvers {
  Eigen::SparseLU<SparseMat> lu;
  Eigen::SimplicialLDLT<SparseMat> ldlt;
};

Rattle::Rattle(RattleOptions opt)
    : Integrator(method_info("rattle", Family::symplectic, 2, 1, kRattleNeeds, kRattleText)),
      opt_(opt),
      solvers_(std::make_unique<Solvers>()) {}

Rattle::~Rattle() = default;

void Rattle::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  cons_ = mech_->holonomic_constraints();
  const Index n = mech_->dofs();
  const Index m = cons_->constraint_count();
  const Vec mass = mech_->masses();
  w_ = mass.cwiseInverse();
  for (const Index i : mech_->fixed_dofs()) w_[i] = 0.0;  // pinned: infinite mass
  acc_.resize(n);
  x_bar_.resize(n);
  x_last_.resize(n);
  step_.resize(n);
  g_val_.resize(m);
  lambda_.resize(m);
  started_ = false;
}

bool Rattle::project_velocity(VecRef v, SolveStats& stats) {
  const Index m = g_val_.size();
  if (m == 0) return true;
  // A = G W Gᵀ at x_{n+1}: symmetric positive definite for independent constraints.
  const SparseMat wg = w_.asDiagonal() * SparseMat(g_new_.transpose());
  const SparseMat a = g_new_ * wg;
  solvers_->ldlt.compute(a);
  ++stats.linear_setups;
  if (solvers_->ldlt.info() != Eigen::Success) return false;
  const double tol = opt_.constraint_tol * std::max(1.0, max_abs(v));
  for (int pass = 0; pass < 3; ++pass) {
    g_val_ = g_new_ * v;  // G v, the velocity residual
    if (!g_val_.allFinite()) return false;
    if (max_abs(g_val_) <= tol) return true;
    lambda_ = solvers_->ldlt.solve(g_val_);
    ++stats.lin_solves;
    v -= wg * lambda_;
  }
  g_val_ = g_new_ * v;
  return g_val_.allFinite() && max_abs(g_val_) <= tol;
}

Status Rattle::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) {
  if (&sys != mech_) throw std::logic_error("Rattle::step: system differs from reset()");
  const Index n = mech_->dofs();
  const Index m = g_val_.size();
  auto x = y.head(n);
  auto v = y.tail(n);

  // a(x_n) and G(x_n): from the previous step when this one starts where it ended (the same
  // position; t is not compared: the driver computes t0 + k h, not the sum of the steps).
  if (!started_ || x != x_last_) {
    mech_->acceleration(t, x, v, acc_);
    if (m > 0) cons_->constraint_jacobian(x, g_new_);
    started_ = true;
  }
  if (m > 0) {
    g_old_ = g_new_;
    wgt_ = w_.asDiagonal() * SparseMat(g_old_.transpose());
  }

  // Positions: free drift x̄, then Newton on Λ = ½h² λ for g(x̄ - W G_nᵀ Λ) = 0.
  x_bar_ = x + h * v + (0.5 * h * h) * acc_;
  step_ = x_bar_;  // the iterate x^k
  lambda_.setZero();
  const double xtol = opt_.constraint_tol * std::max(1.0, max_abs(x_bar_));
  bool converged = m == 0, singular = false;
  for (int iter = 0; !converged; ++iter) {
    cons_->constraint_values(step_, g_val_);
    if (!g_val_.allFinite()) {
      singular = true;  // a NaN multiplier from a (numerically) singular solve
      break;
    }
    if (max_abs(g_val_) <= xtol) {
      converged = true;
      break;
    }
    if (iter == opt_.newton_max_iter) break;
    cons_->constraint_jacobian(step_, g_new_);
    const SparseMat jac = g_new_ * wgt_;  // ∂g(x̄ - W G_nᵀ Λ)/∂Λ = -G(x^k) W G_nᵀ
    solvers_->lu.compute(jac);
    ++stats.linear_setups;
    ++stats.newton_iters;
    if (solvers_->lu.info() != Eigen::Success) {
      singular = true;
      break;
    }
    lambda_ += solvers_->lu.solve(g_val_);
    ++stats.lin_solves;
    step_ = x_bar_ - wgt_ * lambda_;
  }
  if (!converged) {
    started_ = false;  // g_new_ holds a Newton iterate's G now: a retry starts afresh
    ++stats.newton_conv_failures;
    std::ostringstream msg;
    msg << "rattle: the position constraint g(x) = 0 ";
    if (singular)
      msg << "could not be solved at t = " << t + h
          << ": singular G M^-1 G^T (dependent constraints?)";
    else
      msg << "did not converge in " << opt_.newton_max_iter << " Newton iterations at t = " << t + h
          << " (max|g| = " << max_abs(g_val_) << ", tolerance " << xtol << ")";
    stats.message = msg.str();
    return Status::newton_failed;
  }

  // v_{n+½} from Λ directly (no difference quotient), then x_{n+1} and the closing kick.
  v += (0.5 * h) * acc_;
  if (m > 0) v -= (wgt_ * lambda_) / h;
  x = step_;
  mech_->acceleration(t + h, x, v, acc_);  // a(x_{n+1}); v is ignored (velocity-independent)
  v += (0.5 * h) * acc_;
  if (m > 0) {
    cons_->constraint_jacobian(x, g_new_);
    if (!project_velocity(v, stats)) {
      started_ = false;
      ++stats.newton_conv_failures;
      stats.message = "rattle: the velocity constraint G(x) v = 0 could not be solved at t = " +
                      std::to_string(t + h) + " (singular G M^-1 G^T: dependent constraints?)";
      return Status::solver_error;
    }
  }
  x_last_ = x;
  return Status::ok;
}

}  // namespace stiffbench
