// The SUNDIALS front-ends' shared machinery (integrators/reference/sundials.hpp is the public
// face): the settings a registry entry reads, and SundialsAdapter, the library's user data — the
// system behind the C callbacks and the linear solver with its Jacobian. Internal to
// integrators/reference/sundials/; includes the SUNDIALS headers.
#pragma once

#include <arkode/arkode_arkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/ode_system.hpp"
#include "integrators/reference/callback_guard.hpp"
#include "integrators/solvers/velocity_form.hpp"

namespace stiffbench::sundials_detail {

enum class Lin { automatic, dense, band, klu, spgmr, velocity };
const char* to_string(Lin l);

struct Settings {
  double rtol = 1e-6, atol = 1e-10;
  Lin lin = Lin::automatic;
  std::string jacobian = "auto";  // auto | analytic | dq
  long max_steps = 100000;
  int max_order = 0;          // 0: the library's default
  long lsetup_frequency = 1;  // ARKODE: steps between linear-solver setups
  std::string explicit_table, implicit_table;
  // arkode_imex: a pair by number (ARKStepSetTableNum) instead of the names above; -1: names.
  int erk_num = -1, dirk_num = -1;
  // ARKODE's nonlinear solver (implicit stages): the Newton convergence test's coefficient and
  // the iteration limit (ARKStepSetNonlinConvCoef, ARKStepSetMaxNonlinIters); ARKODE's defaults.
  double nonlin_conv_coef = 0.1;
  int max_nonlin_iters = 3;
  // arkode_mri: the slow coupling table and the fast steps per slow step (0: adaptive fast).
  int mri_table = -1;
  long fast_steps = 0;
};

// Reads a FILE* report (PrintAllStats) into a string.
std::string capture(const std::function<void(FILE*)>& print);

// The library functions that attach a Jacobian to the linear solver, with the names the error
// messages quote. CVODE's and ARKODE's callbacks have the same signatures, so one adapter serves
// both.
struct CvodeLinearSolverApi {
  static constexpr auto set_jac_fn = CVodeSetJacFn;
  static constexpr auto set_jac_times = CVodeSetJacTimes;
  static constexpr auto set_preconditioner = CVodeSetPreconditioner;
  static constexpr const char* set_jac_fn_name = "CVodeSetJacFn";
  static constexpr const char* set_jac_times_name = "CVodeSetJacTimes";
  static constexpr const char* set_preconditioner_name = "CVodeSetPreconditioner";
};
struct ArkodeLinearSolverApi {
  static constexpr auto set_jac_fn = ARKStepSetJacFn;
  static constexpr auto set_jac_times = ARKStepSetJacTimes;
  static constexpr auto set_preconditioner = ARKStepSetPreconditioner;
  static constexpr const char* set_jac_fn_name = "ARKStepSetJacFn";
  static constexpr const char* set_jac_times_name = "ARKStepSetJacTimes";
  static constexpr const char* set_preconditioner_name = "ARKStepSetPreconditioner";
};

// Positions in the fixed Jacobian pattern of one block's nonzeros (the block placed at row0,
// col0). The block's own structure is kept so that a model whose pattern changes is noticed
// (the map is rebuilt, or the call fails naming the missing entry) instead of scattering values
// to wrong places; the check is a comparison of index arrays, no allocation.
class BlockMap {
 public:
  BlockMap() = default;
  BlockMap(Index row0, Index col0) : row0_(row0), col0_(col0) {}

  bool matches(const SparseMat& m) const {
    return m.isCompressed() && m.cols() + 1 == static_cast<Index>(outer_.size()) &&
           m.nonZeros() == static_cast<Index>(inner_.size()) &&
           std::equal(outer_.begin(), outer_.end(), m.outerIndexPtr()) &&
           std::equal(inner_.begin(), inner_.end(), m.innerIndexPtr());
  }
  // m compressed; every entry of m (shifted) must be in the pattern p (compressed, sorted).
  void build(const SparseMat& m, const SparseMat& p) {
    outer_.assign(m.outerIndexPtr(), m.outerIndexPtr() + m.cols() + 1);
    inner_.assign(m.innerIndexPtr(), m.innerIndexPtr() + m.nonZeros());
    pos_.resize(static_cast<std::size_t>(m.nonZeros()));
    for (Index c = 0; c < m.cols(); ++c)
      for (Index k = m.outerIndexPtr()[c]; k < m.outerIndexPtr()[c + 1]; ++k)
        pos_[static_cast<std::size_t>(k)] = find(p, row0_ + m.innerIndexPtr()[k], col0_ + c);
  }
  void scatter(const SparseMat& m, double* data) const {
    const double* v = m.valuePtr();
    const std::size_t nnz = pos_.size();
    for (std::size_t k = 0; k < nnz; ++k) data[pos_[k]] = v[k];
  }
  // Index of (r, c) in p's value array; throws when p has no such entry.
  static Index find(const SparseMat& p, Index r, Index c) {
    const auto* b = p.innerIndexPtr() + p.outerIndexPtr()[c];
    const auto* e = p.innerIndexPtr() + p.outerIndexPtr()[c + 1];
    const auto* it = std::lower_bound(b, e, r);
    if (it == e || *it != r)
      throw std::runtime_error("Jacobian entry (" + std::to_string(r) + ", " + std::to_string(c) +
                               ") is outside the pattern fixed at reset()");
    return static_cast<Index>(it - p.innerIndexPtr());
  }

