#include "integrators/reference/sundials/adapter.hpp"

#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spfgmr.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cstdlib>
#include <stdexcept>

#include "core/split_views.hpp"
#include "integrators/reference/sundials.hpp"

namespace stiffbench::sundials_detail {

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

void SundialsAdapter::reset(const OdeSystem& sys, const std::string& name, const Settings& set,
                            bool linear, double t0, CVecRef y0, bool implicit_part) {
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

void SundialsAdapter::create_linear_solver(N_Vector y, SUNContext ctx) {
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

void SundialsAdapter::free_linear_solver() {
  if (ls_) SUNLinSolFree(ls_);
  if (a_) SUNMatDestroy(a_);
  ls_ = nullptr;
  a_ = nullptr;
}

int SundialsAdapter::rhs_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
    Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
    self->sys_->rhs(t, yv, dv);
    return dv.allFinite() ? 0 : 1;  // non-finite: recoverable, the library retries smaller
  });
}

int SundialsAdapter::rhs_explicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
    Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
    self->sys_->rhs_explicit_part(t, yv, dv);
    return dv.allFinite() ? 0 : 1;
  });
}

int SundialsAdapter::rhs_implicit_cb(sunrealtype t, N_Vector y, N_Vector yd, void* ud) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    Eigen::Map<const Vec> yv(N_VGetArrayPointer(y), self->n_);
    Eigen::Map<Vec> dv(N_VGetArrayPointer(yd), self->n_);
    self->sys_->rhs_implicit_part(t, yv, dv);
    return dv.allFinite() ? 0 : 1;
  });
}

void SundialsAdapter::err_cb(int code, const char* module, const char* function, char* msg,
                             void* ud) {
  if (code > 0) return;  // warnings
  auto* self = static_cast<SundialsAdapter*>(ud);
  self->library_error_ = std::string(module) + "::" + function + ": " + msg;
}

void SundialsAdapter::resolve_linear_solver(const OdeSystem& sys, const std::string& name,
                                            Lin requested) {
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

void SundialsAdapter::build_jacobian_layout(double t0, CVecRef y0) {
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
      for (SparseMat::InnerIterator it(k_, c); it; ++it) trips.emplace_back(nd + it.row(), c, 1.0);
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

void SundialsAdapter::fill_jacobian(sunrealtype t, N_Vector y, double* data) {
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

int SundialsAdapter::jac_sparse_cb(sunrealtype t, N_Vector y, N_Vector, SUNMatrix j, void* ud,
                                   N_Vector, N_Vector, N_Vector) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    if (SUNSparseMatrix_NNZ(j) < static_cast<sunindextype>(self->rowind_.size()))
      throw std::logic_error("KLU matrix smaller than the Jacobian pattern");
    std::copy(self->colptr_.begin(), self->colptr_.end(), SUNSparseMatrix_IndexPointers(j));
    std::copy(self->rowind_.begin(), self->rowind_.end(), SUNSparseMatrix_IndexValues(j));
    self->fill_jacobian(t, y, SUNSparseMatrix_Data(j));
  });
}

int SundialsAdapter::jtsetup_cb(sunrealtype t, N_Vector y, N_Vector, void* ud) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] { self->fill_jacobian(t, y, self->jp_.valuePtr()); });
}

int SundialsAdapter::jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector, void* ud,
                               N_Vector) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  Eigen::Map<const Vec> vv(N_VGetArrayPointer(v), self->n_);
  Eigen::Map<Vec> out(N_VGetArrayPointer(jv), self->n_);
  out.noalias() = self->jp_ * vv;
  return 0;
}

int SundialsAdapter::psetup_cb(sunrealtype t, N_Vector y, N_Vector, sunbooleantype jok,
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

int SundialsAdapter::psolve_cb(sunrealtype, N_Vector, N_Vector, N_Vector r, N_Vector z, sunrealtype,
                               sunrealtype, int, void* ud) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    Eigen::Map<const Vec> rr(N_VGetArrayPointer(r), self->n_);
    Eigen::Map<Vec> zz(N_VGetArrayPointer(z), self->n_);
    zz.setZero();
    return self->vel_->solve(rr, zz).ok ? 0 : 1;  // 1: recoverable (the library retries)
  });
}

int SundialsAdapter::velocity_jtimes_cb(N_Vector v, N_Vector jv, sunrealtype, N_Vector, N_Vector,
                                        void* ud, N_Vector) {
  auto* self = static_cast<SundialsAdapter*>(ud);
  return self->guarded([&] {
    Eigen::Map<const Vec> vv(N_VGetArrayPointer(v), self->n_);
    Eigen::Map<Vec> out(N_VGetArrayPointer(jv), self->n_);
    self->vel_->jacobian_times(vv, out);
  });
}

}  // namespace stiffbench::sundials_detail
