#include "integrators/symplectic/kick_drift.hpp"

#include "integrators/method_file.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stiffbench {

namespace {
// Vector updates above this many entries run over OpenMP threads.
constexpr Index kParallelEntries = 50000;
}  // namespace

const std::vector<KickDriftCoefficients>& kick_drift_coefficients() {
  static const std::vector<KickDriftCoefficients> all = [] {
    std::vector<KickDriftCoefficients> out;
    for (const MethodDefinition& m : built_in_methods())
      if (m.kind == MethodKind::kick_drift && m.order <= 2) out.push_back(m.splitting.kick_drift);
    return out;
  }();
  return all;
}

namespace {

// First-same-as-last: the first stage kicks at the step's start position, the last kick is
// followed by no drift (so it saw the end-of-step position), and the force cannot depend on
// the velocity, which changed in between.
// ‖x‖∞ and ‖v‖∞ after a stage's update (NaN when an entry is NaN), where asked for.
struct UpdateNorms {
  double x = 0.0, v = 0.0;
};

// max |p_i| over [0, n) with NaN propagated, order-independent (the same for any thread count):
// nan becomes 1 at a NaN entry. Doubles on both, local to the loop, so the compiler vectorises it.
inline void track(double value, double& m, double& nan) {
  const double a = std::abs(value);
  nan = a != a ? 1.0 : nan;
  m = a > m ? a : m;
}

template <bool Kick, bool Drift, bool NormX, bool NormV>
void update_entries(Index begin, Index end, double* x, double* v, const double* a, double hk,
                    double hd, double& mx, double& mv, bool& nan_x, bool& nan_v) {
  double local_mx = mx, local_mv = mv, local_nan_x = 0.0, local_nan_v = 0.0;
  // `omp simd`: each entry reads and writes its own x_i, v_i and reads a_i only (x, v and a do not
  // overlap), and the norms are maxima, which do not depend on the order. Without it GCC 12 ran
  // the loop one entry at a time, the running maxima a chain of dependent instructions.
#pragma omp simd reduction(max : local_mx, local_mv, local_nan_x, local_nan_v)
  for (Index i = begin; i < end; ++i) {
    if constexpr (Kick) v[i] += hk * a[i];
    if constexpr (Drift) x[i] += hd * v[i];
    if constexpr (NormX) track(x[i], local_mx, local_nan_x);
    if constexpr (NormV) track(v[i], local_mv, local_nan_v);
  }
  mx = local_mx;
  mv = local_mv;
  nan_x = nan_x || local_nan_x != 0.0;
  nan_v = nan_v || local_nan_v != 0.0;
}

template <bool Kick, bool Drift, bool NormX, bool NormV>
UpdateNorms update_range(double* x, double* v, const double* a, Index n, double hk, double hd) {
  double mx = 0.0, mv = 0.0;
  bool nan_x = false, nan_v = false;
  if (n >= kParallelEntries) {
    // Contiguous chunks; the reduction variables are passed by reference inside the region, so
    // each thread updates its private copies.
    const Index chunks = 64;
#pragma omp parallel for schedule(static) reduction(max : mx, mv) reduction(|| : nan_x, nan_v)
    for (Index q = 0; q < chunks; ++q)
      update_entries<Kick, Drift, NormX, NormV>(n * q / chunks, n * (q + 1) / chunks, x, v, a, hk,
                                                hd, mx, mv, nan_x, nan_v);
  } else {
    update_entries<Kick, Drift, NormX, NormV>(0, n, x, v, a, hk, hd, mx, mv, nan_x, nan_v);
  }
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  return {nan_x ? kNaN : mx, nan_v ? kNaN : mv};
}

UpdateNorms update_stage(double* x, double* v, const double* a, Index n, bool kick, bool drift,
                         double hk, double hd, bool norm_x, bool norm_v) {
  const int key = (kick ? 8 : 0) + (drift ? 4 : 0) + (norm_x ? 2 : 0) + (norm_v ? 1 : 0);
  switch (key) {
#define STIFFBENCH_UPDATE_CASE(K) \
  case K:                         \
    return update_range<(K & 8) != 0, (K & 4) != 0, (K & 2) != 0, (K & 1) != 0>(x, v, a, n, hk, hd);
    STIFFBENCH_UPDATE_CASE(0)
    STIFFBENCH_UPDATE_CASE(1)
    STIFFBENCH_UPDATE_CASE(2)
    STIFFBENCH_UPDATE_CASE(3)
    STIFFBENCH_UPDATE_CASE(4)
    STIFFBENCH_UPDATE_CASE(5)
    STIFFBENCH_UPDATE_CASE(6)
    STIFFBENCH_UPDATE_CASE(7)
    STIFFBENCH_UPDATE_CASE(8)
    STIFFBENCH_UPDATE_CASE(9)
    STIFFBENCH_UPDATE_CASE(10)
    STIFFBENCH_UPDATE_CASE(11)
    STIFFBENCH_UPDATE_CASE(12)
    STIFFBENCH_UPDATE_CASE(13)
    STIFFBENCH_UPDATE_CASE(14)
    STIFFBENCH_UPDATE_CASE(15)
#undef STIFFBENCH_UPDATE_CASE
  }
  return {};
}

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
      fsal_(is_fsal(coeffs_, velocity_independent)) {
  for (std::size_t j = 0; j < coeffs_.kick.size(); ++j) {
    if (coeffs_.kick[j] != 0.0) last_kick_ = j;
    if (coeffs_.drift[j] != 0.0) last_drift_ = j;
  }
}

std::optional<double> KickDriftIntegrator::last_step_max_norm() const {
  // Every entry of x and v is written by some stage (a method with no kick or no drift leaves a
  // part unchanged and unmeasured: no norm then).
  if (last_kick_ == kNone || last_drift_ == kNone || !norm_valid_) return std::nullopt;
  return last_norm_;
}

void KickDriftIntegrator::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  mech_ = sys.as_mechanical();
  acc_.resize(mech_->dofs());
  cached_x_.resize(sys.has_constraints() ? mech_->dofs() : 0);
  cached_y_ = nullptr;
  cache_valid_ = false;
  norm_valid_ = false;
}

