#include "integrators/reference/sundials.hpp"

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_mristep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_version.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spfgmr.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <utility>

#include "core/run_control.hpp"
#include "core/split_views.hpp"
#include "integrators/method_entry.hpp"
#include "integrators/reference/callback_guard.hpp"
#include "integrators/solvers/velocity_form.hpp"

namespace stiffbench {

namespace {

enum class Lin { automatic, dense, band, klu, spgmr, velocity };

const char* to_string(Lin l) {
  switch (l) {
    case Lin::automatic:
      return "auto";
    case Lin::dense:
      return "dense";
    case Lin::band:
      return "band";
    case Lin::klu:
      return "klu";
    case Lin::spgmr:
      return "spgmr";
    case Lin::velocity:
      return "velocity";
  }
  return "?";
}

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
std::string capture(const std::function<void(FILE*)>& print) {
  char* buf = nullptr;
  std::size_t len = 0;
  FILE* f = open_memstream(&buf, &len);
  if (!f) return {};
  print(f);
  std::fclose(f);
  std::string out(buf, len);
  std::free(buf);
  return out;
}

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
             double t0, CVecRef y0, bool implicit_part = false) {
    sys_ = &sys;
    jview_ = implicit_part ? implicit_part_view(sys) : nullptr;
    jsys_ = implicit_part ? jview_.get() : &sys;
    n_ = sys.dimension();
    const OdeSystem& js = *jsys_;
    use_analytic_ = set.jacobian == "analytic" || (set.jacobian == "auto" && js.has_jacobian());
    require_input(!use_analytic_ || js.has_jacobian(),
                  "integrator '" + name + "': model '" + sys.name() + "' has no analytic " +
                      (implicit_part ? "Jacobian of its split's implicit part" : "Jacobian"));
    resolve_linear_solver(js, name, set.lin);
    force_jac_evals_ = 0;
    if (use_analytic_ && linear) build_jacobian_layout(t0, y0);
    vel_.reset();
    if (lin_ == Lin::velocity) {
      vel_ = std::make_unique<VelocityFormSolver>();
      vel_->reset(*js.as_mechanical(), LinearSolverOptions{}, t0, y0);
    }
  }

  // The matrix and the linear solver of this run (the caller hands them to the library).
  void create_linear_solver(N_Vector y, SUNContext ctx) {
    switch (lin_) {
      case Lin::automatic:  // resolved in reset()
      case Lin::dense:
        a_ = SUNDenseMatrix(n_, n_, ctx);
        ls_ = SUNLinSol_Dense(y, a_, ctx);
        break;
      case Lin::band: {
        Index mu = n_ - 1, ml = n_ - 1;
        if (use_analytic_ || jsys_->has_jacobian_pattern()) {
          mu = ml = 0;
          const SparseMat p = use_analytic_ ? jp_ : jsys_->jacobian_pattern();
          for (Index c = 0; c < p.outerSize(); ++c)
            for (SparseMat::InnerIterator it(p, c); it; ++it) {
              mu = std::max(mu, c - it.row());
              ml = std::max(ml, it.row() - c);
            }
        }
        a_ = SUNBandMatrix(n_, mu, ml, ctx);
        ls_ = SUNLinSol_Band(y, a_, ctx);
        break;
      }
      case Lin::klu:
        a_ = SUNSparseMatrix(n_, n_, jp_.nonZeros(), CSC_MAT, ctx);
        ls_ = SUNLinSol_KLU(y, a_, ctx);
        break;
      case Lin::spgmr:
        ls_ = SUNLinSol_SPGMR(y, SUN_PREC_NONE, 0, ctx);
        break;
      case Lin::velocity:
        // Flexible GMRES, right-preconditioned by the velocity-form solve of P = I - γJ (an
        // inner Krylov solve to a relative kVelocityPrecTol is not a fixed linear operator, hence
        // the flexible variant); with the exact J the outer iteration converges in one or two.
        ls_ = SUNLinSol_SPFGMR(y, SUN_PREC_RIGHT, 5, ctx);
        break;
    }
  }
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
  void free_linear_solver() {
    if (ls_) SUNLinSolFree(ls_);
    if (a_) SUNMatDestroy(a_);
    ls_ = nullptr;
    a_ = nullptr;
  }

