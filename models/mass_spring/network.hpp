// MassSpringNetwork: mass points joined by springs (with optional dashpots) in 1D, 2D or 3D, as
// a MechanicalSystem with y = [x; v], x = (x_0, x_1, ...) the point coordinates interleaved per
// point (dofs = dim × points). The builders (models/mass_spring/builders.hpp) make chains,
// cloth, soft cubes and pendulum chains from it.
//
// Forces on point i (Baraff & Witkin 1998; docs/reference-values.md),
// d = (x_j - x_i)/l, l = |x_j - x_i|:
//   spring (i, j):    f_i = k (l - L) d
//   dashpot (i, j):   f_i = c ((v_j - v_i)·d) d
//   point damping:    f_i = -γ v_i
//   gravity:          f_i = m_i g              (g a vector)
//   air drag (3D, on the network's triangles, NetworkOptions::air_drag = β_d > 0): triangle
//     (a, b, c) with N = (x_b - x_a) × (x_c - x_a) (|N| = 2 × area A, unit normal n = N/|N|) and
//     mean velocity v̄ = (v_a + v_b + v_c)/3 feels the quadratic drag of still air
//       F = -β_d A (v̄·n)|v̄·n| n = -(β_d/2) u|u| N/|N|²,  u = v̄·N
//     (β_d = ½ ρ C_d: air density ρ, drag coefficient C_d; the aerodynamic model of cloth
//     simulation, e.g. Keckeisen et al. 2004, without lift), shared equally: f_p += F/3 for
//     p = a, b, c. A triangle of zero area feels none. It dissipates: its power is
//     F·v̄ = -β_d A |v̄·n|³ <= 0.
// and a_i = f_i / m_i. The spring and dashpot forces on j are exactly -f_i (internal forces).
// A spring needs l > 0: at l = 0 the direction d is undefined and the force is NaN, which the
// driver reports as a blow-up.
//
// Pinned points: a_i = 0 and their rows of K and D are zero (kept in the sparsity pattern as
// explicit zeros), so their velocity rows of I - hJ are identity rows and x_i' = v_i = 0. The
// constructor sets a pinned point's velocity to zero, so every integrator that forms its stages
// from x + h·Σ(…)·v and v + h·Σ(…)·a keeps pinned points exactly where they are (0·h = 0 in
// floating point; tested for euler, heun, rk4, symplectic Euler, velocity Verlet). Columns of K for
// pinned points are kept: free points do feel where their pinned neighbours are.
//
// Jacobian blocks (Baraff & Witkin 1998). For a spring seen from i, with
//   J_s = k [ d dᵀ + (1 - L/l)(I - d dᵀ) ]                                   (symmetric),
//   J_c = (c/l) [ d (u - s d)ᵀ + s (I - d dᵀ) ],  u = v_j - v_i, s = u·d     (dashpot, ∂/∂x),
//   D_c = c d dᵀ                                                              (dashpot, ∂/∂v),
// the force derivatives are ∂f_i/∂x_j = J_s + J_c = -∂f_i/∂x_i and ∂f_i/∂v_j = D_c =
// -∂f_i/∂v_i; J_c follows from ∂d/∂x_j = (I - d dᵀ)/l (derived in force_jacobians.cpp).
// K = M⁻¹ ∂f/∂x and D = M⁻¹ ∂f/∂v - (γ/m) I. K is returned with one fixed pattern, computed
// once: a dim×dim block for every point's diagonal and for every ordered pair of points joined by
// a spring (explicit zeros where a value happens to vanish); D has the same pattern when the
// network has dashpots or air drag and the diagonal pattern otherwise. A matrix passed in that
// already has the pattern keeps its storage (values written in place, each point's rows by the
// thread that owns the point), so implicit solvers evaluate K and D every step without
// allocating; force_jacobians() fills both in one pass over the springs.
// Air drag's blocks, with β = β_d/2, w = 1/|N|², for each pair (p, q) of a triangle's points:
//   ∂F/∂v_q = -(2β|u|w/3) N Nᵀ,
//   ∂F/∂x_q = G S_q,  G = ∂F/∂N = -β [2|u| w N v̄ᵀ + u|u| w I - 2 u|u| w² N Nᵀ],
//   S_a = [e_2 - e_1]×, S_b = -[e_2]×, S_c = [e_1]× (e_1 = x_b - x_a, e_2 = x_c - x_a; [s]× y =
//   s × y, from dN = (e_2 - e_1) × dx_a - e_2 × dx_b + e_1 × dx_c),
// added to K and D as (1/(3 m_p)) times these, in one serial pass over the triangles after the
// springs (a fixed order: the same bits for any thread count). In the right-hand side the
// triangles' forces go into a scratch array first (in parallel on the OpenMP path), then each
// free point adds F/(3 m_p) of its triangles in ascending triangle order (in parallel over
// points): the same additions in the same order as one serial pass over the triangles. Every edge
// of a triangle must be a spring (the constructor checks it), so the blocks are in the pattern.
// Drag makes K and D non-symmetric.
// Option `compressed_dd_only` (off by default): for compressed springs (l < L) keep only
// k d dᵀ in J_s, dropping k (1 - L/l)(I - d dᵀ), whose negative eigenvalue makes the stiffness
// indefinite. The Jacobian is then inexact (an approximation for implicit solvers); the forces
// are unchanged.
//
// Invariants returned by invariants(): the quantities this configuration conserves.
//   energy   E = Σ ½ m|v|² + Σ ½ k (l - L)² - Σ m g·x, always returned; conserved without damping
//            and drag, dE/dt = -Σ γ|v_i|² - Σ c s² - Σ β_d A |v̄·n|³ <= 0 with them;
//   momentum_x/y/z   P_c = Σ m v_c when there are no pins, no point damping, no drag and g_c = 0;
//   angular_momentum (2D: Σ m (x v_y - y v_x)) when no pins, no point damping and g = 0;
//   angular_momentum_x/y/z (3D: Σ m x × v) when no pins, no point damping, no drag and g ∥ e_c
//            or g = 0 (gravity's torque M x_cm × g has no component along g).
// linear_momentum() and angular_momentum() compute them for any configuration.
//
// Stiffness: ω_max, the largest |eigenvalue|^½ of M⁻¹ ∂f_s/∂x over free dofs (springs only;
// pinned dofs excluded), computed by StiffnessSpectrum (models/mass_spring/stiffness_spectrum.hpp:
// the Gershgorin bound omega_max_bound and the Lanczos estimate omega_max_estimate, which
// stiffness() returns). Networks with constraints return no estimate: the ODE the integrators
// see there is free flight plus projection.
//
// Right-hand side: no heap allocation per call, every spring evaluated once (f_i += c r,
// f_j -= c r, exactly opposite). The springs are stored in structure-of-arrays order (end points
// as 32-bit indices, an index into the table of distinct (k, L) pairs, dashpot coefficients only
// when there are dashpots) and evaluated in blocks of 128: first c r for the whole block in a loop
// without dependences between springs, which the compiler vectorises (`omp simd`, checked with
// -fopt-info-vec: 4 springs per AVX2 vector, 2 per SSE2 vector; an AVX2 build of the kernel is
// chosen at run time when the processor has it, and in 3D an AVX-512 build of the runs (below),
// written with intrinsics; the default build stays portable: kernel_isa()), then the
// additions in spring order, f_i of consecutive springs with the same first end kept in
// registers. Springs of one (j - i, (k, L) pair, split part) whose first ends are consecutive
// points (a lattice's springs of one direction along a row) are packed as runs (kMinRun) and
// evaluated from contiguous coordinates, then f_i += c r and f_j -= c r as two contiguous loops
// over the block; each group evaluates its runs, then its other springs. Neither the vector
// width nor the threads change the order of any point's additions, and without contracted
// multiply-adds (-ffp-contract=off) both builds give the same bits. Networks with at least
// `parallel_threshold` points split their points into kRhsPartitions contiguous index ranges.
// A parallel region clears the points of partitions q and q + 1 and adds the springs between them
// for even q (one thread per pair: their points are disjoint), then for odd q, then any other cross
// springs in a fixed order; then each partition adds its interior springs and turns its points'
// sums into a = g + (f - γv)/m while they are in cache. The partition count depends on the network,
// not on the threads, so every point's sum runs in the same order for any thread count: results are
// bitwise identical for 1 and 2 threads and on the serial path (tested against a
// one-spring-at-a-time evaluation in tests/models/test_spring_kernel.cpp). K and D are filled
// per point (force_jacobians.cpp).
//
// Constraints: distance constraints C = |x_i - x_j| - L (e.g. the constrained pendulum chain),
// held by DistanceConstraints (models/mass_spring/distance_constraints.hpp) and enforced by
// project() after each step (the driver calls it; see core/ode_system.hpp): positions by an
// M-SHAKE Newton iteration, then velocities by the mass-weighted projection onto G v = 0, with a
// Gauss–Seidel fallback for redundant constraints.
// The constraint forces are not in a(x): integrators advance free flight under the other forces
// and the projection puts the state back on the manifold. This keeps the acceleration
// velocity-independent (Verlet methods apply) and the constraint residual at round-off, but a
// projection that sees only the end-of-step state cannot recover RATTLE's velocity update (the
// tangential part of the previous step's constraint impulse is lost, O(h²) per step), so the
// projected schemes are first-order accurate and slowly dissipate energy (measured in
// tests/models/test_mass_spring.cpp).
// constraint_residual() is max |C| (absolute).
// The same constraints are offered as equations (core/constraints.hpp) to methods that enforce
// them themselves (rattle): holonomic_constraints() is the DistanceConstraints object when the
// network has constraints, with g = C over the active constraints only (those not joining two
// pinned points, in list order). The driver does not call project() after such a method's steps.
//
// Additive split (NetworkOptions::split, the models' `split` parameter; core/ode_system.hpp):
//   none     no split (the default; the right-hand side is untouched, bitwise);
//   springs  a_I = springs and dashpots, a_E = gravity, point damping and air drag. K_I = the
//            springs' K and D_I = the dashpots' ∂/∂v (D without -(γ/m) I and without drag), on
//            K's pattern (D_I: the diagonal pattern when no spring has a dashpot);
//   stretch  a_I = the structural springs and their dashpots (SpringKind::structural), a_E =
//            every other spring (shear, bend) with its dashpot, gravity, point damping and air
//            drag. K_I and D_I have only the structural pairs' blocks (a pattern of their own).
// a_E + a_I = a up to rounding (each part sums its own springs; pinned points: 0 in both).
// The parts' Jacobians are written in place like force_jacobians() (fill_blocks on the implicit
// springs' structure). explicit_part_spectrum(): springs: radius max_p (γ + Σ_t 2β|u_t|/3)/m_p
// on the negative real axis (J_E's eigenvalues are 0 and those of D_E, point damping and drag,
// which are real and <= 0; the radius bounds D_E's norm row by row; 0 without either); stretch:
// the Gershgorin bound of ω_max of the explicit springs alone (StiffnessSpectrum on their
// adjacency) on the imaginary axis, point damping and drag ignored.
// (J_E = [[0, 0], [K_E, D_E]] itself is nilpotent in x: the rate that limits an explicit a_E is
// the explicit springs' oscillation ±iω under x' = v, the eigenvalues of [[0, I], [K_E, 0]].)
//
// Spring view (core/springs.hpp): spring_network() lists the springs (i, j, L, k, c), masses,
// pins, gravity and point damping for the graphics solvers (XPBD, projective dynamics), which
// work on the springs directly; with air drag its other_forces says "air drag" and they refuse
// the model. Built on first use (it copies the spring list). Constraints are
// not in it: the driver still projects after every step.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/constraints.hpp"
#include "core/ode_system.hpp"
#include "core/springs.hpp"
#include "models/mass_spring/distance_constraints.hpp"
#include "models/mass_spring/elements.hpp"
#include "models/mass_spring/stiffness_spectrum.hpp"