 private:
  Index row0_ = 0, col0_ = 0;
  std::vector<SparseMat::StorageIndex> outer_, inner_;
  std::vector<Index> pos_;
};

// What CVODE and ARKODE share: the library's user data, i.e. the system seen through the C
// callbacks (f, its IMEX parts, the analytic Jacobian in dense, band or sparse form, J v, the
// velocity-form preconditioner) with the guard that carries exceptions across the C ABI, and
// the linear solver — its choice (linear_solver=auto resolved per run), the fixed Jacobian
// pattern with its index maps, and the SUNMatrix / SUNLinearSolver objects.
class SundialsAdapter {
 public:
  SundialsAdapter() = default;
  SundialsAdapter(const SundialsAdapter&) = delete;
  SundialsAdapter& operator=(const SundialsAdapter&) = delete;

  // Starts a run of integrator `name` on `sys`: resolves the Jacobian (analytic or the
  // library's difference quotients) and the linear solver, and with `linear` (a method with
  // implicit stages) and an analytic Jacobian fixes its pattern. With `implicit_part` (ARKStep
  // on an additive split) the Newton matrices are built from the implicit part's Jacobian J_I
  // (K_I, D_I for a mechanical model), through implicit_part_view(sys): the library's implicit
  // stages solve z = ψ + hγ f_I(z), whose Jacobian is J_I, not the full J.
  void reset(const OdeSystem& sys, const std::string& name, const Settings& set, bool linear,
             double t0, CVecRef y0, bool implicit_part = false);

  // The matrix and the linear solver of this run (the caller hands them to the library).
  void create_linear_solver(N_Vector y, SUNContext ctx);
  SUNLinearSolver linear_solver() const { return ls_; }
  SUNMatrix matrix() const { return a_; }

  // After the library took the linear solver: the analytic Jacobian's callbacks (none for the
  // library's difference quotients).
  template <class Api, class Ok>
  void attach_jacobian(void* mem, Ok&& ok) {
    if (!use_analytic_) return;  // the library's difference quotients
    if (lin_ == Lin::velocity) {
      // J v from the K and D of the last preconditioner set-up (a Jacobian as current as the
      // Newton matrix of the matrix-based solvers), no per-solve Jacobian fill.
      ok(Api::set_preconditioner(mem, psetup_cb, psolve_cb), Api::set_preconditioner_name);
      ok(Api::set_jac_times(mem, nullptr, velocity_jtimes_cb), Api::set_jac_times_name);
      return;
    }
    if (lin_ == Lin::spgmr) {
      ok(Api::set_jac_times(mem, jtsetup_cb, jtimes_cb), Api::set_jac_times_name);
      return;
    }
    auto fn = lin_ == Lin::dense  ? jac_matrix_cb<false>
              : lin_ == Lin::band ? jac_matrix_cb<true>
                                  : jac_sparse_cb;
    ok(Api::set_jac_fn(mem, fn), Api::set_jac_fn_name);
  }

  // Frees the linear solver and the matrix (after the library memory that uses them).
  void free_linear_solver();