  // --- callbacks (C ABI: exceptions must not cross it); user data is the adapter ----------
  static int rhs_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
      Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
      self->sys_->rhs(t, yv, dv);
      return dv.allFinite() ? 0 : 1;  // non-finite: recoverable, the library retries smaller
    });
  }
  static int rhs_explicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
      Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
      self->sys_->rhs_explicit_part(t, yv, dv);
      return dv.allFinite() ? 0 : 1;
    });
  }
  static int rhs_implicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
      Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
      self->sys_->rhs_implicit_part(t, yv, dv);
      return dv.allFinite() ? 0 : 1;
    });
  }
  static void err_cb(int code, const char* module, const char* function, char* msg, void* ud) {
    if (code > 0) return;  // warnings
    auto* self = static_cast<SundialsAdapter*>(ud);
    self->library_error_ = std::string(module) + "::" + function + ": " + msg;
  }

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
  void resolve_linear_solver(const OdeSystem& sys, const std::string& name, Lin requested) {
    if (requested == Lin::automatic) {
      const MechanicalSystem* m = sys.as_mechanical();
      const bool velocity = use_analytic_ && m && m->has_force_jacobians();
      const SundialsLinearSolverChoice c = sundials_auto_linear_solver(n_, use_analytic_, velocity);
      lin_ = c.solver == "klu"        ? Lin::klu
             : c.solver == "spgmr"    ? Lin::spgmr
             : c.solver == "velocity" ? Lin::velocity
                                      : Lin::dense;
      lin_note_ = std::string(to_string(lin_)) + " (linear_solver=auto: " + c.rule + ")";
    } else {
      lin_ = requested;
      lin_note_ = std::string(to_string(lin_)) + " (linear_solver=" + to_string(lin_) + ")";
    }
    require_input(
        lin_ != Lin::klu || use_analytic_,
        "integrator '" + name + "': linear_solver=klu needs the model's analytic sparse Jacobian");
    require_input(lin_ != Lin::velocity || (use_analytic_ && sys.as_mechanical() &&
                                            sys.as_mechanical()->has_force_jacobians()),
                  "integrator '" + name +
                      "': linear_solver=velocity needs a mechanical model with force Jacobians "
                      "(and jacobian=auto or analytic)");
  }

  // The fixed pattern jp_ = pattern(J) ∪ diagonal, computed once per reset(), and the maps
  // from the model's matrices into it. Structure only: the evaluations here are not counted.
  void build_jacobian_layout(double t0, CVecRef y0) {
    const MechanicalSystem* ms = jsys_->as_mechanical();
    mech_ = ms != nullptr && ms->has_force_jacobians();
    std::vector<Eigen::Triplet<double>> trips;
    for (Index i = 0; i < n_; ++i) trips.emplace_back(i, i, 0.0);
    if (mech_) {
      const Index nd = ms->dofs();
      ms->force_jacobians(t0, y0.head(nd), y0.tail(nd), k_, d_);
      k_.makeCompressed();
      d_.makeCompressed();
      for (const SparseMat* b : {&k_, &d_})
        if (b->rows() != nd || b->cols() != nd)
          throw std::logic_error("model '" + sys_->name() + "': force Jacobian block is " +
                                 std::to_string(b->rows()) + " x " + std::to_string(b->cols()) +
                                 ", expected " + std::to_string(nd) + " x " + std::to_string(nd));
      for (Index i = 0; i < nd; ++i) trips.emplace_back(i, nd + i, 1.0);
      for (Index c = 0; c < nd; ++c) {
        for (SparseMat::InnerIterator it(k_, c); it; ++it)
          trips.emplace_back(nd + it.row(), c, 1.0);
        for (SparseMat::InnerIterator it(d_, c); it; ++it)
          trips.emplace_back(nd + it.row(), nd + c, 1.0);
      }
    } else {
      jac_ = jsys_->jacobian_pattern();  // compressed, the structure jacobian() fills
      for (Index c = 0; c < jac_.outerSize(); ++c)
        for (SparseMat::InnerIterator it(jac_, c); it; ++it) trips.emplace_back(it.row(), c, 1.0);
    }
    jp_.resize(n_, n_);
    jp_.setFromTriplets(trips.begin(), trips.end());
    jp_.makeCompressed();
    colptr_.assign(jp_.outerIndexPtr(), jp_.outerIndexPtr() + n_ + 1);
    rowind_.assign(jp_.innerIndexPtr(), jp_.innerIndexPtr() + jp_.nonZeros());
    ones_.clear();
    if (mech_) {
      const Index nd = ms->dofs();
      for (Index i = 0; i < nd; ++i) ones_.push_back(BlockMap::find(jp_, i, nd + i));
      k_map_ = BlockMap(nd, 0);
      d_map_ = BlockMap(nd, nd);
      k_map_.build(k_, jp_);
      d_map_.build(d_, jp_);
    } else {
      j_map_ = BlockMap(0, 0);
      j_map_.build(jac_, jp_);
    }
  }

  // Writes J(t, y) into `data`, the value array of a matrix with jp_'s structure (the KLU
  // matrix's own array, or jp_'s). No allocation once the model's blocks have their pattern.
  void fill_jacobian(sunrealtype t, N_Vector y, double* data) {
    Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), n_);
    std::fill(data, data + jp_.nonZeros(), 0.0);
    auto scatter = [&](SparseMat& m, BlockMap& map) {
      m.makeCompressed();
      if (!map.matches(m)) map.build(m, jp_);  // the model changed its pattern
      map.scatter(m, data);
    };
    if (mech_) {
      const Index nd = n_ / 2;
      jsys_->as_mechanical()->force_jacobians(t, yv.head(nd), yv.tail(nd), k_, d_);
      ++force_jac_evals_;
      for (const Index p : ones_) data[p] = 1.0;
      scatter(k_, k_map_);
      scatter(d_, d_map_);
    } else {
      jsys_->jacobian(t, yv, jac_);
      scatter(jac_, j_map_);
    }
  }

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
                           N_Vector, N_Vector) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      if (SUNSparseMatrix_NNZ(j) < static_cast<sunindextype>(self->rowind_.size()))
        throw std::logic_error("KLU matrix smaller than the Jacobian pattern");
      std::copy(self->colptr_.begin(), self->colptr_.end(), SUNSparseMatrix_IndexPointers(j));
      std::copy(self->rowind_.begin(), self->rowind_.end(), SUNSparseMatrix_IndexValues(j));
      self->fill_jacobian(t, y, SUNSparseMatrix_Data(j));
    });
  }
  static int jtsetup_cb(sunrealtype t, N_Vector y, N_Vector, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] { self->fill_jacobian(t, y, self->jp_.valuePtr()); });
  }
  static int jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector, void* ud,
                       N_Vector) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    Eigen::Map<const Vec> vv(N_VGetArrayPointer(v), self->n_);
    Eigen::Map<Vec> out(N_VGetArrayPointer(jv), self->n_);
    out.noalias() = self->jp_ * vv;
    return 0;
  }
  // Preconditioner P = I - γJ (CVODE's Newton matrix; ARKODE's M - γJ with M = I) set up and
  // solved in velocity form. K and D are evaluated when the library asks for a fresh Jacobian
  // (jok false), counted with the Jacobian evaluations.
  static constexpr double kVelocityPrecTol = 1e-4;
  static int psetup_cb(sunrealtype t, N_Vector y, N_Vector, sunbooleantype jok,
                       sunbooleantype* jcur, sunrealtype gamma, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      if (!jok) {
        Eigen::Map<const Vec> yy(N_VGetArrayPointer(y), self->n_);
        self->vel_->update(t, yy);
        ++self->force_jac_evals_;
      }
      *jcur = jok ? SUNFALSE : SUNTRUE;
      if (!self->vel_->factor(gamma)) {  // the linear solver refused: a solver error
        self->callback_error_ = self->vel_->error();
        return -1;
      }
      self->vel_->set_tolerance(kVelocityPrecTol);
      return 0;
    });
  }
  static int psolve_cb(sunrealtype, N_Vector, N_Vector, N_Vector r, N_Vector z, sunrealtype,
                       sunrealtype, int, void* ud) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      Eigen::Map<const Vec> rr(N_VGetArrayPointer(r), self->n_);
      Eigen::Map<Vec> zz(N_VGetArrayPointer(z), self->n_);
      zz.setZero();
      return self->vel_->solve(rr, zz).ok ? 0 : 1;  // 1: recoverable (the library retries)
    });
  }
  static int velocity_jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector, void* ud,
                                N_Vector) {
    auto* self = static_cast<SundialsAdapter*>(ud);
    return self->guarded([&] {
      Eigen::Map<const Vec> vv(N_VGetArrayPointer(v), self->n_);
      Eigen::Map<Vec> out(N_VGetArrayPointer(jv), self->n_);
      self->vel_->jacobian_times(vv, out);
    });
  }

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

  void reset(const OdeSystem& sys, double t0, CVecRef y0) override {
    check_compatible(info(), sys);
    adapter_.reset(sys, info().name, set_, needs_linear_solver(), t0, y0, uses_implicit_part(sys));
    t_ = t0;
    y_last_ = y0;
    fixed_h_ = 0;
    fixed_mode_ = false;
    free_memory();
    // The library copies y0 into its own vectors; the wrapper only lends it the data.
    N_Vector y = N_VMake_Serial(adapter_.size(), const_cast<double*>(y0.data()), ctx_);
    SolveStats dummy;
    auto ok = [&](int flag, const char* what) {
      if (!check(flag, what, dummy)) throw std::runtime_error(dummy.message);
    };
    create(t0, y, ok);
    if (needs_linear_solver()) {
      adapter_.create_linear_solver(y, ctx_);
      attach_linear_solver(ok);
    }
    N_VDestroy(y);
  }

  Status advance_to(const OdeSystem& sys, double t_out, VecRef y, SolveStats& stats) override {
    sync(sys, t_, y);
    // Step exactly to t_out instead of stepping past it and interpolating: ARKODE's dense
    // output at tolerances near 1e-8 was measured to be off by 1e-5 on y' = (-1+3i)y.
    if (!check(set_stop_time(t_out), "SetStopTime", stats)) return Status::solver_error;
    return evolve(t_out, y, false, stats);
  }

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
                    int (*set_fixed_step)(void*, sunrealtype)) {
    sync(sys, t, y);
    if (h != fixed_h_) {
      if (!check(set_fixed_step(mem_, h), "ARKStepSetFixedStep", stats))
        return Status::solver_error;
      fixed_h_ = h;
    }
    fixed_mode_ = true;
    return evolve(t + h, y, true, stats);
  }

  Settings set_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  SundialsAdapter adapter_;

 private:
  bool check(int flag, const char* what, SolveStats& stats) {
    if (flag >= 0) return true;
    // The library allocates the flag name; the caller frees it.
    char* name = flag_name(flag);
    const std::string& lib = adapter_.library_error();
    stats.message = std::string(what) + " failed: " + (name ? name : "unknown flag") +
                    (lib.empty() ? "" : " (" + lib + ")");
    std::free(name);
    if (!adapter_.callback_error().empty()) stats.message += "; " + adapter_.callback_error();
    std::cerr << "stiffbench: " << info().name << ": " << stats.message << "\n";
    return false;
  }

  // Re-initialises the library when the state was changed from outside (e.g. a constraint
  // projection) or when the driver restarts at another time.
  void sync(const OdeSystem& sys, double t, CVecRef y) {
    if (&sys != adapter_.system())
      throw std::logic_error("SUNDIALS integrator: system differs from reset()");
    // The driver computes t0 + k·h while the library accumulates: equal up to rounding.
    if (std::abs(t - t_) <= 1e-13 * std::max(1.0, std::abs(t)) && y == y_last_) return;
    N_Vector yw = N_VMake_Serial(adapter_.size(), const_cast<double*>(y.data()), ctx_);
    reinit(t, yw);
    N_VDestroy(yw);
    t_ = t;
  }

  Status evolve(double t_out, VecRef y, bool one_step, SolveStats& stats) {
    adapter_.clear_errors();
    // The driver's storage: no copy.
    N_Vector yout = N_VMake_Serial(adapter_.size(), y.data(), ctx_);
    sunrealtype tret = t_;
    const int flag = solve(t_out, yout, &tret, one_step);
    N_VDestroy(yout);
    read_counters(stats);
    adapter_.rethrow();
    if (!check(flag, solve_name(), stats)) return Status::solver_error;
    t_ = tret;
    y_last_ = y;
    return Status::ok;
  }

  void read_counters(SolveStats& s) {
    const Counters c = counters(s);
    if (!fixed_mode_) s.steps = c.steps;  // the fixed-step driver counts its own steps
    s.error_test_failures = c.etf;
    s.newton_iters = c.nni;
    s.newton_conv_failures = c.ncf;
    s.linear_setups = c.nsetups;
    s.lin_solves = needs_linear_solver() ? c.nni : 0;  // one linear solve per Newton iteration
    s.linear_iters = c.nli;
    // Analytic Jacobians through OdeSystem::jacobian() are counted at the system boundary,
    // force_jacobians() calls here; difference-quotient ones are the library's count.
    s.jac_evals = adapter_.use_analytic() ? adapter_.force_jacobian_evals() : c.nje;
    s.library_f_evals = c.nfe + c.nfi + c.nfels;
    if (needs_linear_solver())
      s.library_report = "Linear solver                = " + adapter_.linear_solver_note() + "\n" +
                         s.library_report;
  }

  Vec y_last_;
  double t_ = 0, fixed_h_ = 0;
  bool fixed_mode_ = false;
};

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

