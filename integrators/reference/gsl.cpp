#include "integrators/reference/gsl.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <gsl/gsl_version.h>

#include <cmath>
#include <iostream>
#include <utility>

#include "integrators/method_entry.hpp"
#include "integrators/reference/callback_guard.hpp"

namespace stiffbench {

namespace {

constexpr const char* kGsl = "M. Galassi et al., GNU Scientific Library Reference Manual, odeiv2";

struct GslMethod {
  const char* name;
  const gsl_odeiv2_step_type* const* type;  // address of the GSL global (initialised at load)
  int order;                                // 0: variable order
  bool needs_jacobian;
  bool fixed_ok;
  MethodText text;
};

const std::vector<GslMethod>& gsl_methods() {
  static const std::vector<GslMethod> all = {
      {"gsl_rk4",
       &gsl_odeiv2_step_rk4,
       4,
       false,
       true,
       {.description = "GSL classic RK4 (step doubling for the error)",
        .kind = "library: GSL",
        .reference = kGsl}},
      {"gsl_rkf45",
       &gsl_odeiv2_step_rkf45,
       5,
       false,
       true,
       {.description = "GSL Runge-Kutta-Fehlberg 4(5)",
        .kind = "library: GSL",
        .reference = join_text(kGsl, "; ", "Fehlberg 1969")}},
      {"gsl_rkck",
       &gsl_odeiv2_step_rkck,
       5,
       false,
       true,
       {.description = "GSL Cash-Karp 4(5)",
        .kind = "library: GSL",
        .reference = join_text(kGsl, "; ", "Cash & Karp 1990")}},
      {"gsl_rk8pd",
       &gsl_odeiv2_step_rk8pd,
       8,
       false,
       true,
       {.description = "GSL Prince-Dormand 8(7)",
        .kind = "library: GSL",
        .reference = join_text(
            kGsl, "; ", "P. J. Prince & J. R. Dormand, J. Comput. Appl. Math. 7 (1981) 67-75")}},
      {"gsl_rk2imp",
       &gsl_odeiv2_step_rk2imp,
       2,
       true,
       true,
       {.description = "GSL implicit Gauss-Legendre, 1 stage (midpoint)",
        .kind = "library: GSL (Gauss collocation)",
        .reference = kGsl}},
      {"gsl_rk4imp",
       &gsl_odeiv2_step_rk4imp,
       4,
       true,
       true,
       {.description = "GSL implicit Gauss-Legendre, 2 stages",
        .kind = "library: GSL (Gauss collocation)",
        .reference = kGsl}},
      {"gsl_bsimp",
       &gsl_odeiv2_step_bsimp,
       0,
       true,
       false,
       {.description = "GSL Bader-Deuflhard semi-implicit extrapolation (order set by the "
                       "tolerance); adaptive only",
        .kind = "library: GSL",
        .reference =
            join_text(kGsl, "; ", "G. Bader & P. Deuflhard, Numer. Math. 41 (1983) 373-398")}},
      {"gsl_msadams",
       &gsl_odeiv2_step_msadams,
       0,
       false,
       false,
       {.description = "GSL variable-order Adams (1-12); adaptive only",
        .kind = "library: GSL",
        .reference = kGsl}},
      {"gsl_msbdf",
       &gsl_odeiv2_step_msbdf,
       0,
       true,
       false,
       {.description = "GSL variable-order BDF (1-5); adaptive only",
        .kind = "library: GSL",
        .reference = kGsl}},
  };
  return all;
}

class GslIntegrator final : public Integrator {
 public:
  GslIntegrator(MethodInfo info, const GslMethod& m, double rtol, double atol, double h0)
      : Integrator(std::move(info)), method_(m), rtol_(rtol), atol_(atol), h0_(h0) {
    gsl_set_error_handler_off();  // GSL aborts by default; we report status codes instead
  }
  ~GslIntegrator() override { free_driver(); }

  bool supports_fixed_step() const override { return method_.fixed_ok; }
  bool supports_adaptive() const override { return true; }
  std::optional<double> absolute_tolerance() const override { return atol_; }

