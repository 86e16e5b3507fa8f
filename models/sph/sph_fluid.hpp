// SphFluid: a weakly compressible SPH fluid (2D or 3D) as a MechanicalSystem y = [x; v] over the
// fluid particles, so every integrator of the testbed runs on it unchanged. Formulas from
// docs/reference-values.md (SPH); h is the kernel SUPPORT radius throughout, Δx the initial
// particle spacing.
//
// Density by summation, self term included, fluid and boundary particles (Akinci et al. 2012):
//   ρ_i = Σ_j m W_d(x_i - x_j) + Σ_b ρ0 V_b W_d(x_i - x_b),   V_b = 1 / Σ_{k ∈ boundary} W_d(x_b -
//   x_k)
// Particle masses (parameter `masses`): `lattice` gives every particle m = ρ0 / Σ_{k ∈ Z^D}
// W_d(|k| Δx), so the density of a particle inside a full lattice of spacing Δx is exactly ρ0 at
// the start, while particles near a free surface are deficient and those next to boundary
// particles slightly over-dense (Akinci's volumes over-weight the outer layer: +5% for the
// first row of a 3-layer wall with the default kernel); `equilibrium` solves the kernel system
// Σ_j m_j W_d(x_i - x_j) = ρ_i⁰ - ρ0 Σ_b V_b W_d(x_i - x_b) for all i (CG; the Wendland and poly6
// kernel matrices are positive definite), so every particle starts at exactly its target
// density ρ_i⁰: ρ0 (p = 0), or for fluid at rest under gravity (scenes with a rest height H) the
// hydrostatic density, the EOS inverse of p = ρ0 |g| (H - y_i), so that a tank starts settled
// and a dam-break column starts with the hydrostatic pressure it has behind the gate. A
// free drop with an unclamped EOS then starts without surface tension instead of collapsing,
// and fluid next to walls starts without the over-density kick (the default of every scene;
// free-surface particles are then up to ~2× heavier than the lattice mass, interior ones equal
// to it). Masses are fixed after that; all sums use m_j.
// Equation of state: linear p = k(ρ - ρ0) (sound speed c = √k) or Tait p = B((ρ/ρ0)^γ - 1),
// B = ρ0 c0²/γ; either clamped p = max(0, ·) (no tension) or unclamped.
// Accelerations of fluid particle i (∇W = ∇W_g, the gradient kernel; r_ij = x_i - x_j):
//   pressure, symmetric (Müller 2003):  -Σ_j m (p_i + p_j)/(2 ρ_i ρ_j) ∇W_ij
//   pressure, variational:              -Σ_j m (p_i/ρ_i² + p_j/ρ_j²) ∇W_ij
//   boundary pressure (Akinci 2012):    -f Σ_b ρ0 V_b p_i/ρ_i² ∇W_ib with f = 1 (default,
//     `boundary_pressure=akinci`: Akinci's force, the gradient of the boundary's share of
//     Σ m u(ρ_i), so energy-consistent) or f = 2 (`mirrored`: the pair term of a boundary
//     particle of mass ρ0 V_b carrying the fluid particle's own p/ρ²). Neither holds fluid at rest
//     exactly: a wall of Akinci particles pushes with half the pair repulsion of the fluid above
//     (f = 1) or, with the outer layer's over-weighted volumes, too much (f = 2): measured on
//     sph_tank_2d started hydrostatic, the bottom row accelerates at -7.8 g (f = 1) or +3.1 g
//     (f = 2). With f = 1 the fluid settles to a state with a denser first row; the interior is
//     hydrostatic (tested).
//   viscosity, Müller:                  (μ/ρ_i) Σ_j m (v_j - v_i)/ρ_j ∇²W_visc(r_ij)
//                                       (boundary particles: v_b = 0, m_b = ρ0 V_b, ρ_b = ρ0)
//     The lecture summary's "element-wise absolute value" |v_j - v_i| is a notation slip: with it
//     the pair force is not antisymmetric (momentum is not conserved) and does not oppose the
//     relative velocity (kinetic energy can grow). The difference v_j - v_i is Müller's form.
//   viscosity, artificial (Monaghan 1992): -Σ_j m Π_ij ∇W_ij with, for v_ij·r_ij < 0,
//     Π_ij = -α c h_s (v_ij·r_ij) / (ρ̄_ij (|r_ij|² + 0.01 h_s²)), h_s = h/2 (the smoothing
//     length of a kernel with support 2h_s), ρ̄_ij = (ρ_i + ρ_j)/2; boundary particles as above.
//   gravity g; wall penalty (boundary=penalty, instead of boundary particles): for each wall
//     plane n·x = d with the fluid on the side n·x > d and distance s = n·x - d < d0 = Δx/2,
//     +K (1 - s/d0)² n with K = c²/(4 d0) (potential K d0/3 (1 - s/d0)³, C¹ at s = d0). Fluid
//     starting on the lattice (s = Δx/2) feels nothing; the wall's stiffness ω² = 2K/d0 gives
//     ω·(0.4 h/c) = 0.566 h/Δx (1.41 at the default support 2.5 Δx), so the suggested step is
//     also capped at 1/ω and stiffness() includes ω; K d0/3 = c²/12 per unit mass stops any
//     particle slower than c/√6. (A range of h was tried first: fluid
//     within h of a wall was kicked at 0.6 c²/h and the dam break's front ran 2.6× too fast.)
// The symmetric and variational pair terms and both viscosities are antisymmetric per pair, so
// without gravity and boundaries total linear momentum is conserved; both viscosities dissipate
// kinetic energy (each pair's term is -w|v_ij|² or -w (v_ij·r_ij)²/… with w >= 0).
// Angular momentum L = Σ m x × v (2D: the scalar Σ m (x v_y - y v_x); angular_momentum()):
// dL/dt = Σ_i m_i x_i × a_i, and a pair term m_i m_j c_ij r_ij with c_ij = c_ji (both pressure
// forms, and Monaghan's Π_ij, which acts along ∇W_ij ∥ r_ij) adds m_i m_j c_ij (x_i - x_j) × r_ij
// = 0: central pair forces conserve L. Müller's pair term ∝ (v_j - v_i) is not central: for a
// rigid rotation v = ω e_z × x it gives the pair torque -ω c_ij |r_ij|² e_z with c_ij > 0, so it
// brakes a rigid rotation (which has no viscous stress in a real fluid) and L is not conserved
// (tested). Walls and gravity exert torques. invariants() therefore lists angular_momentum
// (2D) or angular_momentum_x/y/z (3D, component c when g ∥ e_c or g = 0) exactly when there
// are no boundary particles or penalty walls and no Müller viscosity (μ > 0), and in 2D no
// gravity; of the scenes only sph_drop_2d (free, no gravity; `velocity=rotation` spins it).
// Symplectic Euler and velocity Verlet conserve L exactly up to rounding for central forces:
// each is a composition of kicks v += h a(x) (torque Σ m x × a = 0) and drifts x += h v
// (adds h Σ m v × v = 0).
//
// Additive split (SphOptions::split, the scenes' `split` parameter; core/ode_system.hpp):
//   none       no split (the default; the right-hand side is untouched, bit for bit);
//   viscosity  a_I = the viscosity selected (Müller's or Monaghan's, with their boundary-particle
//              terms); a_E = pressure, boundary-particle pressure or penalty walls, gravity.
//              f_E = [0; a_E], f_I = [v; a_I]. Without a viscosity a_I = 0.
// Both parts are the same force pass as a (a template parameter selects the terms; Part::all is
// the unsplit code path), after the same density pass: allocation-free after the first call and
// bitwise identical for any thread count; a_E + a_I = a up to rounding (the artificial
// viscosity's term is added to the pressure coefficient of its pair in a, kept apart in the
// parts). a_I depends on x (densities, kernel) and, for Müller, linearly on v; Monaghan's is
// positively homogeneous in v but acts on approaching pairs only. No analytic Jacobian of either
// part (has_implicit_part_jacobian() is false): the IMEX stages' Newton takes finite-difference
// products of f_I — matrix-free GMRES with `jacobian=auto` above 200 unknowns, a dense
// difference Jacobian below; ARKODE (arkode_imex) SPGMR above 100 unknowns.
// explicit_part_spectrum(): the pressure waves oscillate (imaginary axis) at up to the lattice's
// acoustic rate acoustic_rate() (the penalty walls' ω when larger). Linearising a_E about the
// uniform lattice at rest (p0 = 0, lattice masses m = ρ0/S, S = Σ_j W_d(X_j)): a displacement
// u_i = U e^{ik·X_i} changes the densities by δρ_i = i m T_d(k)·U e^{ik·X_i} and gives
// a_i = -f (c²/ρ0²) m² T_g(k) (T_d(k)·U) e^{ik·X_i}, T(k) = Σ_j ∇W(X_j) sin(k·X_j) over the
// lattice offsets, f = 1 (variational) or 1/2 (symmetric: its (p_i + p_j)/2 has half the
// variational form's linear response); so ω(k)² = f c² T_g·T_d / S², maximised over a grid of k
// in [0, π/Δx]^D at construction. For Wendland C2 with support 2.5 Δx: ω_max = 0.8686 c/Δx in
// 2D, 0.9008 c/Δx in 3D (2.17 and 2.25 c/h; stiffness()'s c/h is the rougher scale). It omits
// walls, free surfaces and the heavier equilibrium masses near them (the measured explicit
// limits on sph_drop_2d are ~0.7 of what it predicts for rk4 and symplectic Euler).
// Energy E = Σ ½ m|v|² + Σ m u(ρ_i) - Σ m g·x (+ the penalty potential), u(ρ) the EOS internal
// energy: linear u = k[ln(ρ/ρ0) + ρ0/ρ - 1], Tait u = B/(γ-1)[ρ^(γ-1)/ρ0^γ + (γ-1)/ρ - γ/ρ0];
// clamped EOS: u = 0 for ρ < ρ0 (then du/dρ = max(0, p)/ρ² still holds). du/dρ = p/ρ², so with
// the variational form, the same kernel for density and gradient, no viscosity, the Akinci
// boundary force with f = 1 (the gradient of the boundary's share of Σ m u(ρ_i)) or no walls,
// and the penalty force, E is conserved in continuous time: energy drift then measures the
// integrator. The mirrored wall (f = 2) does work that is not the gradient of E.
//
// Neighbour search: a Verlet list with a skin s = SphOptions::skin · h (default 0.2 h; Verlet
// 1967). At a build, a uniform grid of cells (h + s)(1 + 1e-6) (neighbour_grid.hpp) sorts the
// fluid particles by cell (the slot order of every per-particle array the passes use), and each
// particle's candidates are listed: the fluid particles and the (static) boundary particles
// within h + s of it, the boundary ones from the boundary grid built once with cells h + s. The
// list is reused until some particle has moved more than s/2 from where it was at the build
// (checked at every evaluation; any pair closer than h now was closer than h + s then), so
// stage positions inside the skin need no search; neighbour_list_builds() and the counter
// EvalCounters::neighbour_builds count the builds. Each particle's fluid candidates are sorted
// by particle index and its boundary candidates by boundary slot (the boundary grid never
// changes): a particle's sums run over its neighbours within h in an order fixed by the
// positions alone, whenever the list was built, so the right-hand side is a function of the
// state, bit for bit. Both passes (density, then forces) gather per particle over the list
// with OpenMP when there are at least `parallel_threshold` particles, the threads taking blocks
// of 256 slots as they become free. Each particle's sums run in four lanes (neighbour q of its
// kept neighbours into lane q mod 4, then (L0 + L1) + (L2 + L3); sph/pair_lanes.inc), compiled
// for SSE2 and, chosen at run time, AVX2 and AVX-512, which give the same bits. So results are
// bitwise identical for any thread count, schedule and processor. The state vector's order never
// changes.
// Nothing edits positions or velocities outside the right-hand side: boundaries are forces, and
// there is no velocity clamping.
//
// velocity_dependent() is true exactly when a viscosity is on (μ > 0 or α > 0).
// stiffness(): c/h (acoustic) + 8ν/h_s² (viscous, ν = μ/ρ0 or Monaghan's effective
// α c h_s/8), a rough spectral-radius scale (at least the penalty walls' ω). suggested_step():
// min(0.4 h/c, 0.125 h_s²/ν, and 1/ω with penalty walls).
// No analytic Jacobian: implicit methods and CVODE/ARKODE use finite-difference
// Jacobian-vector products (matrix-free Krylov), which their `auto` settings choose for it.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/ode_system.hpp"
#include "models/sph/block_queue.hpp"
#include "models/sph/kernels.hpp"
#include "models/sph/neighbour_grid.hpp"