// arkode_erk, arkode_dirk, arkode_imex: ARKStep with explicit, implicit or IMEX tables;
// adaptive or fixed step.
enum class ArkodeMode { explicit_only, implicit_only, imex };

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

std::vector<ParamSpec> common_specs(bool linear) {
  using P = ParamType;
  using B = Bounds;
  std::vector<ParamSpec> s = {
      {"rtol", P::real, "1e-6",
       "relative tolerance (adaptive mode; also scales Newton's tolerance)", B::positive()},
      {"atol", P::real, "1e-10", "absolute tolerance", B::non_negative()},
      {"max_steps", P::integer, "100000", "maximum internal steps per output interval",
       B::at_least(1)},
  };
  if (linear) {
    s.push_back({"linear_solver",
                 P::text,
                 "auto",
                 "dense, band, klu (sparse, needs the analytic Jacobian), spgmr (matrix-free "
                 "GMRES) or velocity (flexible GMRES preconditioned by the velocity-form solve "
                 "of I - gamma J; mechanical models with force Jacobians); auto: dense up to " +
                     std::to_string(kSundialsAutoDenseMax) +
                     " unknowns; above, velocity for mechanical models with force Jacobians, "
                     "klu with another analytic sparse Jacobian, spgmr otherwise (jacobian=dq "
                     "counts as none); solve prints the choice and the rule first in the library "
                     "statistics",
                 {"auto", "dense", "band", "klu", "spgmr", "velocity"}});
    s.push_back({"jacobian",
                 P::text,
                 "auto",
                 "analytic, dq (library difference quotients); auto: analytic where provided",
                 {"auto", "analytic", "dq"}});
  }
  return s;
}

