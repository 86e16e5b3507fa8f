#include "models/sph/sph_fluid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif
#include <omp.h>
#include <Eigen/IterativeLinearSolvers>

#include "models/detail/with_dim.hpp"

namespace stiffbench {

// GCC and clang note that the 32-byte vectors of pair_lanes.inc would be passed differently with
// and without AVX; its helpers are always inlined, so no such call exists (reported at the end of
// the file, hence for the whole file).
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

// The pair loops' arguments (pair_lanes.inc): the slot-ordered fields and the neighbour rows.
namespace sph_lanes {
// The fields of a fluid slot's record (SphFluid::SlotRecord): position (D), mass, velocity (D),
// density.
constexpr int kRecLen = 8, kRecX = 0, kRecM = 3, kRecV = 4, kRecRho = 7;

struct DensityArgs {
  const double* rec;    // fluid records by slot (position and mass read)
  const double* bx;     // boundary positions by boundary slot
  const double* sbvol;  // boundary volumes by boundary slot
  const std::uint32_t* cand;
  const std::uint32_t* cand_count;
  const std::uint32_t* cand_bcount;
  std::uint32_t* nb_index;
  std::size_t* nb_count;
  std::size_t* nb_bcount;
  double* srho;  // out: densities by slot
  std::size_t cap;
  double h2, rho0;
  const sph::Kernel* wd;
};

struct ForceArgs {
  const double* rec;  // fluid records by slot
  const double *sp, *spr2, *sinv_rho, *bx, *sbvol;
  const std::uint32_t* nb_index;
  const std::size_t *nb_count, *nb_bcount;
  double* spair;  // out: the pair sums by slot (D each)
  std::size_t cap;
  bool variational, artificial, muller;
  double rho0, mu, av, eps2, bfac;
  const sph::Kernel *wg, *wv;
};
}  // namespace sph_lanes

// The pair loops, portable (SSE2 on x86-64: two lanes per instruction) ...
#ifdef __AVX2__
#define STIFFBENCH_LANES_AVX2 1
#else
#define STIFFBENCH_LANES_AVX2 0
#endif
#define STIFFBENCH_LANES_AVX512 0
namespace sph_lanes_portable {
using namespace sph_lanes;
#include "models/sph/pair_lanes.inc"
}  // namespace sph_lanes_portable
#undef STIFFBENCH_LANES_AVX2

// ... and, in a build without -mavx2, the same source compiled for AVX2 (four lanes per
// instruction, a branch-free left-pack in the density pass) and for AVX-512 (full groups of eight
// neighbours in eight lanes, compressed stores in the density pass, 32 vector registers), chosen
// at run time when the processor has them.
// All give the same bits (pair_lanes.inc).
// (GCC only: clang has no `#pragma GCC target`; a clang build uses the portable loops.)
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__AVX2__)
#define STIFFBENCH_SPH_AVX2_DISPATCH 1
#pragma GCC push_options
#pragma GCC target("avx2")
#define STIFFBENCH_LANES_AVX2 1
namespace sph_lanes_avx2 {
using namespace sph_lanes;
#include "models/sph/pair_lanes.inc"
}  // namespace sph_lanes_avx2
#undef STIFFBENCH_LANES_AVX2
#pragma GCC pop_options
#pragma GCC push_options
#pragma GCC target("avx2,avx512f,avx512vl,avx512dq")
#undef STIFFBENCH_LANES_AVX512
#define STIFFBENCH_LANES_AVX512 1
#define STIFFBENCH_LANES_AVX2 1
namespace sph_lanes_avx512 {
using namespace sph_lanes;
#include "models/sph/pair_lanes.inc"
}  // namespace sph_lanes_avx512
#undef STIFFBENCH_LANES_AVX2
#pragma GCC pop_options
#endif
#undef STIFFBENCH_LANES_AVX512

namespace {

std::string short_num(double x) {
  std::ostringstream os;
  os.precision(4);
  os << x;
  return os.str();
}

// Σ_{k ∈ Z^D} W(|k| Δx): the kernel summed over a full lattice around one of its points.
double lattice_sum(const sph::Kernel& w, int dim, double dx) {
  const int r = static_cast<int>(std::ceil(w.support() / dx)) + 1;
  double sum = 0.0;
  for (int i = -r; i <= r; ++i)
    for (int j = -r; j <= r; ++j)
      for (int k = (dim == 3 ? -r : 0); k <= (dim == 3 ? r : 0); ++k)
        sum += w.w(dx * std::sqrt(double(i * i + j * j + k * k)));
  return sum;
}

}  // namespace