namespace stiffbench {

enum class SphEos { linear, tait };
enum class SphPressureForm { symmetric, variational };
enum class SphViscosity { none, muller, artificial };
enum class SphBoundary { particles, penalty };
enum class SphSplit { none, viscosity };

struct SphOptions {
  double spacing = 0.01;   // Δx
  double support = 0.025;  // h, the kernel support radius
  double rho0 = 1000.0;
  sph::KernelType density_kernel = sph::KernelType::wendland_c2;
  sph::KernelType gradient_kernel = sph::KernelType::wendland_c2;
  SphEos eos = SphEos::linear;
  bool clamp = true;
  double c0 = 10.0;  // sound speed (Tait's c0; linear: k = c0² unless k >= 0 is given)
  double k = -1.0;   // linear EOS constant (< 0: c0²)
  double tait_gamma = 7.0;
  SphPressureForm form = SphPressureForm::variational;
  SphViscosity viscosity = SphViscosity::artificial;
  double mu = 0.0;     // Müller dynamic viscosity
  double alpha = 0.0;  // Monaghan's α
  std::array<double, 3> gravity{};
  SphBoundary boundary = SphBoundary::particles;
  // false: every particle has the lattice mass ρ0/Σ_lattice W; true: masses solve
  // Σ_j m_j W_ij + ρ0 Σ_b V_b W_ib = ρ_i⁰ at the initial positions, ρ_i⁰ = ρ0 or the
  // hydrostatic density of scenes at rest (see the header comment).
  bool equilibrium_masses = false;
  bool mirror_boundary_pressure = false;  // f = 2 in the boundary pressure force (see above)
  Index parallel_threshold = 512;         // particles; below this the passes run serially
  double skin = 0.2;                      // Verlet list skin, a fraction of the support h
  SphSplit split = SphSplit::none;        // additive split (see the header comment)
};

// A wall plane n·x = offset; the fluid is on the side n·x > offset.
struct SphWall {
  std::array<double, 3> normal{};
  double offset = 0.0;
};

// Geometry of a scene: particles, walls, and what its observables measure.
struct SphScene {
  int dim = 2;
  std::vector<std::array<double, 3>> fluid_x, fluid_v;
  std::vector<std::array<double, 3>> boundary_x;  // used when boundary = particles
  std::vector<SphWall> walls;                     // used when boundary = penalty
  // Observables: surge front (largest x of fluid, from the left wall at x = 0) and water height
  // at the left wall; pressure at probe points.
  bool dam_break = false;
  double column_width = 0.0;  // dam break: a, for the dimensionless Z = front/a, T = t √(2g/a)
  // Free-surface height H of fluid at rest (tank, dam-break column): with equilibrium masses the
  // particles start at the hydrostatic density, p = ρ0 |g| (H - y). 0: start at ρ0.
  double rest_height = 0.0;
  std::vector<std::array<double, 3>> probes;
  std::string description;
};

class SphFluid final : public MechanicalSystem {
 public:
  SphFluid(std::string name, SphScene scene, SphOptions options);