Settings read_common(const Params& p, bool linear) {
  Settings s;
  s.rtol = p.real("rtol");
  s.atol = p.real("atol");
  require_input(s.rtol > 0, "parameter 'rtol' must be > 0");
  require_input(s.atol >= 0, "parameter 'atol' must be >= 0");
  s.max_steps = p.integer("max_steps");
  require_input(s.max_steps >= 1, "parameter 'max_steps' must be >= 1");
  if (linear) {
    const std::string& l = p.text("linear_solver");
    s.lin = l == "band"       ? Lin::band
            : l == "klu"      ? Lin::klu
            : l == "spgmr"    ? Lin::spgmr
            : l == "velocity" ? Lin::velocity
            : l == "dense"    ? Lin::dense
                              : Lin::automatic;
    s.jacobian = p.text("jacobian");
  }
  return s;
}

// Order of an ARKODE table by name (BadInput for an unknown name).
int erk_order(const std::string& name) {
  ARKodeButcherTable t = ARKodeButcherTable_LoadERKByName(name.c_str());
  require_input(t != nullptr,
                "parameter 'explicit_table': unknown ARKODE explicit table '" + name + "'");
  const int q = t->q;
  ARKodeButcherTable_Free(t);
  return q;
}
int dirk_order(const std::string& name) {
  ARKodeButcherTable t = ARKodeButcherTable_LoadDIRKByName(name.c_str());
  require_input(t != nullptr,
                "parameter 'implicit_table': unknown ARKODE implicit table '" + name + "'");
  const int q = t->q;
  ARKodeButcherTable_Free(t);
  return q;
}

