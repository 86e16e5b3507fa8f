#include "integrators/symplectic/kick_drift.hpp"

#include "integrators/method_file.hpp"

namespace stiffbench {

namespace {
// Vector updates above this many entries run over OpenMP threads.
constexpr Index kParallelEntries = 50000;
}  // namespace

const std::vector<KickDriftCoefficients>& kick_drift_coefficients() {
  static const std::vector<KickDriftCoefficients> all = [] {
    std::vector<KickDriftCoefficients> out;
    for (const MethodDefinition& m : built_in_methods())
      if (m.kind == MethodKind::splitting && m.order <= 2) out.push_back(m.splitting.kick_drift);
    return out;
  }();
  return all;
}

namespace {

// First-same-as-last: the first stage kicks at the step's start position, the last kick is
// followed by no drift (so it saw the end-of-step position), and the force cannot depend on
// the velocity, which changed in between.
bool is_fsal(const KickDriftCoefficients& c, bool velocity_independent) {
  const std::size_t s = c.kick.size();
  std::size_t last_kick = s;
  for (std::size_t j = 0; j < s; ++j)
    if (c.kick[j] != 0.0) last_kick = j;
  if (!velocity_independent || s < 2 || c.kick[0] == 0.0 || last_kick == 0 || last_kick == s)
    return false;
  for (std::size_t j = last_kick; j < s; ++j)
    if (c.drift[j] != 0.0) return false;
  return true;
}

}  // namespace

KickDriftIntegrator::KickDriftIntegrator(KickDriftCoefficients coeffs, bool velocity_independent,
                                         std::string description)
    : Integrator({coeffs.name, Family::symplectic, coeffs.order,
                  coeffs.evaluations_per_step() - (is_fsal(coeffs, velocity_independent) ? 1 : 0),
                  Requirements{true, velocity_independent, false}, std::move(description)}),
      coeffs_(std::move(coeffs)),
      fsal_(is_fsal(coeffs_, velocity_independent)) {}

void KickDriftIntegrator::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  acc_.resize(mech_->dofs());
  cached_x_.resize(sys.has_constraints() ? mech_->dofs() : 0);
  cached_y_ = nullptr;
  cache_valid_ = false;
}

Status KickDriftIntegrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_)
    throw std::logic_error("KickDriftIntegrator::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  double tj = t;
  const std::size_t s = coeffs_.kick.size();
  for (std::size_t j = 0; j < s; ++j) {
    const double kj = coeffs_.kick[j], dj = coeffs_.drift[j];
    if (kj != 0.0) {
      const bool reuse = fsal_ && j == 0 && cache_valid_ && cached_y_ == y.data() &&
                         (!mech_->has_constraints() || cached_x_ == x);
      if (!reuse) mech_->acceleration(tj, x, v, acc_);
    }
    // Kick and drift fused in one pass (v_i += h k_j a_i, then x_i += h d_j v_i: the same
    // operations per entry as two separate passes), over OpenMP threads for large systems.
    const double hk = h * kj, hd = h * dj;
    double* xp = x.data();
    double* vp = v.data();
    const double* ap = acc_.data();
    const auto update = [&](Index i) {
      if (kj != 0.0) vp[i] += hk * ap[i];
      if (dj != 0.0) xp[i] += hd * vp[i];
    };
    if (n >= kParallelEntries) {
#pragma omp parallel for schedule(static)
      for (Index i = 0; i < n; ++i) update(i);
    } else {
      for (Index i = 0; i < n; ++i) update(i);
    }
    if (dj != 0.0) tj += hd;
  }
  if (fsal_) {
    // The last kick evaluated a at the final position; keep it for the next step.
    if (mech_->has_constraints()) cached_x_ = x;  // the driver's projection may move x
    cached_y_ = y.data();
    cache_valid_ = true;
  }
  return Status::ok;
}

}  // namespace stiffbench