  // --- callbacks (C ABI: exceptions must not cross it); user data is the adapter ----------
  static int rhs_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud);
  static int rhs_explicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud);
  static int rhs_implicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud);
  static void err_cb(int code, const char* module, const char* function, char* msg, void* ud);

  // Before a library call: no error recorded yet.
  void clear_errors() {
    library_error_.clear();
    callback_error_.clear();
    guard_.clear();
  }
  // After it: rethrows what a callback threw.
  void rethrow() { guard_.rethrow(); }
  const std::string& library_error() const { return library_error_; }
  const std::string& callback_error() const { return callback_error_; }

  const OdeSystem* system() const { return sys_; }
  Index size() const { return n_; }
  bool use_analytic() const { return use_analytic_; }
  long force_jacobian_evals() const { return force_jac_evals_; }
  const std::string& linear_solver_note() const { return lin_note_; }

 private:
  void resolve_linear_solver(const OdeSystem& sys, const std::string& name, Lin requested);

  // The fixed pattern jp_ = pattern(J) ∪ diagonal, computed once per reset(), and the maps
  // from the model's matrices into it. Structure only: the evaluations here are not counted.
  void build_jacobian_layout(double t0, CVecRef y0);

  // Writes J(t, y) into `data`, the value array of a matrix with jp_'s structure (the KLU
  // matrix's own array, or jp_'s). No allocation once the model's blocks have their pattern.
  void fill_jacobian(sunrealtype t, N_Vector y, double* data);

  // A callback body under guard_ (callback_guard.hpp); -1: unrecoverable for the library.
  template <class F>
  int guarded(F&& f) {
    return guard_.run(std::forward<F>(f), -1);
  }

  // Dense or band SUNMatrix from the sparse J (entries outside the band are not in the pattern).
  template <bool Band>
  static int jac_matrix_cb(sunrealtype t, N_Vector y, N_Vector, SUNMatrix j, void* ud, N_Vector,
                           N_Vector, N_Vector) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      const SparseMat& m = self->jp_;
      self->fill_jacobian(t, y, self->jp_.valuePtr());
      SUNMatZero(j);
      for (Index c = 0; c < m.outerSize(); ++c)
        for (SparseMat::InnerIterator it(m, c); it; ++it) {
          if constexpr (Band)
            SM_ELEMENT_B(j, it.row(), c) = it.value();
          else
            SM_ELEMENT_D(j, it.row(), c) = it.value();
        }
    });
  }
  // KLU: the structure is copied from the fixed pattern (SUNMatZero may have cleared it), the
  // values written in place into the library's array.
  static int jac_sparse_cb(sunrealtype t, N_Vector y, N_Vector, SUNMatrix j, void* ud, N_Vector,
                           N_Vector, N_Vector);
  static int jtsetup_cb(sunrealtype t, N_Vector y, N_Vector, void* ud);
  static int jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector, void* ud,
                       N_Vector);
  // Preconditioner P = I - γJ (CVODE's Newton matrix; ARKODE's M - γJ with M = I) set up and
  // solved in velocity form. K and D are evaluated when the library asks for a fresh Jacobian
  // (jok false), counted with the Jacobian evaluations.
  static constexpr double kVelocityPrecTol = 1e-4;
  static int psetup_cb(sunrealtype t, N_Vector y, N_Vector, sunbooleantype jok,
                       sunbooleantype* jcur, sunrealtype gamma, void* ud);
  static int psolve_cb(sunrealtype, N_Vector, N_Vector, N_Vector r, N_Vector z, sunrealtype,
                       sunrealtype, int, void* ud);
  static int velocity_jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector, void* ud,
                                N_Vector);

  const OdeSystem* sys_ = nullptr;
  // The system whose Jacobian the linear solver uses: sys_, or the view of its implicit part.
  const OdeSystem* jsys_ = nullptr;
  std::unique_ptr<OdeSystem> jview_;
  Index n_ = 0;
  bool use_analytic_ = false;
  Lin lin_ = Lin::dense;                     // the linear solver of this run (auto resolved)
  std::unique_ptr<VelocityFormSolver> vel_;  // linear_solver=velocity: the preconditioner
  std::string lin_note_;  // which solver and why, first line of the library report
  SUNLinearSolver ls_ = nullptr;
  SUNMatrix a_ = nullptr;
  // Analytic Jacobian: fixed pattern with current values, its structure in SUNDIALS' index type,
  // the maps into it, the model's matrices kept between calls.
  SparseMat jp_;
  std::vector<sunindextype> colptr_, rowind_;
  bool mech_ = false;  // values from MechanicalSystem::force_jacobians
  SparseMat k_, d_, jac_;
  BlockMap k_map_, d_map_, j_map_;
  std::vector<Index> ones_;  // positions of the identity block's entries
  long force_jac_evals_ = 0;
  std::string library_error_, callback_error_;
  CallbackGuard guard_;  // what a callback threw, rethrown when the library returns
};

}  // namespace stiffbench::sundials_detail