// The ARK pairs of ARKODE 5.4 (SUNDIALS 6.4) by the `tables` key of arkode_imex: explicit and
// implicit tables of C. A. Kennedy & M. H. Carpenter, Additive Runge-Kutta schemes for
// convection-diffusion-reaction equations, Appl. Numer. Math. 44 (2003) 139-181 (ark324l2sa,
// ark436l2sa, ark548l2sa) and Higher-order additive Runge-Kutta schemes for ordinary
// differential equations, Appl. Numer. Math. 136 (2019) 183-205 (ark437l2sa, ark548l2sab).
struct ArkPair {
  const char* key;
  ARKODE_ERKTableID erk;
  ARKODE_DIRKTableID dirk;
  const char* erk_name;
  const char* dirk_name;
};
constexpr ArkPair kArkPairs[] = {
    {"ark324l2sa", ARKODE_ARK324L2SA_ERK_4_2_3, ARKODE_ARK324L2SA_DIRK_4_2_3,
     "ARKODE_ARK324L2SA_ERK_4_2_3", "ARKODE_ARK324L2SA_DIRK_4_2_3"},
    {"ark436l2sa", ARKODE_ARK436L2SA_ERK_6_3_4, ARKODE_ARK436L2SA_DIRK_6_3_4,
     "ARKODE_ARK436L2SA_ERK_6_3_4", "ARKODE_ARK436L2SA_DIRK_6_3_4"},
    {"ark437l2sa", ARKODE_ARK437L2SA_ERK_7_3_4, ARKODE_ARK437L2SA_DIRK_7_3_4,
     "ARKODE_ARK437L2SA_ERK_7_3_4", "ARKODE_ARK437L2SA_DIRK_7_3_4"},
    {"ark548l2sa", ARKODE_ARK548L2SA_ERK_8_4_5, ARKODE_ARK548L2SA_DIRK_8_4_5,
     "ARKODE_ARK548L2SA_ERK_8_4_5", "ARKODE_ARK548L2SA_DIRK_8_4_5"},
    {"ark548l2sab", ARKODE_ARK548L2SAb_ERK_8_4_5, ARKODE_ARK548L2SAb_DIRK_8_4_5,
     "ARKODE_ARK548L2SAb_ERK_8_4_5", "ARKODE_ARK548L2SAb_DIRK_8_4_5"},
};

// arkode_imex's `tables`: a pair by number, or (named) the two tables by name.
void read_ark_pair(const Params& p, Settings& s) {
  const std::string key = p.text("tables");
  s.explicit_table = p.text("explicit_table");
  s.implicit_table = p.text("implicit_table");
  if (key == "named") {
    require_input(!s.explicit_table.empty() && !s.implicit_table.empty(),
                  "tables=named needs both parameters 'explicit_table' and 'implicit_table'");
    return;
  }
  require_input(s.explicit_table.empty() && s.implicit_table.empty(),
                "parameters 'explicit_table' and 'implicit_table' need tables=named (tables=" +
                    key + " chooses both tables)");
  for (const ArkPair& a : kArkPairs)
    if (key == a.key) {
      s.erk_num = a.erk;
      s.dirk_num = a.dirk;
      s.explicit_table = a.erk_name;
      s.implicit_table = a.dirk_name;
      return;
    }
  throw BadInput("parameter 'tables': unknown ARK pair '" + key + "'");
}