SphFluid::SphFluid(std::string name, SphScene scene, SphOptions options)
    : name_(std::move(name)), scene_(std::move(scene)), opt_(options), dim_(scene_.dim) {
  const std::string who = "model '" + name_ + "': ";
  require_input(dim_ == 2 || dim_ == 3, who + "dimension must be 2 or 3");
  require_input(std::isfinite(opt_.spacing) && opt_.spacing > 0, who + "spacing must be > 0");
  require_input(std::isfinite(opt_.support) && opt_.support > opt_.spacing,
                who + "support radius must exceed the particle spacing (support > 1)");
  require_input(std::isfinite(opt_.rho0) && opt_.rho0 > 0, who + "rho0 must be > 0");
  require_input(std::isfinite(opt_.c0) && opt_.c0 >= 0, who + "c0 must be >= 0");
  require_input(std::isfinite(opt_.k), who + "k must be finite");
  require_input(std::isfinite(opt_.tait_gamma) && opt_.tait_gamma > 1,
                who + "tait_gamma must be > 1");
  require_input(std::isfinite(opt_.mu) && opt_.mu >= 0, who + "mu must be >= 0");
  require_input(std::isfinite(opt_.alpha) && opt_.alpha >= 0, who + "alpha must be >= 0");
  require_input(std::isfinite(opt_.skin) && opt_.skin >= 0, who + "skin must be >= 0");
  require_input(opt_.density_kernel != sph::KernelType::viscosity,
                who + "the viscosity kernel is singular at r = 0: not a density kernel");
  require_input(opt_.gradient_kernel != sph::KernelType::viscosity,
                who +
                    "the viscosity kernel's gradient is singular at r = 0: not a gradient "
                    "kernel");
  require_input(!scene_.fluid_x.empty(), who + "the scene has no fluid particles");
  require_input(scene_.fluid_v.size() == scene_.fluid_x.size(),
                who + "one velocity per fluid particle is required");

  // The neighbour lists hold 32-bit slots.
  require_input(scene_.fluid_x.size() < (std::size_t{1} << 32) &&
                    scene_.boundary_x.size() < (std::size_t{1} << 32),
                who + "more than 2^32 - 1 fluid or boundary particles");
  n_ = static_cast<Index>(scene_.fluid_x.size());
  wd_ = sph::Kernel(opt_.density_kernel, dim_, opt_.support);
  wg_ = sph::Kernel(opt_.gradient_kernel, dim_, opt_.support);
  wv_ = sph::Kernel(sph::KernelType::viscosity, dim_, opt_.support);
  hs_ = 0.5 * opt_.support;
  skin_ = opt_.skin * opt_.support;
  mass_ = opt_.rho0 / lattice_sum(wd_, dim_, opt_.spacing);
  m_.assign(static_cast<std::size_t>(n_), mass_);

  if (opt_.eos == SphEos::linear) {
    k_ = opt_.k >= 0 ? opt_.k : opt_.c0 * opt_.c0;
    c_ = std::sqrt(k_);
  } else {
    c_ = opt_.c0;
    tait_b_ = opt_.rho0 * c_ * c_ / opt_.tait_gamma;
  }
  switch (opt_.viscosity) {
    case SphViscosity::none:
      nu_ = 0.0;
      break;
    case SphViscosity::muller:
      nu_ = opt_.mu / opt_.rho0;
      break;
    case SphViscosity::artificial:
      nu_ = opt_.alpha * c_ * hs_ / 8.0;
      break;
  }
  viscous_ = (opt_.viscosity == SphViscosity::muller && opt_.mu > 0) ||
             (opt_.viscosity == SphViscosity::artificial && opt_.alpha > 0);
  parallel_ = n_ >= opt_.parallel_threshold;
  acoustic_rate_ = lattice_acoustic_rate();

  y0_.resize(2 * dofs());
  for (Index i = 0; i < n_; ++i)
    for (int d = 0; d < dim_; ++d) {
      y0_[dim_ * i + d] = scene_.fluid_x[static_cast<std::size_t>(i)][static_cast<std::size_t>(d)];
      y0_[dofs() + dim_ * i + d] =
          scene_.fluid_v[static_cast<std::size_t>(i)][static_cast<std::size_t>(d)];
    }
  require_input(y0_.allFinite(), who + "non-finite initial state");

  if (opt_.boundary == SphBoundary::particles) {
    const Index nb = static_cast<Index>(scene_.boundary_x.size());
    bx_.resize(static_cast<std::size_t>(nb * dim_));
    for (Index b = 0; b < nb; ++b)
      for (int d = 0; d < dim_; ++d)
        bx_[static_cast<std::size_t>(dim_ * b + d)] =
            scene_.boundary_x[static_cast<std::size_t>(b)][static_cast<std::size_t>(d)];
    bvol_.assign(static_cast<std::size_t>(nb), 0.0);
    detail::with_dim<2, 3>(dim_, [&](auto dc) {
      constexpr int D = decltype(dc)::value;
      auto& g = const_cast<sph::NeighbourGrid<D>&>(boundary_grid<D>());
      g.build(bx_.data(), nb, opt_.support);
      // Akinci et al. 2012: V_b = 1 / Σ_k W(x_b - x_k) over the boundary particles (self
      // included), so that densely sampled walls do not push harder than sparse ones.
      for (Index b = 0; b < nb; ++b) {
        double sum = 0.0;
        g.for_each_neighbour(bx_.data() + D * b, opt_.support,
                             [&](Index, double r2, const auto&) { sum += wd_.w(std::sqrt(r2)); });
        bvol_[static_cast<std::size_t>(b)] = 1.0 / sum;
      }
      // The Verlet list's boundary candidates come from this grid with cells h + s: rebuilt
      // once here (the volumes above keep the cells h), with the volumes in its slot order.
      g.build(bx_.data(), nb, opt_.support + skin_);
      sbvol_.resize(bvol_.size());
      for (std::size_t k = 0; k < sbvol_.size(); ++k)
        sbvol_[k] = bvol_[static_cast<std::size_t>(g.order()[k])];
    });
  }
  if (opt_.equilibrium_masses) solve_equilibrium_masses();
  rho_.assign(static_cast<std::size_t>(n_), opt_.rho0);
  p_.assign(static_cast<std::size_t>(n_), 0.0);
}