  std::string name() const override { return name_; }
  Index dofs() const override { return dim_ * n_; }
  Vec initial_state() const override { return y0_; }
  bool autonomous() const override { return true; }
  bool velocity_dependent() const override { return viscous_; }
  Vec masses() const override;

  std::vector<Invariant> invariants() const override;
  std::vector<Invariant> observables() const override;
  std::optional<double> stiffness(double t, CVecRef y) const override;
  std::optional<SuggestedStep> suggested_step() const override;
  bool has_particles() const override { return true; }
  ParticleFrame particles(double t, CVecRef y) const override;

  // Additive split (see the header comment). No analytic Jacobian of either part.
  bool has_imex_split() const override { return opt_.split != SphSplit::none; }
  std::optional<SplitInfo> imex_split() const override;
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override;

  // Data.
  int dim() const { return dim_; }
  Index fluid_particles() const { return n_; }
  Index boundary_particles() const { return static_cast<Index>(bvol_.size()); }
  double lattice_mass() const { return mass_; }  // ρ0 / Σ_lattice W
  const std::vector<double>& particle_masses() const { return m_; }
  double total_mass() const;
  double sound_speed() const { return c_; }
  const SphOptions& options() const { return opt_; }
  const SphScene& scene() const { return scene_; }
  const std::vector<double>& boundary_volumes() const { return bvol_; }