// ARKODE's Newton iteration on the implicit stages. It stops when its estimate of the stage
// error, in the WRMS norm of the weights 1/(rtol |y| + atol), is below nonlin_conv_coef; ARKODE's
// defaults (0.1, 3 iterations) leave a stage error near 0.1 rtol. A fixed-step run that is to
// agree with another implementation of the same tables to round-off needs the iteration
// converged: rtol=1e-12 atol=1e-14 nonlin_conv_coef=1e-3 max_nonlin_iters=20 (docs/design.md).
std::vector<ParamSpec> nonlin_specs() {
  return {{"nonlin_conv_coef", ParamType::real, "0.1",
           "Newton stops when its error estimate (WRMS norm with the rtol/atol weights) is below "
           "this (ARKStepSetNonlinConvCoef; ARKODE's default 0.1); fixed-step comparisons: "
           "1e-3 with rtol=1e-12 atol=1e-14",
           Bounds::positive()},
          {"max_nonlin_iters", ParamType::integer, "3",
           "Newton iterations per stage before the step fails (ARKStepSetMaxNonlinIters; "
           "ARKODE's default 3; a failure in fixed-step mode ends the run)",
           Bounds::at_least(1)}};
}
void read_nonlin(const Params& p, Settings& s) {
  s.nonlin_conv_coef = p.real("nonlin_conv_coef");
  require_input(s.nonlin_conv_coef > 0, "parameter 'nonlin_conv_coef' must be > 0");
  s.max_nonlin_iters = static_cast<int>(p.integer("max_nonlin_iters"));
  require_input(s.max_nonlin_iters >= 1, "parameter 'max_nonlin_iters' must be >= 1");
}

// arkode_mri's slow coupling tables: explicit slow part (f_E) only.
struct MriTable {
  const char* key;
  ARKODE_MRITableID id;
  int order;
};
constexpr MriTable kMriTables[] = {
    {"mri_gark_erk33a", ARKODE_MRI_GARK_ERK33a, 3},
    {"mis_kw3", ARKODE_MIS_KW3, 3},
    {"mri_gark_erk45a", ARKODE_MRI_GARK_ERK45a, 4},
};

constexpr MethodText kArkodeMriText{
    .description =
        "SUNDIALS ARKODE MRIStep on the model's split: slow f_E explicit (MRI coupling "
        "table), fast f_I by an inner implicit ARKStep with J_I; fixed slow step",
    .kind = "library: ARKODE (multirate)",
    .reference =
        "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a "
        "flexible IVP solver infrastructure for one-step methods, ACM Trans. Math. "
        "Softw. 49 (2023) 19; A. Sandu, A class of multirate infinitesimal GARK methods, "
        "SIAM J. Numer. Anal. 57 (2019) 2300-2327"};

void register_arkode_mri(IntegratorRegistry& reg, const ParamSpec& lsetup) {
  auto specs = common_specs(true);
  specs.push_back(lsetup);
  for (const ParamSpec& n : nonlin_specs()) specs.push_back(n);
  std::vector<std::string> keys;
  for (const MriTable& m : kMriTables) keys.emplace_back(m.key);
  specs.push_back({"coupling", ParamType::text, "mri_gark_erk33a",
                   "slow coupling table (MRIStepSetCoupling): mri_gark_erk33a (order 3, Sandu "
                   "2019), mis_kw3 (order 3, ARKODE's own default at order 3; Knoth & Wolke "
                   "1998), mri_gark_erk45a (order 4)",
                   keys});
  specs.push_back({"fast_steps", ParamType::integer, "0",
                   "fast (inner) steps of h/fast_steps (ARKStepSetFixedStep on the inner "
                   "ARKStep); 0: the inner ARKStep adapts its step to rtol/atol",
                   Bounds::at_least(0)});
  specs.push_back({"implicit_table", ParamType::text, "ARKODE_SDIRK_5_3_4",
                   "the inner ARKStep's DIRK table for f_I, by ARKODE name"});
  add_built_in_integrator(
      reg, {method_info("arkode_mri", Family::reference, 3, 0, Requirements{.split = true},
                        kArkodeMriText),
            specs, [](const Params& p) {
              Settings s = read_common(p, true);
              s.lsetup_frequency = p.integer("lsetup_frequency");
              require_input(s.lsetup_frequency >= 1, "parameter 'lsetup_frequency' must be >= 1");
              read_nonlin(p, s);
              s.fast_steps = p.integer("fast_steps");
              require_input(s.fast_steps >= 0, "parameter 'fast_steps' must be >= 0");
              s.implicit_table = p.text("implicit_table");
              dirk_order(s.implicit_table);  // BadInput for an unknown name
              const std::string key = p.text("coupling");
              int order = 0;
              for (const MriTable& m : kMriTables)
                if (key == m.key) {
                  s.mri_table = m.id;
                  order = m.order;
                }
              require_input(order > 0, "parameter 'coupling': unknown MRI table '" + key + "'");
              Requirements needs;
              needs.split = true;
              MethodInfo info =
                  method_info("arkode_mri", Family::reference, order, 0, needs, kArkodeMriText);
              info.description = "ARKODE MRIStep " + key + ", fast " + s.implicit_table +
                                 (s.fast_steps > 0 ? " at h/" + std::to_string(s.fast_steps)
                                                   : std::string(" adaptive"));
              return std::make_unique<MriIntegrator>(info, s);
            }});
}

}  // namespace