void SphFluid::solve_equilibrium_masses() {
  // Σ_j m_j W(x_i - x_j) = ρ0 - ρ0 Σ_b V_b W(x_i - x_b) for every fluid particle i: the kernel
  // matrix of a Wendland or poly6 kernel is symmetric positive definite, so CG solves it.
  const Vec x = y0_.head(dofs());
  std::vector<Eigen::Triplet<double>> trips;
  Vec rhs(n_);
  const double g = std::abs(opt_.gravity[1]);
  for (Index i = 0; i < n_; ++i) {
    const double depth = scene_.rest_height - x[dim_ * i + 1];
    const double p = scene_.rest_height > 0 && depth > 0 ? opt_.rho0 * g * depth : 0.0;
    // The EOS solved for ρ at pressure p >= 0.
    rhs[i] = opt_.eos == SphEos::linear
                 ? (k_ > 0 ? opt_.rho0 + p / k_ : opt_.rho0)
                 : opt_.rho0 * std::pow(1.0 + p / tait_b_, 1.0 / opt_.tait_gamma);
  }
  detail::with_dim<2, 3>(dim_, [&](auto dc) {
    constexpr int D = decltype(dc)::value;
    auto& grid = const_cast<sph::NeighbourGrid<D>&>(fluid_grid<D>());
    grid.build(x.data(), n_, opt_.support);
    for (Index i = 0; i < n_; ++i) {
      grid.for_each_neighbour(x.data() + D * i, opt_.support, [&](Index j, double r2, const auto&) {
        trips.emplace_back(i, j, wd_.w(std::sqrt(r2)));
      });
      if (!bvol_.empty()) {
        double bsum = 0.0;
        boundary_grid<D>().for_each_neighbour(
            x.data() + D * i, opt_.support, [&](Index b, double r2, const auto&) {
              bsum += bvol_[static_cast<std::size_t>(b)] * wd_.w(std::sqrt(r2));
            });
        rhs[i] -= opt_.rho0 * bsum;
      }
    }
  });
  SparseMat a(n_, n_);
  a.setFromTriplets(trips.begin(), trips.end());
  Eigen::ConjugateGradient<SparseMat, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-14);
  cg.setMaxIterations(10 * static_cast<int>(n_));
  cg.compute(a);
  const Vec m = cg.solveWithGuess(rhs, Vec::Constant(n_, mass_));
  require_input(cg.info() == Eigen::Success && m.allFinite(),
                "model '" + name_ + "': masses=equilibrium: CG did not solve the kernel system (" +
                    std::to_string(cg.iterations()) + " iterations, error " +
                    short_num(cg.error()) +
                    "; the kernel may not be positive definite, e.g. cubic_spline); use "
                    "masses=lattice");
  require_input(m.minCoeff() > 0,
                "model '" + name_ + "': masses=equilibrium gives negative particle masses (min " +
                    short_num(m.minCoeff()) +
                    "; large supports and kernels that are not positive definite do this); use "
                    "masses=lattice");
  for (Index i = 0; i < n_; ++i) m_[static_cast<std::size_t>(i)] = m[i];
}

template <int D>
const sph::NeighbourGrid<D>& SphFluid::fluid_grid() const {
  if constexpr (D == 2)
    return grid2_;
  else
    return grid3_;
}

template <int D>
const sph::NeighbourGrid<D>& SphFluid::boundary_grid() const {
  if constexpr (D == 2)
    return bgrid2_;
  else
    return bgrid3_;
}

double SphFluid::pressure(double rho) const {
  double p;
  if (opt_.eos == SphEos::linear)
    p = k_ * (rho - opt_.rho0);
  else
    p = tait_b_ * (std::pow(rho / opt_.rho0, opt_.tait_gamma) - 1.0);
  return opt_.clamp ? std::max(0.0, p) : p;
}

double SphFluid::internal_energy(double rho) const {
  if (opt_.clamp && rho < opt_.rho0) return 0.0;
  const double r0 = opt_.rho0;
  if (opt_.eos == SphEos::linear) return k_ * (std::log(rho / r0) + r0 / rho - 1.0);
  const double g = opt_.tait_gamma;
  return tait_b_ / (g - 1.0) *
         (std::pow(rho, g - 1.0) / std::pow(r0, g) + (g - 1.0) / rho - g / r0);
}

// The Verlet list (see the header comment). update_list() rebuilds it when some particle has
// moved more than s/2 since the last build (or at the first call, or when a coordinate is not
// finite: the comparison fails).
template <int D>
void SphFluid::update_list(const double* x) const {
  const std::size_t n = static_cast<std::size_t>(n_);
  bool stale = list_x_.size() != n * D;
  if (!stale) {
    const double half = 0.5 * skin_, half2 = half * half;
    double worst = 0.0;
#pragma omp parallel for schedule(static) reduction(max : worst) if (parallel_)
    for (Index i = 0; i < n_; ++i) {
      double d2 = 0.0;
      for (int d = 0; d < D; ++d) {
        const double e = x[D * i + d] - list_x_[static_cast<std::size_t>(D * i + d)];
        d2 += e * e;
      }
      // A NaN displacement counts as stale (max would drop it).
      worst = std::max(worst, d2 == d2 ? d2 : std::numeric_limits<double>::infinity());
    }
    stale = !(worst <= half2);
  }
  if (stale) build_list<D>(x);
}

template <int D>
void SphFluid::build_list(const double* x) const {
  ++list_builds_;
  count_neighbour_build();
  const std::size_t n = static_cast<std::size_t>(n_);
  const double radius = opt_.support + skin_;
  auto& grid = const_cast<sph::NeighbourGrid<D>&>(fluid_grid<D>());
  grid.build(x, n_, radius);
  list_x_.assign(x, x + n * D);
  list_order_ = grid.order();
  slot_of_.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    slot_of_[static_cast<std::size_t>(list_order_[k])] = static_cast<std::uint32_t>(k);
  cand_count_.resize(n);
  cand_bcount_.resize(n);
  const auto& order = list_order_;
  const auto& bgrid = boundary_grid<D>();
  const bool with_boundary = !bvol_.empty();
  while (true) {
    const std::size_t cap = cand_capacity_;
    cand_.resize(n * cap);
    std::size_t most = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(max : most) if (parallel_)
    for (Index s = 0; s < n_; ++s) {
      const std::size_t k = static_cast<std::size_t>(s);
      std::uint32_t* c = cand_.data() + k * cap;
      std::size_t count = 0;
      const double* xi = grid.positions() + D * k;
      // Fluid candidates as particle indices first (sorted below, then mapped to slots).
      grid.for_each_neighbour_slot(xi, radius, [&](std::size_t j, double, const auto&) {
        if (count < cap) c[count] = static_cast<std::uint32_t>(order[j]);
        ++count;
      });
      const std::size_t fluid = count;
      if (with_boundary)
        bgrid.for_each_neighbour_slot(xi, radius, [&](std::size_t b, double, const auto&) {
          if (count < cap) c[count] = static_cast<std::uint32_t>(b);
          ++count;
        });
      most = std::max(most, count);
      if (count > cap) continue;
      // Fluid candidates by particle index, boundary ones by boundary slot: orders that do not
      // depend on the positions at the build.
      std::sort(c, c + fluid);
      for (std::size_t q = 0; q < fluid; ++q) c[q] = slot_of_[c[q]];
      std::sort(c + fluid, c + count);
      cand_count_[k] = static_cast<std::uint32_t>(fluid);
      cand_bcount_[k] = static_cast<std::uint32_t>(count - fluid);
    }
    if (most <= cap) break;
    cand_capacity_ = most + most / 4;
  }
  nb_index_.resize(n * cand_capacity_);
}

