// The Integrator face shared by the SUNDIALS front-ends (cvode.cpp, arkode.cpp, mri.cpp) and the
// factories registration calls. Internal to integrators/reference/sundials/.
#pragma once

#include <memory>

#include "core/integrator.hpp"
#include "integrators/reference/sundials/adapter.hpp"

namespace stiffbench::sundials_detail {

// The Integrator face of a SUNDIALS library: reset, fixed steps, adaptive runs to exact stops,
// restarts after outside changes to y, error messages and counters. CvodeIntegrator and
// ArkodeIntegrator supply the library calls; both run on one SundialsAdapter (the callbacks'
// user data and the linear solver).
class SundialsFrontEnd : public Integrator {
 public:
  SundialsFrontEnd(MethodInfo info, Settings s) : Integrator(std::move(info)), set_(std::move(s)) {
    SUNContext_Create(nullptr, &ctx_);
  }
  // The derived class frees the library memory (free_memory()) before the context goes.
  ~SundialsFrontEnd() override { SUNContext_Free(&ctx_); }

  bool supports_adaptive() const override { return true; }
  std::optional<double> absolute_tolerance() const override { return set_.atol; }
  void reset(const OdeSystem& sys, double t0, CVecRef y0) override;
  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override;

 protected:
  using Ok = std::function<void(int, const char*)>;

  // --- the library calls ---------------------------------------------------------------
  virtual bool needs_linear_solver() const = 0;
  // True when the implicit stages solve for the implicit part f_I of the model's split (the
  // Newton matrices then come from J_I).
  virtual bool uses_implicit_part(const OdeSystem&) const { return false; }
  // Creates mem_ at (t0, y) with the user data, error handler, tolerances and options.
  virtual void create(double t0, N_Vector y, const Ok& ok) = 0;
  // Hands the adapter's linear solver to the library, then the adapter's Jacobian.
  virtual void attach_linear_solver(const Ok& ok) = 0;
  virtual void reinit(double t, N_Vector y) = 0;
  virtual int set_stop_time(double t_out) = 0;
  // One call of the library's solver towards t_out (one step when one_step), named `name`.
  virtual int solve(double t_out, N_Vector yout, sunrealtype* tret, bool one_step) = 0;
  virtual const char* solve_name() const = 0;
  virtual char* flag_name(int flag) const = 0;  // allocated by the library; the caller frees it
  // The library's counters, as read_counters() below maps them.
  struct Counters {
    long steps = 0, etf = 0, nni = 0, ncf = 0, nsetups = 0, nje = 0, nli = 0, nfe = 0, nfi = 0,
         nfels = 0;
  };
  virtual Counters counters(SolveStats& s) const = 0;  // also sets s.library_report
  virtual void free_library_memory() = 0;

  void free_memory() {
    if (mem_) free_library_memory();
    adapter_.free_linear_solver();
    mem_ = nullptr;
  }

  // One step of exactly h (fixed-step mode; ARKODE only).
  Status fixed_step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats& stats,
                    int (*set_fixed_step)(void*, sunrealtype));

  Settings set_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  SundialsAdapter adapter_;

 private:
  bool check(int flag, const char* what, SolveStats& stats);

  // Re-initialises the library when the state was changed from outside (e.g. a constraint
  // projection) or when the driver restarts at another time.
  void sync(const OdeSystem& sys, double t, CVecRef y);
  Status evolve(double t_out, VecRef y, bool one_step, SolveStats& stats);
  void read_counters(SolveStats& s);

  Vec y_last_;
  double t_ = 0, fixed_h_ = 0;
  bool fixed_mode_ = false;
};

// cvode_bdf, cvode_adams (lmm CV_BDF or CV_ADAMS): cvode.cpp.
std::unique_ptr<Integrator> make_cvode_integrator(MethodInfo info, int lmm, Settings s);

// arkode_erk, arkode_dirk, arkode_imex: ARKStep with explicit, implicit or IMEX tables;
// adaptive or fixed step.
enum class ArkodeMode { explicit_only, implicit_only, imex };
std::unique_ptr<Integrator> make_arkode_integrator(MethodInfo info, ArkodeMode mode, Settings s);

// arkode_mri: mri.cpp.
std::unique_ptr<Integrator> make_mri_integrator(MethodInfo info, Settings s);

}  // namespace stiffbench::sundials_detail