// A dense n x n matrix is 8n² bytes (4.8 GB for cloth n = 64's 24,576 unknowns) and its LU costs
// 2n³/3 flops per setup; KLU factorises the sparse I - γJ instead, and without an analytic
// Jacobian SPGMR needs only f and products (no n difference quotients per setup). The limit's
// measurements are in sundials.hpp.
SundialsLinearSolverChoice sundials_auto_linear_solver(Index unknowns, bool analytic_jacobian,
                                                       bool mechanical_blocks) {
  const std::string size = std::to_string(unknowns) + " unknowns";
  const std::string limit = std::to_string(kSundialsAutoDenseMax);
  if (unknowns <= kSundialsAutoDenseMax) return {"dense", size + " <= " + limit};
  if (analytic_jacobian && mechanical_blocks)
    return {"velocity", size + " > " + limit + " and a mechanical model with force Jacobians"};
  if (analytic_jacobian) return {"klu", size + " > " + limit + " and an analytic sparse Jacobian"};
  return {"spgmr", size + " > " + limit + " and no analytic Jacobian"};
}

namespace {

constexpr const char* kSundials =
    "A. C. Hindmarsh et al., SUNDIALS: suite of nonlinear and differential/algebraic equation "
    "solvers, ACM Trans. Math. Softw. 31 (2005) 363-396";
constexpr const char* kArkode =
    "D. R. Reynolds, D. J. Gardner, C. S. Woodward & R. Chinomona, ARKODE: a flexible IVP "
    "solver infrastructure for one-step methods, ACM Trans. Math. Softw. 49 (2023) 19";

struct CvodeMethod {
  const char* name;
  int lmm;
  int max_order;
  MethodText text;
};

constexpr MethodText kArkodeErkText{
    .description = "SUNDIALS ARKODE ARKStep, explicit table by name; adaptive or fixed step",
    .kind = "library: ARKODE",
    .reference = kArkode};
constexpr MethodText kArkodeDirkText{
    .description =
        "SUNDIALS ARKODE ARKStep, DIRK table by name (default L-stable SDIRK order 4); "
        "adaptive or fixed step",
    .kind = "library: ARKODE",
    .reference = kArkode};
constexpr MethodText kArkodeImexText{
    .description = "SUNDIALS ARKODE ARKStep IMEX with the model's split (all-implicit without one)",
    .kind = "library: ARKODE",
    .reference = kArkode};

// The MethodInfo of an ARKODE integrator created with the given tables: the registered kind
// and reference, and a description naming the tables.
MethodInfo arkode_info(const char* name, int order, const MethodText& text,
                       std::string description) {
  MethodInfo info = method_info(name, Family::reference, order, 0, {}, text);
  info.description = std::move(description);
  return info;
}

}  // namespace