// The pair passes hand out slots in blocks of this many through a BlockQueue (block_queue.hpp):
// each thread works through its own contiguous share first, so that what it reads was mostly
// written by its own core in the previous pass, then takes blocks from the tails of the others'
// (the two vCPUs of the development machine at times differ by up to 1.7x in speed: equal
// static shares would wait for the slower one). A particle's sums do not depend on the thread
// that computes them, so the results are the same for any thread count and any order.
constexpr Index kSlotBlock = 256;

Index SphFluid::slot_blocks() const { return (n_ + kSlotBlock - 1) / kSlotBlock; }

std::pair<std::size_t, std::size_t> SphFluid::slot_block(Index block) const {
  const Index first = block * kSlotBlock;
  return {static_cast<std::size_t>(first),
          static_cast<std::size_t>(std::min(n_, first + kSlotBlock))};
}

namespace {

#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
std::atomic<bool> g_avx2_allowed{true};
bool avx2_usable() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes && g_avx2_allowed.load(std::memory_order_relaxed);
}
std::atomic<bool> g_avx512_allowed{true};
bool avx512_usable() {
  static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                          __builtin_cpu_supports("avx512dq");
  return yes && avx2_usable() && g_avx512_allowed.load(std::memory_order_relaxed);
}
#endif

// The pair loops' build a pass runs (read once per pass, so that all its blocks use one build).
enum class LanesBuild { portable, avx2, avx512 };
LanesBuild lanes_build() {
#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
  return avx512_usable() ? LanesBuild::avx512
                         : (avx2_usable() ? LanesBuild::avx2 : LanesBuild::portable);
#elif defined(__AVX2__)
  return LanesBuild::avx2;
#else
  return LanesBuild::portable;
#endif
}

template <int D, sph::KernelType KD>
void density_range(const sph_lanes::DensityArgs& a, std::size_t first, std::size_t last,
                   double* scratch, LanesBuild build) {
#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
  if (build == LanesBuild::avx512)
    return sph_lanes_avx512::density_range<D, KD>(a, first, last, scratch);
  if (build == LanesBuild::avx2)
    return sph_lanes_avx2::density_range<D, KD>(a, first, last, scratch);
#else
  (void)build;
#endif
  sph_lanes_portable::density_range<D, KD>(a, first, last, scratch);
}

template <int D, sph::KernelType KG, bool Explicit, bool Implicit>
void force_range(const sph_lanes::ForceArgs& a, std::size_t first, std::size_t last,
                 LanesBuild build) {
#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
  if (build == LanesBuild::avx512)
    return sph_lanes_avx512::force_range<D, KG, Explicit, Implicit>(a, first, last);
  if (build == LanesBuild::avx2)
    return sph_lanes_avx2::force_range<D, KG, Explicit, Implicit>(a, first, last);
#else
  (void)build;
#endif
  sph_lanes_portable::force_range<D, KG, Explicit, Implicit>(a, first, last);
}

}  // namespace

void SphFluid::allow_avx2(bool yes) {
#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
  g_avx2_allowed.store(yes, std::memory_order_relaxed);
#else
  (void)yes;
#endif
}

void SphFluid::allow_avx512(bool yes) {
#ifdef STIFFBENCH_SPH_AVX2_DISPATCH
  g_avx512_allowed.store(yes, std::memory_order_relaxed);
#else
  (void)yes;
#endif
}

bool SphFluid::uses_avx2() const { return lanes_build() != LanesBuild::portable; }

bool SphFluid::uses_avx512() const { return lanes_build() == LanesBuild::avx512; }

