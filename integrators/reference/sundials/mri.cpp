#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_mristep.h>

#include <stdexcept>

#include "integrators/reference/sundials/front_end.hpp"

namespace stiffbench::sundials_detail {

namespace {

// arkode_mri: MRIStep, slow part f_E explicit with an MRI coupling table at a fixed slow step
// h; fast part f_I by an inner ARKStep with an implicit (DIRK) table, its Newton on J_I and the
// same linear solvers as arkode_imex, adaptive at rtol/atol or fast_steps fixed steps of
// h/fast_steps. MRIStep 2.x (SUNDIALS 6.4) has fixed slow steps only: no adaptive mode.
class MriIntegrator final : public SundialsFrontEnd {
 public:
  MriIntegrator(MethodInfo info, Settings s) : SundialsFrontEnd(std::move(info), std::move(s)) {}
  ~MriIntegrator() override { free_memory(); }

  bool supports_adaptive() const override { return false; }
  Status advance_to(const OdeSystem&, double, VecRef, SolveStats&) override {
    throw BadInput("integrator '" + info().name +
                   "' runs at a fixed slow step only (MRIStep of SUNDIALS 6.4): give --h");
  }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats) override {
    if (set_.fast_steps > 0 && h != fast_for_h_) {
      const int flag = ARKStepSetFixedStep(inner_, h / static_cast<double>(set_.fast_steps));
      if (flag < 0) {
        stats.message = "ARKStepSetFixedStep (fast) failed";
        return Status::solver_error;
      }
      fast_for_h_ = h;
    }
    return fixed_step(sys, t, y, h, stats, MRIStepSetFixedStep);
  }

 private:
  bool needs_linear_solver() const override { return true; }
  bool uses_implicit_part(const OdeSystem&) const override { return true; }
  void create(double t0, N_Vector y, const Ok& ok) override {
    fast_for_h_ = 0;
    inner_ = ARKStepCreate(nullptr, SundialsAdapter::rhs_implicit_cb, t0, y, ctx_);
    ok(ARKStepSetUserData(inner_, &adapter_), "ARKStepSetUserData");
    ok(ARKStepSetErrHandlerFn(inner_, SundialsAdapter::err_cb, &adapter_),
       "ARKStepSetErrHandlerFn");
    ok(ARKStepSStolerances(inner_, set_.rtol, set_.atol), "ARKStepSStolerances");
    ok(ARKStepSetMaxNumSteps(inner_, set_.max_steps), "ARKStepSetMaxNumSteps");
    ok(ARKStepSetTableName(inner_, set_.implicit_table.c_str(), "ARKODE_ERK_NONE"),
       "ARKStepSetTableName");
    ok(ARKStepSetNonlinConvCoef(inner_, set_.nonlin_conv_coef), "ARKStepSetNonlinConvCoef");
    ok(ARKStepSetMaxNonlinIters(inner_, set_.max_nonlin_iters), "ARKStepSetMaxNonlinIters");
    ok(ARKStepCreateMRIStepInnerStepper(inner_, &stepper_), "ARKStepCreateMRIStepInnerStepper");
    mem_ = MRIStepCreate(SundialsAdapter::rhs_explicit_cb, nullptr, t0, y, stepper_, ctx_);
    if (!mem_) throw std::runtime_error("MRIStepCreate failed");
    ok(MRIStepSetUserData(mem_, &adapter_), "MRIStepSetUserData");
    ok(MRIStepSetErrHandlerFn(mem_, SundialsAdapter::err_cb, &adapter_), "MRIStepSetErrHandlerFn");
    ok(MRIStepSStolerances(mem_, set_.rtol, set_.atol), "MRIStepSStolerances");
    ok(MRIStepSetMaxNumSteps(mem_, set_.max_steps), "MRIStepSetMaxNumSteps");
    MRIStepCoupling c = MRIStepCoupling_LoadTable(static_cast<ARKODE_MRITableID>(set_.mri_table));
    if (!c) throw std::runtime_error("MRIStepCoupling_LoadTable failed");
    const int flag = MRIStepSetCoupling(mem_, c);
    MRIStepCoupling_Free(c);  // MRIStep keeps its own copy
    ok(flag, "MRIStepSetCoupling");
  }
  void attach_linear_solver(const Ok& ok) override {
    ok(ARKStepSetLinearSolver(inner_, adapter_.linear_solver(), adapter_.matrix()),
       "ARKStepSetLinearSolver");
    ok(ARKStepSetLSetupFrequency(inner_, static_cast<int>(set_.lsetup_frequency)),
       "ARKStepSetLSetupFrequency");
    adapter_.attach_jacobian<ArkodeLinearSolverApi>(inner_, ok);
  }
  void reinit(double t, N_Vector y) override {
    MRIStepReInit(mem_, SundialsAdapter::rhs_explicit_cb, nullptr, t, y);
  }
  int set_stop_time(double t_out) override { return MRIStepSetStopTime(mem_, t_out); }
  int solve(double t_out, N_Vector yout, sunrealtype* tret, bool one_step) override {
    return MRIStepEvolve(mem_, t_out, yout, tret, one_step ? ARK_ONE_STEP : ARK_NORMAL);
  }
  const char* solve_name() const override { return "MRIStepEvolve"; }
  char* flag_name(int flag) const override { return MRIStepGetReturnFlagName(flag); }
  Counters counters(SolveStats& s) const override {
    Counters c;
    long nfsi = 0, nfe_fast = 0;
    MRIStepGetNumSteps(mem_, &c.steps);
    MRIStepGetNumRhsEvals(mem_, &c.nfe, &nfsi);
    ARKStepGetNumRhsEvals(inner_, &nfe_fast, &c.nfi);
    ARKStepGetNumErrTestFails(inner_, &c.etf);
    ARKStepGetNumNonlinSolvIters(inner_, &c.nni);
    ARKStepGetNumNonlinSolvConvFails(inner_, &c.ncf);
    ARKStepGetNumLinSolvSetups(inner_, &c.nsetups);
    ARKStepGetNumJacEvals(inner_, &c.nje);
    ARKStepGetNumLinIters(inner_, &c.nli);
    ARKStepGetNumLinRhsEvals(inner_, &c.nfels);
    long inner_steps = 0;
    ARKStepGetNumSteps(inner_, &inner_steps);
    s.library_report =
        "Fast (inner ARKStep) steps   = " + std::to_string(inner_steps) + "\n" +
        capture([&](FILE* f) { MRIStepPrintAllStats(mem_, f, SUN_OUTPUTFORMAT_TABLE); }) +
        capture([&](FILE* f) { ARKStepPrintAllStats(inner_, f, SUN_OUTPUTFORMAT_TABLE); });
    return c;
  }
  void free_library_memory() override {
    MRIStepFree(&mem_);
    MRIStepInnerStepper_Free(&stepper_);
    ARKStepFree(&inner_);
  }

  void* inner_ = nullptr;
  MRIStepInnerStepper stepper_ = nullptr;
  double fast_for_h_ = 0;
};

}  // namespace

std::unique_ptr<Integrator> make_mri_integrator(MethodInfo info, Settings s) {
  return std::make_unique<MriIntegrator>(std::move(info), std::move(s));
}

}  // namespace stiffbench::sundials_detail