namespace stiffbench {

enum class NetworkSplit { none, springs, stretch };

struct NetworkOptions {
  std::array<double, 3> gravity{};          // g (components beyond dim must be 0)
  double point_damping = 0.0;               // γ (>= 0), force -γ v on every free point
  bool compressed_dd_only = false;          // see the header comment
  Index parallel_threshold = 2048;          // points; below this the right-hand side runs serially
  NetworkSplit split = NetworkSplit::none;  // additive split (see the header comment)
  double air_drag = 0.0;  // β_d = ½ρC_d (>= 0) of the air drag on the triangles (3D only)
};

// Builds of the right-hand side's spring kernel (see the header comment), narrowest first: the
// portable one (the build's own target), the AVX2 one, and, in 3D, AVX-512 runs. All give the same
// bits.
enum class SpringKernelIsa { portable = 0, avx2 = 1, avx512 = 2 };
const char* to_string(SpringKernelIsa isa);

namespace detail {
// A run of the right-hand side's springs (MassSpringNetwork, kMinRun): n springs of one (k, L)
// pair and part with ends (i + D s, j + D s), s = 0 .. n-1, in slots first .. first + n - 1.
struct SpringRun {
  Index first;            // its first spring's slot in the packed springs
  Index n;                // springs
  std::int32_t i, j;      // first spring's ends' first coordinates (dim × point index)
  std::int32_t kind;      // index into the distinct (k, L) pairs
  std::uint8_t implicit;  // in a_I (split only)
};
}  // namespace detail

class MassSpringNetwork final : public MechanicalSystem {
 public:
  // Checks the data (BadInput naming the model and the offending item) and precomputes the
  // packed springs of the right-hand side (the adjacency lists and the Jacobian pattern are built
  // on first use).
  MassSpringNetwork(std::string name, int dim, std::vector<MassPoint> points,
                    std::vector<Spring> springs, NetworkOptions options,
                    std::vector<DistanceConstraint> constraints = {},
                    std::vector<Triangle> triangles = {});