// Both passes work in slot order (the Verlet list's cell order): slot k is particle
// list_order_[k], and every per-particle array they use (positions, velocities, masses,
// densities, pressures, neighbour slots) is indexed by slot, so the neighbours of consecutive
// particles sit in nearby memory. The state's order never changes: densities and pressures are
// also written by particle index, accelerations by particle index. The pair sums themselves are
// pair_lanes.inc's loops (four lanes; their summation order is documented there).
template <int D, sph::KernelType KD>
void SphFluid::density_pass(const double* x) const {
  update_list<D>(x);
  const auto& order = list_order_;
  const std::size_t n = static_cast<std::size_t>(n_);
  rho_.resize(n);
  p_.resize(n);
  srho_.resize(n);
  sp_.resize(n);
  spr2_.resize(n);
  sinv_rho_.resize(n);
  nb_count_.resize(n);
  nb_bcount_.resize(n);
  rec_.resize(n);
  double* rec = rec_.data()->f;
  const sph_lanes::DensityArgs args{rec,
                                    boundary_grid<D>().positions(),
                                    sbvol_.data(),
                                    cand_.data(),
                                    cand_count_.data(),
                                    cand_bcount_.data(),
                                    nb_index_.data(),
                                    nb_count_.data(),
                                    nb_bcount_.data(),
                                    srho_.data(),
                                    cand_capacity_,
                                    opt_.support * opt_.support,
                                    opt_.rho0,
                                    &wd_};
  const LanesBuild build = lanes_build();
  // One row of squared distances per thread (+ 4: the left-pack's full-vector stores).
  scratch_.resize(static_cast<std::size_t>(parallel_ ? omp_get_max_threads() : 1) *
                  (cand_capacity_ + 4));
  blocks_.reset(slot_blocks(), parallel_ ? omp_get_max_threads() : 1);
#pragma omp parallel if (parallel_)
  {
#pragma omp for schedule(static)
    for (Index s = 0; s < n_; ++s) {
      const std::size_t k = static_cast<std::size_t>(s), i = static_cast<std::size_t>(order[k]);
      double* r = rec + sph_lanes::kRecLen * k;
      for (int d = 0; d < D; ++d) r[sph_lanes::kRecX + d] = x[D * i + d];
      r[sph_lanes::kRecM] = m_[i];
    }
    const std::size_t t = parallel_ ? static_cast<std::size_t>(omp_get_thread_num()) : 0;
    double* scratch = scratch_.data() + t * (cand_capacity_ + 4);
    for (std::int64_t block; (block = blocks_.next(static_cast<int>(t))) >= 0;) {
      const auto [first, last] = slot_block(block);
      density_range<D, KD>(args, first, last, scratch, build);
      for (std::size_t k = first; k < last; ++k) {
        const double rho = srho_[k], p = pressure(rho);
        sp_[k] = p;
        sinv_rho_[k] = 1.0 / rho;
        spr2_[k] = p / (rho * rho);
        const std::size_t iu = static_cast<std::size_t>(order[k]);
        rho_[iu] = rho;
        p_[iu] = p;
      }
    }
  }
}

// P selects the terms (Part::all: every term, so split=none is the sum of the two parts' terms
// in one pass): explicit_part = gravity, pressure, boundary pressure and penalty walls;
// implicit_part = both viscosities with their boundary terms. a_i = g + (pair sum) + walls.
template <int D, sph::KernelType KG, SphFluid::Part P>
void SphFluid::force_pass(const double* v, double* a) const {
  constexpr bool with_explicit = P != Part::implicit_part;
  constexpr bool with_implicit = P != Part::explicit_part;
  const auto& order = list_order_;
  const std::size_t n = static_cast<std::size_t>(n_);
  const bool penalty = opt_.boundary == SphBoundary::penalty;
  const double d0 = wall_range(), k_wall = wall_strength();
  spair_.resize(n * D);
  double* rec = rec_.data()->f;  // (sized and half filled by density_pass)
  const sph_lanes::ForceArgs args{rec,
                                  sp_.data(),
                                  spr2_.data(),
                                  sinv_rho_.data(),
                                  boundary_grid<D>().positions(),
                                  sbvol_.data(),
                                  nb_index_.data(),
                                  nb_count_.data(),
                                  nb_bcount_.data(),
                                  spair_.data(),
                                  cand_capacity_,
                                  opt_.form == SphPressureForm::variational,
                                  opt_.viscosity == SphViscosity::artificial && opt_.alpha > 0,
                                  opt_.viscosity == SphViscosity::muller && opt_.mu > 0,
                                  opt_.rho0,
                                  opt_.mu,
                                  opt_.alpha * c_ * hs_,
                                  0.01 * hs_ * hs_,
                                  opt_.mirror_boundary_pressure ? 2.0 : 1.0,
                                  &wg_,
                                  &wv_};
  const LanesBuild build = lanes_build();
  blocks_.reset(slot_blocks(), parallel_ ? omp_get_max_threads() : 1);
#pragma omp parallel if (parallel_)
  {
#pragma omp for schedule(static)
    for (Index s = 0; s < n_; ++s) {
      const std::size_t k = static_cast<std::size_t>(s);
      double* r = rec + sph_lanes::kRecLen * k;
      for (int d = 0; d < D; ++d) r[sph_lanes::kRecV + d] = v[D * order[k] + d];
      r[sph_lanes::kRecRho] = srho_[k];
    }
    const int me = parallel_ ? omp_get_thread_num() : 0;
    for (std::int64_t block; (block = blocks_.next(me)) >= 0;) {
      const auto [first, last] = slot_block(block);
      force_range<D, KG, with_explicit, with_implicit>(args, first, last, build);
      for (std::size_t k = first; k < last; ++k) {
        const double* xi = rec + sph_lanes::kRecLen * k + sph_lanes::kRecX;
        std::array<double, D> acc;
        for (int d = 0; d < D; ++d)
          acc[d] = (with_explicit ? opt_.gravity[static_cast<std::size_t>(d)] : 0.0) +
                   spair_[D * k + static_cast<std::size_t>(d)];
        if (with_explicit && penalty) {
          for (const auto& wall : scene_.walls) {
            double sd = -wall.offset;
            for (int d = 0; d < D; ++d) sd += wall.normal[static_cast<std::size_t>(d)] * xi[d];
            if (sd < d0) {
              const double qw = 1.0 - sd / d0;
              for (int d = 0; d < D; ++d)
                acc[d] += k_wall * qw * qw * wall.normal[static_cast<std::size_t>(d)];
            }
          }
        }
        const Index i = order[k];
        for (int d = 0; d < D; ++d) a[D * i + d] = acc[d];
      }
    }
  }
}