Status KickDriftIntegrator::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  if (&sys != mech_)
    throw std::logic_error("KickDriftIntegrator::step: system differs from reset()");
  const Index n = mech_->dofs();
  auto x = y.head(n);
  auto v = y.tail(n);
  double tj = t;
  const std::size_t s = coeffs_.kick.size();
  double norm_x = 0.0, norm_v = 0.0;
  for (std::size_t j = 0; j < s; ++j) {
    const double kj = coeffs_.kick[j], dj = coeffs_.drift[j];
    if (kj != 0.0) {
      const bool reuse = fsal_ && j == 0 && cache_valid_ && cached_y_ == y.data() &&
                         (!mech_->has_constraints() || cached_x_ == x);
      if (!reuse) mech_->acceleration(tj, x, v, acc_);
    }
    // Kick and drift fused in one pass (v_i += h k_j a_i, then x_i += h d_j v_i: the same
    // operations per entry as two separate passes), over OpenMP threads for large systems. The
    // stage that writes x (v) for the last time also takes its ‖·‖∞ for the driver.
    const UpdateNorms norms = update_stage(x.data(), v.data(), acc_.data(), n, kj != 0.0, dj != 0.0,
                                           h * kj, h * dj, j == last_drift_, j == last_kick_);
    if (j == last_drift_) norm_x = norms.x;
    if (j == last_kick_) norm_v = norms.v;
    if (dj != 0.0) tj += h * dj;
  }
  // max propagates no NaN: a NaN norm of either part wins explicitly.
  last_norm_ =
      std::isnan(norm_x) || std::isnan(norm_v) ? norm_x + norm_v : std::max(norm_x, norm_v);
  norm_valid_ = true;
  if (fsal_) {
    // The last kick evaluated a at the final position; keep it for the next step.
    if (mech_->has_constraints()) cached_x_ = x;  // the driver's projection may move x
    cached_y_ = y.data();
    cache_valid_ = true;
  }
  return Status::ok;
}

}  // namespace stiffbench