  std::string name() const override { return name_; }
  Index dofs() const override { return dim_ * num_points(); }
  Vec initial_state() const override { return y0_; }
  bool autonomous() const override { return true; }
  bool velocity_dependent() const override { return velocity_dependent_; }
  Vec masses() const override { return dof_mass_; }

  bool has_force_jacobians() const override { return true; }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override;
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override;
  // K and D in one pass over the springs, in place (see fill_blocks in force_jacobians.cpp).
  void force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k, SparseMat& d) const override;
  // The pinned points' dofs.
  std::vector<Index> fixed_dofs() const override;
  // ∂f/∂x of springs is a Hessian and point damping is -γI; dashpots and drag make ∂f/∂x
  // non-symmetric.
  bool symmetric_force_jacobians() const override { return !has_dashpots_ && !drag(); }

  std::vector<Invariant> invariants() const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;

  const SpringNetworkView* spring_network() const override;

  // Additive split (see the header comment).
  bool has_imex_split() const override { return opt_.split != NetworkSplit::none; }
  std::optional<SplitInfo> imex_split() const override;
  void implicit_force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k,
                                SparseMat& d) const override;
  bool implicit_part_velocity_dependent() const override { return implicit_dashpots_; }
  bool symmetric_implicit_force_jacobians() const override { return !implicit_dashpots_; }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override;

  bool has_constraints() const override { return !distance_constraints_.empty(); }
  void project(double t, VecRef y) const override;
  double constraint_residual(CVecRef y) const override;

  // The constraints as equations (see the header comment); nullptr without constraints.
  const HolonomicConstraints* holonomic_constraints() const override {
    return distance_constraints_.empty() ? nullptr : &distance_constraints_;
  }
  const DistanceConstraints& distance_constraints() const { return distance_constraints_; }

  // An exact solution supplied by a builder (the linear chain's normal modes).
  void set_exact(std::function<void(double, VecRef)> exact) { exact_ = std::move(exact); }
  bool has_exact() const override { return static_cast<bool>(exact_); }
  void exact(double t, VecRef y) const override;

  // Network data.
  int dim() const { return dim_; }
  Index num_points() const { return static_cast<Index>(points_.size()); }
  const std::vector<MassPoint>& points() const { return points_; }
  const std::vector<Spring>& springs() const { return springs_; }
  const std::vector<Triangle>& triangles() const { return triangles_; }
  // True when air drag acts (air_drag > 0 and the network has triangles).
  bool drag() const { return opt_.air_drag > 0.0 && !triangles_.empty(); }
  const std::vector<DistanceConstraint>& constraints() const {
    return distance_constraints_.list();
  }
  const NetworkOptions& options() const { return opt_; }

  // Observables at state y = [x; v].
  double energy(CVecRef y) const;
  Vec linear_momentum(CVecRef y) const;   // dim components
  Vec angular_momentum(CVecRef y) const;  // 3 components in 3D, 1 in 2D, none in 1D

  // ω_max at positions x (StiffnessSpectrum, models/mass_spring/stiffness_spectrum.hpp).
  double omega_max_bound(CVecRef x) const;
  double omega_max_estimate(CVecRef x) const;
  // Smallest and largest eigenvalue of S = M^{-1/2}(-∂f_s/∂x)M^{-1/2} on free dofs (Lanczos).
  std::pair<double, double> stiffness_eigen_range(CVecRef x) const;

  // True when the right-hand side takes the OpenMP path.
  bool parallel() const { return num_points() >= opt_.parallel_threshold; }
  // The build of the spring kernel the right-hand sides of this process run: the widest the
  // processor has, at most the limit set by limit_kernel_isa (default: no limit). Tests and
  // benchmarks lower the limit to compare the builds; the bits do not change.
  static SpringKernelIsa kernel_isa();
  static void limit_kernel_isa(SpringKernelIsa widest);

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override;
  void eval_acceleration_in_ranges(double t, CVecRef x, CVecRef v, VecRef a,
                                   DofRangeFn done) const override;

 public:
  // The partitions of the right-hand side as a chain (MechanicalSystem::acceleration_chain):
  // offered when there are at least two, no spring joins partitions that are not neighbours, no
  // point has springs to both neighbouring partitions (so no entry gets terms from two links)
  // and there is no air drag; nullptr otherwise.
  const AccelerationChain* acceleration_chain() const override {
    return chain_ok_ && !drag() ? &chain_ : nullptr;
  }

 protected:
  void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override;
  void eval_acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override;

 private:
  // Which forces an acceleration evaluation sums: all of them, or one part of the split.
  enum class Part { all, explicit_part, implicit_part };
  // The springs' adjacency and the fixed pattern of K and D built from it, with for each point's
  // diagonal block and each adjacency entry the position in valuePtr() of every block entry
  // (row-major within the block). One for the whole network, one for the implicit springs of
  // split=stretch.
  struct Structure {
    const SpringAdjacency* adjacency = nullptr;  // adjacency_ or implicit_adjacency_
    SparseMat pattern;
    SparseMat diag_pattern;        // D's pattern without dashpots (D = -(γ/m) I)
    std::vector<Index> diag_pos;   // dim² per point
    std::vector<Index> adj_pos;    // dim² per adjacency entry
    std::vector<Index> adj_pos_t;  // the same for the transposed block (rows of the neighbour)
    bool dashpots = false;         // some spring of this structure has a dashpot
    // With drag (the whole network's structure only): per triangle, the position of entry (0, 0)
    // of its 9 blocks (p, q), p and q over (a, b, c) row-major; entry (r, s) of block (p, q) is
    // at that position + r + s × (length of column 3q).
    std::vector<Index> face_pos;
  };
  // One piece of a chained evaluation (Chain): clear(q), link(q) or finish(q).
  struct ChainCall {
    enum class What { clear, link, finish } what;
    Index q;
  };
  // With call: only that piece of the evaluation.
  template <int D, Part P>
  void acceleration_impl(const double* x, const double* v, double* a, const DofRangeFn* done,
                         const ChainCall* call = nullptr) const;
  // The right-hand side's partitions as an AccelerationChain: block q is partition q, link(q)
  // the group of springs between partitions q and q + 1, clear(q) the clearing of the points
  // outside late_clear_, finish(q) the partition's late clear, interior springs and finish (the
  // same pieces as the whole evaluation, so the same sums).
  class Chain final : public AccelerationChain {
   public:
    explicit Chain(const MassSpringNetwork& net) : net_(net) {}
    Index blocks() const override { return net_.rhs_parts_; }
    Index begin(Index q) const override {
      return net_.dim_ * (net_.num_points() * q / net_.rhs_parts_);
    }
    void clear(Index q, VecRef a) const override;
    void link(Index q, double t, CVecRef x, CVecRef v, VecRef a) const override;
    void finish(Index q, double t, CVecRef x, CVecRef v, VecRef a) const override;

   private:
    void call(ChainCall::What what, Index q, const double* x, const double* v, double* a) const;
    const MassSpringNetwork& net_;
  };
  template <int D>
  void blocks_impl(const Structure& st, double gamma, const double* x, const double* v,
                   double* k_values, double* d_values) const;
  // with_drag: add air drag's blocks (the whole network's K and D; not the implicit part's).
  void fill_blocks(const Structure& st, double gamma, bool with_drag, CVecRef x, CVecRef v,
                   SparseMat* k, SparseMat* d) const;
  // Air drag: its accelerations added to a, and its blocks added to K and D (either may be null).
  void add_drag(const double* x, const double* v, double* a) const;
  void add_drag_blocks(const Structure& st, const double* x, const double* v, double* k_values,
                       double* d_values) const;
  void pack_rhs_springs();        // rhs_springs_, runs_ and the groups (constructor)
  void ensure_adjacency() const;  // builds the adjacency lists once
  void ensure_structure() const;  // builds the members marked "on first use" once
  Structure build_structure(const std::vector<Spring>& springs, const SpringAdjacency& adjacency,
                            bool with_faces) const;
  void check_triangles() const;  // constructor: the triangles and the drag coefficient
  const Structure& implicit_structure() const {
    return opt_.split == NetworkSplit::stretch ? implicit_structure_ : structure_;
  }
  // The springs of the split's implicit part (implicit = true) or explicit part, in order.
  std::vector<Spring> springs_of_part(bool implicit) const;
  // Whether spring s is in the implicit part of the active split.
  bool implicit_spring(const Spring& s) const {
    return opt_.split == NetworkSplit::springs ||
           (opt_.split == NetworkSplit::stretch && s.kind == SpringKind::structural);
  }

  std::string name_;
  int dim_;
  std::vector<MassPoint> points_;
  std::vector<Spring> springs_;
  std::vector<Triangle> triangles_;
  // With drag: each point's triangles in ascending order (CSR), and the triangles' forces of
  // the current evaluation (scratch, sized once; like the SPH model's, one evaluation at a time).
  std::vector<Index> point_face_start_, point_faces_;
  mutable std::vector<double> face_force_;
  NetworkOptions opt_;
  bool velocity_dependent_ = false;
  bool has_dashpots_ = false;
  Vec y0_, dof_mass_;
  std::vector<double> inv_mass_;  // per point, 0 for pinned points
  DistanceConstraints distance_constraints_;

  // Right-hand side springs (see the header comment), in structure-of-arrays order, by group:
  // group q < parts holds partition q's interior springs; the springs between partitions follow
  // in groups parts + g: first the groups of springs joining partitions (q, q+1) for even q
  // (disjoint points: run in parallel), then those for odd q, then one group of all other cross
  // springs (serial). Group G's springs are [group_start_[G], group_start_[G+1]): first its runs
  // (runs_[group_runs_[G] .. group_runs_[G+1]), then its loose springs from group_loose_[G].
  static constexpr Index kRhsPartitions = 32;
  // A run: at least kMinRun springs of one (k, L) pair and part whose ends are consecutive
  // points, (i0 + s, j0 + s) for s = 0 .. n-1 (a lattice's springs of one direction along a row),
  // evaluated with contiguous loads and stores instead of gathers and scatters.
  static constexpr Index kMinRun = 8;
  struct RhsSprings {
    std::vector<std::int32_t> i, j;  // end points' first coordinates (dim × point index)
    std::vector<std::int32_t> kind;  // index into k and rest: the distinct (k, L) pairs
    std::vector<double> k, rest;
    std::vector<double> damping;  // per spring; empty without dashpots
    std::size_t size() const { return i.size(); }
  };
  RhsSprings rhs_springs_;
  std::vector<detail::SpringRun> runs_;
  Index rhs_parts_ = 1;
  std::vector<Index> group_start_, group_loose_, group_runs_;
  Index even_groups_ = 0, odd_groups_ = 0;
  // Per partition q, points [late_clear_[2q], late_clear_[2q + 1]): the longest range of its
  // points that no spring between partitions touches. The right-hand side clears them just
  // before the partition's own springs (in cache) instead of with the rest of the partition
  // before the springs between partitions: the same sums.
  std::vector<Index> late_clear_;
  bool chain_ok_ = false;  // acceleration_chain()'s conditions on the packing (pack_rhs_springs)
  Chain chain_{*this};
  std::vector<double> point_mass_;             // per point
  std::vector<std::uint8_t> pinned_;           // per point
  std::vector<std::uint8_t> packed_implicit_;  // per packed spring: in a_I (split only)
  bool implicit_dashpots_ = false;             // some implicit spring has a dashpot

  // Built on first use (an explicit run never needs them). ensure_adjacency: the adjacency lists
  // of the whole network (stiffness spectrum), of the implicit springs and of the explicit
  // springs (stretch: explicit_part_spectrum). ensure_structure: the whole network's structure
  // and the implicit springs' (stretch), for the Jacobian blocks. The stiffness estimates need
  // the adjacency only, which is a fraction of the structure's memory on a large network.
  mutable std::once_flag adjacency_once_;
  mutable SpringAdjacency adjacency_;
  mutable SpringAdjacency implicit_adjacency_;
  mutable SpringAdjacency explicit_adjacency_;
  mutable std::once_flag structure_once_;
  mutable Structure structure_;
  mutable Structure implicit_structure_;

  std::function<void(double, VecRef)> exact_;

  mutable std::once_flag view_once_;  // spring_network(), built on first use
  mutable SpringNetworkView view_;
};

}  // namespace stiffbench