template <SphFluid::Part P>
void SphFluid::acceleration_impl(const double* x, const double* v, double* a) const {
  detail::with_dim<2, 3>(dim_, [&](auto dc) {
    constexpr int D = decltype(dc)::value;
    sph::with_kernel(opt_.density_kernel,
                     [&](auto kd) { density_pass<D, decltype(kd)::value>(x); });
    sph::with_kernel(opt_.gradient_kernel,
                     [&](auto kg) { force_pass<D, decltype(kg)::value, P>(v, a); });
  });
}

void SphFluid::eval_acceleration(double, CVecRef x, CVecRef v, VecRef a) const {
  acceleration_impl<Part::all>(x.data(), v.data(), a.data());
}

void SphFluid::eval_acceleration_explicit_part(double, CVecRef x, CVecRef v, VecRef a) const {
  require_input(has_imex_split(), name_ + ": no split (parameter split=none)");
  acceleration_impl<Part::explicit_part>(x.data(), v.data(), a.data());
}

void SphFluid::eval_acceleration_implicit_part(double, CVecRef x, CVecRef v, VecRef a) const {
  require_input(has_imex_split(), name_ + ": no split (parameter split=none)");
  acceleration_impl<Part::implicit_part>(x.data(), v.data(), a.data());
}

std::optional<SplitInfo> SphFluid::imex_split() const {
  if (opt_.split == SphSplit::none) return std::nullopt;
  std::string visc =
      "viscosity (Mueller's mu or Monaghan's artificial alpha, whichever is selected) with its "
      "boundary-particle terms (with x' = v)";
  if (!viscous_) visc += "; none is selected here, so a_I = 0";
  return SplitInfo{"viscosity", "pressure, boundary-particle pressure or penalty walls, gravity",
                   visc};
}

// f_E = [0; a_E]: its Jacobian is nilpotent; the rate that limits an explicit a_E is the pressure
// waves' oscillation ±iω under x' = v (eigenvalues of [[0, I], [∂a_E/∂x, 0]]), ω up to the
// lattice's acoustic rate, and the penalty walls' ω where they are on.
std::optional<SpectrumEstimate> SphFluid::explicit_part_spectrum(double, CVecRef) const {
  if (opt_.split == SphSplit::none) return std::nullopt;
  double rate = acoustic_rate_;
  if (opt_.boundary == SphBoundary::penalty && !scene_.walls.empty())
    rate = std::max(rate, penalty_frequency());
  return SpectrumEstimate{rate, SpectrumEstimate::Ray::imaginary};
}

// The fastest pressure wave of the uniform lattice at rest (p0 = 0, lattice masses; derivation
// in the header comment): ω² = f c² (T_g(k)·T_d(k)) / S², T(k) = Σ_j ∇W(X_j) sin(k·X_j) over
// the lattice offsets X_j, S = Σ_j W_d(X_j), f = 1 (variational) or 1/2 (symmetric), maximised
// over a grid of wave vectors k ∈ [0, π/Δx]^D with k_x >= k_y (>= k_z) (the lattice's and the
// radial kernels' symmetry).
double SphFluid::lattice_acoustic_rate() const {
  const double dx = opt_.spacing;
  const double h = std::max(wd_.support(), wg_.support());
  const int r = static_cast<int>(std::ceil(h / dx)) + 1;
  const int kz = dim_ == 3 ? r : 0;
  struct Offset {
    double x[3];
    double gd, gg;  // dW/dr / r of the density and gradient kernels
  };
  std::vector<Offset> offs;
  double sum_w = 0.0;
  for (int i = -r; i <= r; ++i)
    for (int j = -r; j <= r; ++j)
      for (int k = -kz; k <= kz; ++k) {
        const double len = dx * std::sqrt(double(i * i + j * j + k * k));
        sum_w += wd_.w(len);
        if (len == 0.0 || len >= h) continue;
        offs.push_back({{dx * i, dx * j, dx * k}, wd_.dw(len) / len, wg_.dw(len) / len});
      }
  const int grid = dim_ == 2 ? 48 : 16;
  const double kpi = 3.14159265358979323846 / dx;
  double best = 0.0;
  for (int a = 0; a <= grid; ++a)
    for (int b = 0; b <= a; ++b)
      for (int c = 0; c <= (dim_ == 3 ? b : 0); ++c) {
        const double kv[3] = {kpi * a / grid, kpi * b / grid, kpi * c / grid};
        double td[3] = {0, 0, 0}, tg[3] = {0, 0, 0};
        for (const Offset& o : offs) {
          const double s = std::sin(kv[0] * o.x[0] + kv[1] * o.x[1] + kv[2] * o.x[2]);
          for (int d = 0; d < 3; ++d) {
            td[d] += o.gd * o.x[d] * s;
            tg[d] += o.gg * o.x[d] * s;
          }
        }
        best = std::max(best, td[0] * tg[0] + td[1] * tg[1] + td[2] * tg[2]);
      }
  const double form = opt_.form == SphPressureForm::variational ? 1.0 : 0.5;
  return c_ * std::sqrt(form * best) / sum_w;
}

void SphFluid::compute_densities(CVecRef x) const {
  detail::with_dim<2, 3>(dim_, [&](auto dc) {
    sph::with_kernel(opt_.density_kernel, [&](auto kd) {
      density_pass<decltype(dc)::value, decltype(kd)::value>(x.data());
    });
  });
}

Vec SphFluid::densities(CVecRef x) const {
  compute_densities(x);
  return Eigen::Map<const Vec>(rho_.data(), n_);
}

Vec SphFluid::masses() const {
  Vec m(dofs());
  for (Index i = 0; i < n_; ++i)
    m.segment(dim_ * i, dim_).setConstant(m_[static_cast<std::size_t>(i)]);
  return m;
}

double SphFluid::total_mass() const {
  double total = 0.0;
  for (double m : m_) total += m;
  return total;
}