  // Observables at y = [x; v].
  Vec densities(CVecRef x) const;  // ρ_i of every fluid particle
  double pressure(double rho) const;
  double internal_energy(double rho) const;  // u(ρ) per unit mass
  double energy(CVecRef y) const;
  double kinetic_energy(CVecRef y) const;
  Vec linear_momentum(CVecRef y) const;
  Vec angular_momentum(CVecRef y) const;  // 2D: 1 component Σ m (x v_y - y v_x); 3D: Σ m x × v
  // The Verlet list (see the header comment): its skin s (absolute) and how many times it was
  // built since construction (also counted in counters().neighbour_builds).
  double neighbour_skin() const { return skin_; }
  long neighbour_list_builds() const { return list_builds_; }
  // Whether the pair loops run their AVX2 build (x86-64 processors with AVX2, in a build without
  // -mavx2, which compiles them for AVX2 throughout), or their AVX-512 build (processors with
  // AVX-512F, VL and DQ, in a build without -mavx2; it counts as an AVX2 build too).
  // allow_avx512(false) makes every SphFluid of the process use the AVX2 build instead, and
  // allow_avx2(false) the portable build; all give the same bits (tests compare them).
  bool uses_avx2() const;
  bool uses_avx512() const;
  static void allow_avx2(bool yes);
  static void allow_avx512(bool yes);
  // ω_max of the pressure waves on the uniform lattice at rest (see the header comment).
  double acoustic_rate() const { return acoustic_rate_; }
  double max_density_error(CVecRef y) const;  // max_i |ρ_i/ρ0 - 1| (free surfaces included)
  double max_compression(CVecRef y) const;    // max_i (ρ_i/ρ0 - 1), the WCSPH accuracy measure
  // Penalty wall range d0 = Δx/2 and strength K = c²/(4 d0) (see the header comment).
  double wall_range() const { return 0.5 * opt_.spacing; }
  double wall_strength() const { return 0.25 * c_ * c_ / wall_range(); }
  // ω = √(2K/d0) of a particle against a penalty wall.
  double penalty_frequency() const { return std::sqrt(2.0 * wall_strength() / wall_range()); }
  double front(CVecRef y) const;        // max_i x_i + Δx/2 (dam break)
  double height_left(CVecRef y) const;  // max y (+Δx/2) of fluid within h of the left wall
  // Shepard-normalised SPH interpolation of the pressure at a point (0 when no fluid is near).
  double probe_pressure(CVecRef y, const std::array<double, 3>& point) const;

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override;
  void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override;
  void eval_acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override;

