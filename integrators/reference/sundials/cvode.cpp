#include <cvode/cvode.h>

#include "integrators/reference/sundials/front_end.hpp"

namespace stiffbench::sundials_detail {

namespace {

// cvode_bdf, cvode_adams: variable order and step, adaptive only.
class CvodeIntegrator final : public SundialsFrontEnd {
 public:
  CvodeIntegrator(MethodInfo info, int lmm, Settings s)
      : SundialsFrontEnd(std::move(info), std::move(s)), lmm_(lmm) {}
  ~CvodeIntegrator() override { free_memory(); }

  bool supports_fixed_step() const override { return false; }
  Status step(const OdeSystem&, double, VecRef, double, SolveStats&) override {
    throw BadInput("integrator '" + info().name +
                   "' is adaptive only: give --param rtol=R, not --h");
  }

 private:
  bool needs_linear_solver() const override { return true; }
  void create(double t0, N_Vector y, const Ok& ok) override {
    mem_ = CVodeCreate(lmm_, ctx_);
    ok(CVodeInit(mem_, SundialsAdapter::rhs_cb, t0, y), "CVodeInit");
    ok(CVodeSetUserData(mem_, &adapter_), "CVodeSetUserData");
    ok(CVodeSetErrHandlerFn(mem_, SundialsAdapter::err_cb, &adapter_), "CVodeSetErrHandlerFn");
    ok(CVodeSStolerances(mem_, set_.rtol, set_.atol), "CVodeSStolerances");
    ok(CVodeSetMaxNumSteps(mem_, set_.max_steps), "CVodeSetMaxNumSteps");
    if (set_.max_order > 0) ok(CVodeSetMaxOrd(mem_, set_.max_order), "CVodeSetMaxOrd");
  }
  void attach_linear_solver(const Ok& ok) override {
    ok(CVodeSetLinearSolver(mem_, adapter_.linear_solver(), adapter_.matrix()),
       "CVodeSetLinearSolver");
    adapter_.attach_jacobian<CvodeLinearSolverApi>(mem_, ok);
  }
  void reinit(double t, N_Vector y) override { CVodeReInit(mem_, t, y); }
  int set_stop_time(double t_out) override { return CVodeSetStopTime(mem_, t_out); }
  int solve(double t_out, N_Vector yout, sunrealtype* tret, bool one_step) override {
    return CVode(mem_, t_out, yout, tret, one_step ? CV_ONE_STEP : CV_NORMAL);
  }
  const char* solve_name() const override { return "CVode"; }
  char* flag_name(int flag) const override { return CVodeGetReturnFlagName(flag); }
  Counters counters(SolveStats& s) const override {
    Counters c;
    CVodeGetNumSteps(mem_, &c.steps);
    CVodeGetNumErrTestFails(mem_, &c.etf);
    CVodeGetNumRhsEvals(mem_, &c.nfe);
    CVodeGetNumNonlinSolvIters(mem_, &c.nni);
    CVodeGetNumNonlinSolvConvFails(mem_, &c.ncf);
    CVodeGetNumLinSolvSetups(mem_, &c.nsetups);
    CVodeGetNumJacEvals(mem_, &c.nje);
    CVodeGetNumLinIters(mem_, &c.nli);
    CVodeGetNumLinRhsEvals(mem_, &c.nfels);
    s.library_report =
        capture([&](FILE* f) { CVodePrintAllStats(mem_, f, SUN_OUTPUTFORMAT_TABLE); });
    return c;
  }
  void free_library_memory() override { CVodeFree(&mem_); }

  int lmm_;  // CV_BDF or CV_ADAMS
};

}  // namespace

std::unique_ptr<Integrator> make_cvode_integrator(MethodInfo info, int lmm, Settings s) {
  return std::make_unique<CvodeIntegrator>(std::move(info), lmm, std::move(s));
}

}  // namespace stiffbench::sundials_detail