double SphFluid::kinetic_energy(CVecRef y) const {
  double ke = 0.0;
  for (Index i = 0; i < n_; ++i)
    ke += 0.5 * m_[static_cast<std::size_t>(i)] * y.segment(dofs() + dim_ * i, dim_).squaredNorm();
  return ke;
}

Vec SphFluid::linear_momentum(CVecRef y) const {
  Vec p = Vec::Zero(dim_);
  for (Index i = 0; i < n_; ++i)
    for (int d = 0; d < dim_; ++d)
      p[d] += m_[static_cast<std::size_t>(i)] * y[dofs() + dim_ * i + d];
  return p;
}

Vec SphFluid::angular_momentum(CVecRef y) const {
  Vec l = Vec::Zero(dim_ == 2 ? 1 : 3);
  for (Index i = 0; i < n_; ++i) {
    const double m = m_[static_cast<std::size_t>(i)];
    const double* x = y.data() + dim_ * i;
    const double* v = y.data() + dofs() + dim_ * i;
    if (dim_ == 2) {
      l[0] += m * (x[0] * v[1] - x[1] * v[0]);
    } else {
      l[0] += m * (x[1] * v[2] - x[2] * v[1]);
      l[1] += m * (x[2] * v[0] - x[0] * v[2]);
      l[2] += m * (x[0] * v[1] - x[1] * v[0]);
    }
  }
  return l;
}

double SphFluid::energy(CVecRef y) const {
  compute_densities(y.head(dofs()));
  double e = kinetic_energy(y);
  const double d0 = wall_range(), k_wall = wall_strength();
  for (Index i = 0; i < n_; ++i) {
    double per_mass = internal_energy(rho_[static_cast<std::size_t>(i)]);
    for (int d = 0; d < dim_; ++d)
      per_mass -= opt_.gravity[static_cast<std::size_t>(d)] * y[dim_ * i + d];
    if (opt_.boundary == SphBoundary::penalty) {
      for (const auto& wall : scene_.walls) {
        double sd = -wall.offset;
        for (int d = 0; d < dim_; ++d)
          sd += wall.normal[static_cast<std::size_t>(d)] * y[dim_ * i + d];
        if (sd < d0) per_mass += k_wall * d0 / 3.0 * std::pow(1.0 - sd / d0, 3);
      }
    }
    e += m_[static_cast<std::size_t>(i)] * per_mass;
  }
  return e;
}

double SphFluid::max_density_error(CVecRef y) const {
  compute_densities(y.head(dofs()));
  double e = 0.0;
  for (double r : rho_) e = std::max(e, std::abs(r / opt_.rho0 - 1.0));
  return e;
}

double SphFluid::max_compression(CVecRef y) const {
  compute_densities(y.head(dofs()));
  double e = -std::numeric_limits<double>::infinity();
  for (double r : rho_) e = std::max(e, r / opt_.rho0 - 1.0);
  return e;
}

double SphFluid::front(CVecRef y) const {
  double f = -std::numeric_limits<double>::infinity();
  for (Index i = 0; i < n_; ++i) f = std::max(f, y[dim_ * i]);
  return f + 0.5 * opt_.spacing;
}

double SphFluid::height_left(CVecRef y) const {
  double top = 0.0;
  for (Index i = 0; i < n_; ++i)
    if (y[dim_ * i] < opt_.support) top = std::max(top, y[dim_ * i + 1] + 0.5 * opt_.spacing);
  return top;
}

double SphFluid::probe_pressure(CVecRef y, const std::array<double, 3>& point) const {
  compute_densities(y.head(dofs()));
  double num = 0.0, den = 0.0;
  for (Index i = 0; i < n_; ++i) {
    double r2 = 0.0;
    for (int d = 0; d < dim_; ++d) {
      const double dx = y[dim_ * i + d] - point[static_cast<std::size_t>(d)];
      r2 += dx * dx;
    }
    const double w = wd_.w(std::sqrt(r2));
    if (w <= 0) continue;
    const double vol = m_[static_cast<std::size_t>(i)] / rho_[static_cast<std::size_t>(i)];
    num += vol * p_[static_cast<std::size_t>(i)] * w;
    den += vol * w;
  }
  return den > 0 ? num / den : 0.0;
}

std::vector<Invariant> SphFluid::invariants() const {
  std::vector<Invariant> out;
  out.push_back({"energy", [this](double, CVecRef y) { return energy(y); }});
  const bool free = bvol_.empty() && opt_.boundary != SphBoundary::penalty;
  if (free) {
    static const char* names[] = {"momentum_x", "momentum_y", "momentum_z"};
    for (int d = 0; d < dim_; ++d)
      if (opt_.gravity[static_cast<std::size_t>(d)] == 0.0)
        out.push_back({names[d], [this, d](double, CVecRef y) { return linear_momentum(y)[d]; }});
  }
  // Angular momentum: central pair forces only (pressure, Monaghan's viscosity), no walls; in 2D
  // no gravity, in 3D component c when g ∥ e_c (gravity's torque M x_cm × g has no component
  // along g). Müller's pair force (v_j - v_i) is not central: not listed.
  const bool central = !(opt_.viscosity == SphViscosity::muller && opt_.mu > 0);
  if (free && central) {
    const auto& g = opt_.gravity;
    if (dim_ == 2 && g[0] == 0.0 && g[1] == 0.0) {
      out.push_back(
          {"angular_momentum", [this](double, CVecRef y) { return angular_momentum(y)[0]; }});
    } else if (dim_ == 3) {
      static const char* axis[] = {"angular_momentum_x", "angular_momentum_y",
                                   "angular_momentum_z"};
      for (int c = 0; c < 3; ++c) {
        bool parallel = true;
        for (int o = 0; o < 3; ++o)
          if (o != c && g[static_cast<std::size_t>(o)] != 0.0) parallel = false;
        if (parallel)
          out.push_back({axis[c], [this, c](double, CVecRef y) { return angular_momentum(y)[c]; }});
      }
    }
  }
  return out;
}