  void reset(const OdeSystem& sys, double t0, CVecRef y0) override {
    check_compatible(info(), sys);
    sys_ = &sys;
    n_ = sys.dimension();
    t_ = t0;
    y_last_ = y0;
    f0_.resize(n_);
    f1_.resize(n_);
    tmp_.resize(n_);
    yerr_.resize(n_);
    fixed_steps_ = 0;
    accepted_ = banked_count_ = banked_failed_ = 0;
    gsys_ = {func, method_.needs_jacobian ? jac : nullptr, static_cast<std::size_t>(n_), this};
    fixed_h_ = 0;
    make_driver(h0_);
  }

  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override {
    require_input(method_.fixed_ok, "integrator '" + info().name +
                                        "' is adaptive only: give --param rtol=R, not --h");
    sync(sys, t, y);
    if (h != fixed_h_) {
      make_driver(h);
      fixed_h_ = h;
    }
    // The bare stepper: the driver's fixed-step function still applies the error control and
    // refuses steps whose estimate exceeds the tolerance.
    guard_.clear();
    const int status =
        gsl_odeiv2_step_apply(driver_->s, t_, h, y.data(), yerr_.data(), nullptr, nullptr, &gsys_);
    guard_.rethrow();
    if (status == GSL_SUCCESS) ++fixed_steps_;
    return finish(status, t_ + h, y, stats, true);
  }

  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override {
    sync(sys, t_, y);
    double tt = t_;
    guard_.clear();
    const int status = gsl_odeiv2_driver_apply(driver_, &tt, t_out, y.data());
    accepted_ += static_cast<long>(driver_->n);  // the steps this call accepted
    guard_.rethrow();
    return finish(status, tt, y, stats, false);
  }

 private:
  // A callback body under guard_ (callback_guard.hpp); GSL_EBADFUNC ends GSL's step at once.
  template <class F>
  int guarded(F&& f) {
    return guard_.run(std::forward<F>(f), GSL_EBADFUNC);
  }

  static int func(double t, const double y[], double f[], void* p) {
    auto* self = static_cast<GslIntegrator*>(p);
    return self->guarded([&] {
      Eigen::Map<const Vec> yv(y, self->n_);
      Eigen::Map<Vec> fv(f, self->n_);
      self->sys_->rhs(t, yv, fv);
      return fv.allFinite() ? GSL_SUCCESS : GSL_EBADFUNC;
    });
  }

  static int jac(double t, const double y[], double* dfdy, double dfdt[], void* p) {
    auto* self = static_cast<GslIntegrator*>(p);
    return self->guarded([&] { return self->jacobian(t, y, dfdy, dfdt); });
  }

  // dfdy is row-major: dfdy[i*n + j] = ∂f_i/∂y_j.
  int jacobian(double t, const double y[], double* dfdy, double dfdt[]) {
    const Index n = n_;
    Eigen::Map<const Vec> yv(y, n);
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jm(dfdy, n,
                                                                                          n);
    if (sys_->has_jacobian()) {
      sys_->jacobian(t, yv, jac_);
      jm = Mat(jac_);
    } else {
      jm = finite_difference_jacobian(*sys_, t, yv);
      ++fd_jacobians_;
    }
    Eigen::Map<Vec> ft(dfdt, n);
    if (sys_->autonomous()) {
      ft.setZero();
    } else {
      const double dt = 1.4901161193847656e-08 * std::max(1.0, std::abs(t));
      sys_->rhs(t, yv, f0_);
      sys_->rhs(t + dt, yv, f1_);
      ft = (f1_ - f0_) / dt;
    }
    return GSL_SUCCESS;
  }

  void free_driver() {
    if (driver_) gsl_odeiv2_driver_free(driver_);
    driver_ = nullptr;
  }

  // Keeps the evolve object's counts before a reset or a new driver clears them.
  void bank_counts() {
    if (!driver_) return;
    banked_count_ += static_cast<long>(driver_->e->count);
    banked_failed_ += static_cast<long>(driver_->e->failed_steps);
  }

  void make_driver(double h) {
    bank_counts();
    free_driver();
    driver_ = gsl_odeiv2_driver_alloc_y_new(&gsys_, *method_.type, h, atol_, rtol_);
    if (!driver_)
      throw std::runtime_error("gsl_odeiv2_driver_alloc_y_new failed for " + info().name);
  }

