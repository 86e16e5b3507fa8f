#include <arkode/arkode_arkstep.h>

#include "integrators/reference/sundials/front_end.hpp"

namespace stiffbench::sundials_detail {

namespace {

class ArkodeIntegrator final : public SundialsFrontEnd {
 public:
  ArkodeIntegrator(MethodInfo info, ArkodeMode mode, Settings s)
      : SundialsFrontEnd(std::move(info), std::move(s)), mode_(mode) {}
  ~ArkodeIntegrator() override { free_memory(); }

  // One internal step of exactly h (ARK_ONE_STEP with a fixed step size).
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override {
    return fixed_step(sys, t, y, h, stats, ARKStepSetFixedStep);
  }

 private:
  bool needs_linear_solver() const override { return mode_ != ArkodeMode::explicit_only; }
  bool uses_implicit_part(const OdeSystem& sys) const override {
    return mode_ == ArkodeMode::imex && sys.has_imex_split();
  }
  // IMEX with the model's split; all-implicit (arkode_imex on a model without one) otherwise.
  bool split() const { return mode_ == ArkodeMode::imex && adapter_.system()->has_imex_split(); }
  ARKRhsFn explicit_rhs() const {
    return mode_ == ArkodeMode::explicit_only ? SundialsAdapter::rhs_cb
           : split()                          ? SundialsAdapter::rhs_explicit_cb
                                              : nullptr;
  }
  ARKRhsFn implicit_rhs() const {
    return mode_ == ArkodeMode::explicit_only ? nullptr
           : split()                          ? SundialsAdapter::rhs_implicit_cb
                                              : SundialsAdapter::rhs_cb;
  }
  void create(double t0, N_Vector y, const Ok& ok) override {
    mem_ = ARKStepCreate(explicit_rhs(), implicit_rhs(), t0, y, ctx_);
    ok(ARKStepSetUserData(mem_, &adapter_), "ARKStepSetUserData");
    ok(ARKStepSetErrHandlerFn(mem_, SundialsAdapter::err_cb, &adapter_), "ARKStepSetErrHandlerFn");
    ok(ARKStepSStolerances(mem_, set_.rtol, set_.atol), "ARKStepSStolerances");
    ok(ARKStepSetMaxNumSteps(mem_, set_.max_steps), "ARKStepSetMaxNumSteps");
    // A part without a right-hand side gets no table.
    if (set_.dirk_num >= 0) {
      ok(ARKStepSetTableNum(
             mem_,
             implicit_rhs() ? static_cast<ARKODE_DIRKTableID>(set_.dirk_num) : ARKODE_DIRK_NONE,
             explicit_rhs() ? static_cast<ARKODE_ERKTableID>(set_.erk_num) : ARKODE_ERK_NONE),
         "ARKStepSetTableNum");
    } else {
      const char* itab = implicit_rhs() ? set_.implicit_table.c_str() : "ARKODE_DIRK_NONE";
      const char* etab = explicit_rhs() ? set_.explicit_table.c_str() : "ARKODE_ERK_NONE";
      ok(ARKStepSetTableName(mem_, itab, etab), "ARKStepSetTableName");
    }
    if (implicit_rhs()) {
      ok(ARKStepSetNonlinConvCoef(mem_, set_.nonlin_conv_coef), "ARKStepSetNonlinConvCoef");
      ok(ARKStepSetMaxNonlinIters(mem_, set_.max_nonlin_iters), "ARKStepSetMaxNonlinIters");
    }
  }
  void attach_linear_solver(const Ok& ok) override {
    ok(ARKStepSetLinearSolver(mem_, adapter_.linear_solver(), adapter_.matrix()),
       "ARKStepSetLinearSolver");
    ok(ARKStepSetLSetupFrequency(mem_, static_cast<int>(set_.lsetup_frequency)),
       "ARKStepSetLSetupFrequency");
    adapter_.attach_jacobian<ArkodeLinearSolverApi>(mem_, ok);
  }
  void reinit(double t, N_Vector y) override {
    ARKStepReInit(mem_, explicit_rhs(), implicit_rhs(), t, y);
  }
  int set_stop_time(double t_out) override { return ARKStepSetStopTime(mem_, t_out); }
  int solve(double t_out, N_Vector yout, sunrealtype* tret, bool one_step) override {
    return ARKStepEvolve(mem_, t_out, yout, tret, one_step ? ARK_ONE_STEP : ARK_NORMAL);
  }
  const char* solve_name() const override { return "ARKStepEvolve"; }
  char* flag_name(int flag) const override { return ARKStepGetReturnFlagName(flag); }
  Counters counters(SolveStats& s) const override {
    Counters c;
    ARKStepGetNumSteps(mem_, &c.steps);
    ARKStepGetNumErrTestFails(mem_, &c.etf);
    ARKStepGetNumRhsEvals(mem_, &c.nfe, &c.nfi);
    if (needs_linear_solver()) {
      ARKStepGetNumNonlinSolvIters(mem_, &c.nni);
      ARKStepGetNumNonlinSolvConvFails(mem_, &c.ncf);
      ARKStepGetNumLinSolvSetups(mem_, &c.nsetups);
      ARKStepGetNumJacEvals(mem_, &c.nje);
      ARKStepGetNumLinIters(mem_, &c.nli);
      ARKStepGetNumLinRhsEvals(mem_, &c.nfels);
    }
    s.library_report =
        capture([&](FILE* f) { ARKStepPrintAllStats(mem_, f, SUN_OUTPUTFORMAT_TABLE); });
    return c;
  }
  void free_library_memory() override { ARKStepFree(&mem_); }

  ArkodeMode mode_;
};

}  // namespace

std::unique_ptr<Integrator> make_arkode_integrator(MethodInfo info, ArkodeMode mode, Settings s) {
  return std::make_unique<ArkodeIntegrator>(std::move(info), mode, std::move(s));
}

}  // namespace stiffbench::sundials_detail