void register_sundials_integrators(IntegratorRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  // CVodeSetMaxOrd refuses an order above the method's (CV_ILL_INPUT): at most 5 for BDF, 12 for
  // Adams.
  for (const CvodeMethod& m :
       {CvodeMethod{
            "cvode_bdf",
            CV_BDF,
            5,
            {.description = "SUNDIALS CVODE, variable-order BDF (1-5) with Newton; adaptive",
            .kind = "library: CVODE",
            .reference = kSundials}},
        CvodeMethod{"cvode_adams",
                    CV_ADAMS,
                    12,
                    {.description = "SUNDIALS CVODE, variable-order Adams-Moulton (1-12) with "
                                    "Newton; adaptive",
                    .kind = "library: CVODE",
                    .reference = kSundials}}}) {
    auto cvode_specs = common_specs(true);
    cvode_specs.push_back({"max_order", P::integer, "0",
                           "maximum order (0: CVODE default, 5 for BDF, 12 for Adams)",
                           B::in(0, m.max_order)});
    const MethodInfo info = method_info(m.name, Family::reference, 0, 0, {}, m.text);
    add_built_in_integrator(reg, {info, cvode_specs, [info, lmm = m.lmm](const Params& p) {
                                    Settings s = read_common(p, true);
                                    s.max_order = static_cast<int>(p.integer("max_order"));
                                    require_input(s.max_order >= 0,
                                                  "parameter 'max_order' must be >= 0");
                                    return std::make_unique<CvodeIntegrator>(info, lmm, s);
                                  }});
  }
  auto erk_specs = common_specs(false);
  erk_specs.push_back({"explicit_table", P::text, "ARKODE_DORMAND_PRINCE_7_4_5",
                       "ARKODE explicit Butcher table name"});
  add_built_in_integrator(
      reg, {method_info("arkode_erk", Family::reference, erk_order("ARKODE_DORMAND_PRINCE_7_4_5"),
                        7, {}, kArkodeErkText),
            erk_specs, [](const Params& p) {
              Settings s = read_common(p, false);
              s.explicit_table = p.text("explicit_table");
              MethodInfo info = arkode_info("arkode_erk", erk_order(s.explicit_table),
                                            kArkodeErkText, "ARKODE ERK " + s.explicit_table);
              return std::make_unique<ArkodeIntegrator>(info, ArkodeMode::explicit_only, s);
            }});
  // ARKODE's default reuses M - γJ for up to 20 steps; with ARKODE_SDIRK_5_3_4 and a matrix
  // solver that gave errors of 2e-6 at rtol = 1e-8 on y' = (-1+3i)y (SPGMR: 5e-11), measured
  // with a standalone ARKODE 5.4.1 program. A setup every step restores the accuracy.
  const ParamSpec lsetup{
      "lsetup_frequency", P::integer, "1",
      "steps between linear-solver setups (ARKODE's own default is 20; see sundials.cpp)",
      B::at_least(1)};
  auto dirk_specs = common_specs(true);
  dirk_specs.push_back(lsetup);
  for (const ParamSpec& n : nonlin_specs()) dirk_specs.push_back(n);
  dirk_specs.push_back(
      {"implicit_table", P::text, "ARKODE_SDIRK_5_3_4", "ARKODE implicit Butcher table name"});
  add_built_in_integrator(
      reg, {method_info("arkode_dirk", Family::reference, dirk_order("ARKODE_SDIRK_5_3_4"), 5, {},
                        kArkodeDirkText),
            dirk_specs, [](const Params& p) {
              Settings s = read_common(p, true);
              s.lsetup_frequency = p.integer("lsetup_frequency");
              require_input(s.lsetup_frequency >= 1, "parameter 'lsetup_frequency' must be >= 1");
              read_nonlin(p, s);
              s.implicit_table = p.text("implicit_table");
              MethodInfo info = arkode_info("arkode_dirk", dirk_order(s.implicit_table),
                                            kArkodeDirkText, "ARKODE DIRK " + s.implicit_table);
              return std::make_unique<ArkodeIntegrator>(info, ArkodeMode::implicit_only, s);
            }});
  auto imex_specs = common_specs(true);
  imex_specs.push_back(lsetup);
  for (const ParamSpec& n : nonlin_specs()) imex_specs.push_back(n);
  std::vector<std::string> pair_keys;
  for (const ArkPair& a : kArkPairs) pair_keys.emplace_back(a.key);
  pair_keys.emplace_back("named");
  imex_specs.push_back(
      {"tables", P::text, "ark436l2sa",
       "the ARK pair (ARKStepSetTableNum): ark324l2sa = ARKODE_ARK324L2SA_ERK_4_2_3 + "
       "ARKODE_ARK324L2SA_DIRK_4_2_3 (order 3, ARKODE's default at order 3), ark436l2sa = "
       "ARK436L2SA_ERK_6_3_4 + _DIRK_6_3_4 (order 4, ARKODE's default), ark437l2sa, ark548l2sa "
       "(ARKODE's default at order 5), ark548l2sab; named: explicit_table and implicit_table",
       pair_keys});
  imex_specs.push_back({"explicit_table", P::text, "",
                        "with tables=named: the explicit table of the pair by ARKODE name"});
  imex_specs.push_back({"implicit_table", P::text, "",
                        "with tables=named: the implicit table of the pair by ARKODE name"});
  const ArkPair& def = kArkPairs[1];
  add_built_in_integrator(
      reg, {method_info("arkode_imex", Family::reference, dirk_order(def.dirk_name), 6, {},
                        kArkodeImexText),
            imex_specs, [](const Params& p) {
              Settings s = read_common(p, true);
              s.lsetup_frequency = p.integer("lsetup_frequency");
              require_input(s.lsetup_frequency >= 1, "parameter 'lsetup_frequency' must be >= 1");
              read_nonlin(p, s);
              read_ark_pair(p, s);
              const int q = std::min(erk_order(s.explicit_table), dirk_order(s.implicit_table));
              MethodInfo info =
                  arkode_info("arkode_imex", q, kArkodeImexText,
                              "ARKODE IMEX " + s.explicit_table + " / " + s.implicit_table);
              return std::make_unique<ArkodeIntegrator>(info, ArkodeMode::imex, s);
            }});
  register_arkode_mri(reg, lsetup);
}

std::string sundials_library_version() {
  char version[64] = {};
  if (SUNDIALSGetVersion(version, static_cast<int>(sizeof version)) != 0) return "unknown";
  return version;
}

}  // namespace stiffbench