 private:
  // Which terms a force pass sums: all of them, or one part of the split.
  enum class Part { all, explicit_part, implicit_part };
  template <int D, sph::KernelType KD>
  void density_pass(const double* x) const;
  template <int D, sph::KernelType KG, Part P>
  void force_pass(const double* v, double* a) const;
  template <Part P>
  void acceleration_impl(const double* x, const double* v, double* a) const;
  double lattice_acoustic_rate() const;
  template <int D>
  void update_list(const double* x) const;  // rebuilds the Verlet list when it is stale
  template <int D>
  void build_list(const double* x) const;
  // The pair passes' blocks of slots (sph_fluid.cpp, kSlotBlock): their number, and block b's
  // slots [first, last).
  Index slot_blocks() const;
  std::pair<std::size_t, std::size_t> slot_block(Index block) const;
  template <int D>
  const sph::NeighbourGrid<D>& fluid_grid() const;
  template <int D>
  const sph::NeighbourGrid<D>& boundary_grid() const;
  void compute_densities(CVecRef x) const;  // fills rho_ and p_
  void solve_equilibrium_masses();

  std::string name_;
  SphScene scene_;
  SphOptions opt_;
  int dim_ = 2;
  Index n_ = 0;
  double mass_ = 0.0, c_ = 0.0, k_ = 0.0, tait_b_ = 0.0, hs_ = 0.0, nu_ = 0.0;
  double acoustic_rate_ = 0.0;
  bool viscous_ = false, parallel_ = false;
  sph::Kernel wd_, wg_, wv_;  // density, gradient and viscosity-Laplacian kernels
  Vec y0_;
  std::vector<double> m_;          // particle masses
  std::vector<double> bx_, bvol_;  // boundary positions (dim each) and Akinci volumes