  // GSL keeps its steppers' history inside the driver: a state changed from outside (or a new
  // time) resets it.
  void sync(const OdeSystem& sys, double t, CVecRef y) {
    if (&sys != sys_) throw std::logic_error("GslIntegrator: system differs from reset()");
    if (std::abs(t - t_) <= 1e-13 * std::max(1.0, std::abs(t)) && y == y_last_) return;
    bank_counts();
    gsl_odeiv2_driver_reset(driver_);
    t_ = t;
  }

  Status finish(int status, double tt, VecRef y, SolveStats& stats, bool fixed) {
    if (!fixed) {
      // GSL's evolve counts every step it computed (`count`: accepted ones and those the error
      // test rejected) and every retry with a smaller step (`failed_steps`: error-test
      // rejections and steps whose stepper failed, e.g. its implicit solve did not converge);
      // the driver counts the accepted ones (`n`, per call). Hence accepted steps, error-test
      // failures = count - accepted, and stepper failures = failed_steps - error-test failures
      // (the implicit steppers' nonlinear solve failures; 0 for explicit ones).
      const long count = banked_count_ + static_cast<long>(driver_->e->count);
      const long failed = banked_failed_ + static_cast<long>(driver_->e->failed_steps);
      stats.steps = accepted_;
      stats.error_test_failures = count - accepted_;
      stats.newton_conv_failures = failed - stats.error_test_failures;
    }
    stats.jac_evals = fd_jacobians_;
    // The steppers that take a Jacobian factorise and solve inside GSL and keep no count the
    // testbed can read; rk2imp, rk4imp and msbdf also iterate (modified Newton), bsimp does not
    // (linearly implicit: newton_iters is a true 0).
    if (method_.needs_jacobian) {
      stats.linear_setups = stats.lin_solves = SolveStats::kNotReported;
      if (method_.type != &gsl_odeiv2_step_bsimp) stats.newton_iters = SolveStats::kNotReported;
    }
    if (status != GSL_SUCCESS) {
      stats.message = "GSL " + info().name + ": " + gsl_strerror(status) + " (status " +
                      std::to_string(status) + ") at t = " + std::to_string(tt);
      std::cerr << "stiffbench: " << stats.message << "\n";
      return Status::solver_error;
    }
    t_ = tt;
    y_last_ = y;
    return Status::ok;
  }

  GslMethod method_;
  double rtol_, atol_, h0_;
  const OdeSystem* sys_ = nullptr;
  Index n_ = 0;
  gsl_odeiv2_system gsys_{};
  gsl_odeiv2_driver* driver_ = nullptr;
  SparseMat jac_;
  Vec f0_, f1_, tmp_, yerr_, y_last_;
  long fixed_steps_ = 0;
  // Adaptive counts: steps accepted (the driver's n, summed over calls) and the evolve object's
  // count and failed_steps from drivers or resets already gone.
  long accepted_ = 0, banked_count_ = 0, banked_failed_ = 0;
  CallbackGuard guard_;  // what a callback threw, rethrown when GSL returns
  double t_ = 0, fixed_h_ = 0;
  long fd_jacobians_ = 0;
};

}  // namespace

void register_gsl_integrators(IntegratorRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  // GSL takes rtol = 0 when atol > 0 (the pair is checked when the integrator is created).
  const std::vector<ParamSpec> specs = {
      {"rtol", P::real, "1e-6", "relative tolerance (adaptive mode)", B::non_negative()},
      {"atol", P::real, "1e-10", "absolute tolerance (adaptive mode)", B::non_negative()},
      {"h0", P::real, "1e-6", "initial step of the adaptive driver", B::positive()},
  };
  for (const GslMethod& m : gsl_methods()) {
    const MethodInfo info = method_info(m.name, Family::reference, m.order, 0, {}, m.text);
    add_built_in_integrator(
        reg, {info, specs, [info, m](const Params& p) {
                const double rtol = p.real("rtol"), atol = p.real("atol"), h0 = p.real("h0");
                require_input(rtol >= 0 && atol >= 0 && rtol + atol > 0,
                              "parameters 'rtol'/'atol' must be >= 0, not both 0");
                require_input(h0 > 0, "parameter 'h0' must be > 0");
                return std::make_unique<GslIntegrator>(info, m, rtol, atol, h0);
              }});
  }
}

std::string gsl_library_version() { return gsl_version; }

}  // namespace stiffbench