std::vector<Invariant> SphFluid::observables() const {
  std::vector<Invariant> out;
  out.push_back({"mass", [this](double, CVecRef) { return total_mass(); }});
  out.push_back({"kinetic_energy", [this](double, CVecRef y) { return kinetic_energy(y); }});
  out.push_back({"max_density_error", [this](double, CVecRef y) { return max_density_error(y); }});
  out.push_back({"max_compression", [this](double, CVecRef y) { return max_compression(y); }});
  out.push_back({"max_speed", [this](double, CVecRef y) {
                   double v2 = 0.0;
                   for (Index i = 0; i < n_; ++i)
                     v2 = std::max(v2, y.segment(dofs() + dim_ * i, dim_).squaredNorm());
                   return std::sqrt(v2);
                 }});
  if (scene_.dam_break) {
    out.push_back({"front", [this](double, CVecRef y) { return front(y); }});
    out.push_back({"height_left", [this](double, CVecRef y) { return height_left(y); }});
    // Koshizuka & Oka's dimensionless front Z = front/a and time T = t √(2|g|/a).
    const double a = scene_.column_width;
    const double g =
        std::sqrt(opt_.gravity[0] * opt_.gravity[0] + opt_.gravity[1] * opt_.gravity[1] +
                  opt_.gravity[2] * opt_.gravity[2]);
    out.push_back({"Z", [this, a](double, CVecRef y) { return front(y) / a; }});
    out.push_back({"T", [a, g](double t, CVecRef) { return t * std::sqrt(2.0 * g / a); }});
  }
  for (std::size_t k = 0; k < scene_.probes.size(); ++k) {
    out.push_back({"p_probe" + std::to_string(k + 1),
                   [this, k](double, CVecRef y) { return probe_pressure(y, scene_.probes[k]); }});
  }
  return out;
}

std::optional<double> SphFluid::stiffness(double, CVecRef) const {
  double rate = c_ / opt_.support + 8.0 * nu_ / (hs_ * hs_);
  if (opt_.boundary == SphBoundary::penalty) rate = std::max(rate, penalty_frequency());
  if (!(rate > 0)) return std::nullopt;
  return rate;
}

std::optional<SuggestedStep> SphFluid::suggested_step() const {
  const double acoustic =
      c_ > 0 ? 0.4 * opt_.support / c_ : std::numeric_limits<double>::infinity();
  const double viscous =
      nu_ > 0 ? 0.125 * hs_ * hs_ / nu_ : std::numeric_limits<double>::infinity();
  // Penalty walls: a particle against a wall oscillates at ω = √(2K/d0) = √2 c/Δx; at
  // support/Δx above 3.5 that exceeds what 0.4 h/c resolves (symplectic Euler needs ω h < 2), so
  // the step is also capped at 1/ω.
  const double wall = opt_.boundary == SphBoundary::penalty && penalty_frequency() > 0
                          ? 1.0 / penalty_frequency()
                          : std::numeric_limits<double>::infinity();
  if (!std::isfinite(acoustic) && !std::isfinite(viscous)) return std::nullopt;
  SuggestedStep s;
  if (wall < std::min(acoustic, viscous)) {
    s.h = wall;
    s.rule = "penalty-wall limit 1/omega, omega = sqrt(2) c/dx = " + short_num(penalty_frequency());
  } else if (acoustic <= viscous) {
    s.h = acoustic;
    s.rule = "CFL 0.4 h/c with support radius h = " + short_num(opt_.support) +
             ", sound speed c = " + short_num(c_);
  } else {
    s.h = viscous;
    s.rule =
        "viscous limit 0.125 h_s^2/nu with h_s = " + short_num(hs_) + ", nu = " + short_num(nu_);
  }
  return s;
}

ParticleFrame SphFluid::particles(double, CVecRef y) const {
  compute_densities(y.head(dofs()));
  const Index nb = boundary_particles();
  const Index total = n_ + nb;
  ParticleFrame f;
  f.positions.assign(static_cast<std::size_t>(3 * total), 0.0);
  ParticleFrame::Field rho{"density", 1, std::vector<double>(static_cast<std::size_t>(total))};
  ParticleFrame::Field p{"pressure", 1, std::vector<double>(static_cast<std::size_t>(total), 0.0)};
  ParticleFrame::Field vel{"velocity", 3,
                           std::vector<double>(static_cast<std::size_t>(3 * total), 0.0)};
  ParticleFrame::Field fluid{"fluid", 1, std::vector<double>(static_cast<std::size_t>(total), 0.0)};
  for (Index i = 0; i < n_; ++i) {
    const std::size_t iu = static_cast<std::size_t>(i);
    for (int d = 0; d < dim_; ++d) {
      f.positions[3 * iu + static_cast<std::size_t>(d)] = y[dim_ * i + d];
      vel.values[3 * iu + static_cast<std::size_t>(d)] = y[dofs() + dim_ * i + d];
    }
    rho.values[iu] = rho_[iu];
    p.values[iu] = p_[iu];
    fluid.values[iu] = 1.0;
  }
  // Boundary particles: at rest, density ρ0 and pressure 0 (Akinci's particles carry a volume,
  // not a state).
  for (Index b = 0; b < nb; ++b) {
    const std::size_t iu = static_cast<std::size_t>(n_ + b);
    for (int d = 0; d < dim_; ++d)
      f.positions[3 * iu + static_cast<std::size_t>(d)] =
          bx_[static_cast<std::size_t>(dim_ * b + d)];
    rho.values[iu] = opt_.rho0;
  }
  f.fields = {std::move(rho), std::move(p), std::move(vel), std::move(fluid)};
  return f;
}

}  // namespace stiffbench