  // Scratch of one evaluation (the right-hand side allocates nothing after the first call).
  mutable std::vector<double> rho_, p_;  // ρ and p by particle index (observables)
  // ρ, p, p/ρ² and 1/ρ in cell order (slot k = particle order()[k]).
  mutable std::vector<double> srho_, sp_, spr2_, sinv_rho_;
  // Per slot one cache line: position (dim), mass, velocity (dim), density (pair_lanes.inc's
  // kRec* offsets); the density pass writes position and mass, the force pass velocity and ρ.
  struct alignas(64) SlotRecord {
    double f[8];
  };
  mutable std::vector<SlotRecord> rec_;
  mutable std::vector<double> spair_;  // the force pass's pair sums by slot (D each)
  // Neighbours within h of each slot from the density pass, in its candidates' order: fluid
  // slots (self included) in [k·cand_capacity_, k·cand_capacity_ + nb_count_k) of nb_index_,
  // then boundary slots in the next nb_bcount_k entries (the force pass recomputes r from the
  // positions: the same bits, and less memory traffic than storing it).
  mutable std::vector<std::size_t> nb_count_, nb_bcount_;  // fluid, then boundary neighbours
  // The Verlet list: positions at its build (by particle index), slot order (slot k holds
  // particle list_order_[k]), current positions in slot order, and per slot its candidates in
  // [k·cand_capacity_, ... + cand_count_k) (fluid slots, by particle index) followed by
  // cand_bcount_k boundary slots (ascending).
  double skin_ = 0.0;
  mutable long list_builds_ = 0;
  mutable std::vector<double> list_x_;
  mutable std::vector<Index> list_order_;
  mutable std::vector<std::uint32_t> slot_of_;  // particle index -> slot
  mutable std::size_t cand_capacity_ = 64;
  mutable std::vector<std::uint32_t> cand_;
  mutable std::vector<std::uint32_t> cand_count_, cand_bcount_;
  std::vector<double> sbvol_;  // boundary volumes in boundary-grid slot order
  mutable std::vector<std::uint32_t> nb_index_;
  mutable std::vector<double> scratch_;  // the density pass's rows of r², one per thread
  mutable sph::BlockQueue blocks_;       // the pair passes' blocks of slots (block_queue.hpp)
  mutable sph::NeighbourGrid<2> grid2_, bgrid2_;
  mutable sph::NeighbourGrid<3> grid3_, bgrid3_;
};

}  // namespace stiffbench
