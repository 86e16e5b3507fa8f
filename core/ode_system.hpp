// OdeSystem and MechanicalSystem: the only face of a model that integrators see.
//
// Evaluation counting happens here, at the system boundary: the public, non-virtual rhs(),
// acceleration() and jacobian() count each call and then dispatch to the model's protected
// eval_*() overrides. Every integrator, hand-written or library, and every finite-difference
// Jacobian goes through these, so the counts in SolveStats are true for all of them.
#pragma once

#include <functional>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/fused_evaluation.hpp"
#include "core/run_control.hpp"
#include "core/types.hpp"

namespace stiffbench {

struct EvalCounters {
  long f_evals = 0;    // rhs() and acceleration() calls, and calls of either part of a split
  long jac_evals = 0;  // analytic jacobian() and implicit_part_jacobian() calls
  long fe_evals = 0;   // calls of the explicit part f_E of an additive split (also in f_evals)
  long fi_evals = 0;   // calls of the implicit part f_I (also in f_evals)
  // Neighbour-list builds of particle models that reuse a list across evaluations (SphFluid's
  // Verlet list; 0 for every other model).
  long neighbour_builds = 0;
};

// An additive split f = f_E + f_I of a model (OdeSystem::imex_split()): its name (the model's
// `split` parameter value) and what each part holds, in words, for `describe` and the results'
// metadata.
struct SplitInfo {
  std::string name;
  std::string explicit_part;  // e.g. "gravity and point damping"
  std::string implicit_part;  // e.g. "springs and dashpots (with x' = v)"
};

// Where the eigenvalues of a part of f lie, as a model estimates them: radius ρ (the largest
// modulus) and the ray the extreme eigenvalues lie on (imaginary: ±iρ, e.g. central-difference
// advection or undamped oscillation; negative_real: -ρ, e.g. diffusion or decay).
struct SpectrumEstimate {
  enum class Ray { imaginary, negative_real };
  double radius = 0.0;
  Ray ray = Ray::negative_real;
};

// A conserved (or monitored) quantity of a model, e.g. energy or angular momentum.
struct Invariant {
  Invariant() = default;
  Invariant(std::string name_, std::function<double(double t, CVecRef y)> value_,
            std::string arbitrary_zero_ = {})
      : name(std::move(name_)),
        value(std::move(value_)),
        arbitrary_zero(std::move(arbitrary_zero_)) {}

  std::string name;
  std::function<double(double t, CVecRef y)> value;
  // Why the quantity's zero is arbitrary, or empty when it is not. An energy whose gravitational
  // potential -m g·x is zero at x = 0 rather than at a rest state is an example: its change
  // relative to |I0| then depends on where the model put the origin, so the studies report the
  // absolute change |I(t) - I0| instead (energy, solve, budget), and `stability` does not judge
  // growth by it (its `auto` criterion falls back to the norm).
  std::string arbitrary_zero;
};

class MechanicalSystem;
class HolonomicConstraints;  // core/constraints.hpp
struct SpringNetworkView;    // core/springs.hpp
class GridFluid;

// A model's suggested fixed step (its CFL or diffusion limit) and the rule that gave it, e.g.
// "CFL 0.4 h/c, h = 0.0114 (support radius), c = 23.9 m/s". Fixed-step commands and studies run
// at it when they are given no --h, and say so.
struct SuggestedStep {
  double h = 0.0;
  std::string rule;
};

// One snapshot of a particle model for frame output (VTK): positions and per-point fields.
// Points are the model's particles (fluid first, then fixed boundary particles, for SPH).
struct ParticleFrame {
  struct Field {
    std::string name;
    int components = 1;          // 1 (scalar) or 3 (vector)
    std::vector<double> values;  // components per point, interleaved
  };
  std::vector<double> positions;  // 3 per point (unused components 0)
  std::vector<Field> fields;
  Index points() const { return static_cast<Index>(positions.size() / 3); }
};

// One snapshot of a grid model for frame output (VTK image data): cell-centred fields on an
// nx × ny grid of square cells of side `spacing` whose lower-left corner is `origin`. Values are
// stored cell by cell, x fastest (the VTK order); vector fields have 3 components.
struct GridFrame {
  int nx = 0, ny = 0;
  double origin_x = 0, origin_y = 0, spacing = 1;
  std::vector<ParticleFrame::Field> cell_fields;
  Index cells() const { return static_cast<Index>(nx) * ny; }
};

// A table a model derives from its state for output beside the frames, e.g. a velocity profile
// along a line; `solve --frames` writes it as DIR/<name>.csv at every frame (so the file holds the
// last frame's values).
struct Profile {
  std::string name;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

// 0, 1, ..., n-1: every component (the nonnegative_components() of a model whose unknowns are
// all concentrations).
inline std::vector<Index> all_components(Index n) {
  std::vector<Index> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), Index{0});
  return all;
}

// What a problem's literature says beyond its equations: the end time, a published solution, a
// suggested step. A capability of OdeSystem apart from the mathematics; every hook has a default
// (none), so a system overrides only what it has.
class ProblemMetadata {
 public:
  virtual ~ProblemMetadata() = default;
  // The literature's end time of the problem, used when a command is given no --t-end.
  virtual std::optional<double> end_time() const { return std::nullopt; }
  // A published solution at one time (IVP test set, Hairer–Wanner) for problems without an exact
  // one; `solve` compares its final state with it when the run ends at that time.
  struct PublishedSolution {
    double t = 0.0;
    Vec y;
    std::string source;
  };
  virtual std::optional<PublishedSolution> published_solution() const { return std::nullopt; }
  // Suggested fixed step (see SuggestedStep). Empty when the model has none.
  virtual std::optional<SuggestedStep> suggested_step() const { return std::nullopt; }
  // The components the exact solution keeps non-negative (concentrations), by index: the
  // admissible set {y : y_i >= 0 for each listed i}. A state outside it at an output time ends
  // the run with status invalid_state (core/driver.hpp says by how much it may be outside).
  // Declare only what the problem guarantees for every admissible parameter value and initial
  // state, e.g. by the positivity criterion (Hundsdorfer & Verwer, Numerical Solution of
  // Time-Dependent Advection-Diffusion-Reaction Equations, 2003, §I.7): y(0) >= 0 and
  // f_i(t, y) >= 0 whenever y >= 0 and y_i = 0 keep y(t) >= 0 (a mass-action kinetics' species
  // is consumed only by reactions whose rate contains it). Empty (the default): no such set.
  virtual std::vector<Index> nonnegative_components() const { return {}; }
  // The name of component i where the literature has one (a species, "v_3" of an interleaved
  // grid), for messages such as invalid_state's; empty (the default) otherwise.
  virtual std::string component_name(Index /*i*/) const { return {}; }
};

// What `solve --frames` writes besides the state: particle and grid views, profiles and
// monitored observables. A capability of OdeSystem apart from the mathematics (defaults: none).
class FrameOutput {
 public:
  virtual ~FrameOutput() = default;
  // Monitored quantities that are not conserved (a dam break's surge front, the largest density
  // error), recorded beside the invariants by `solve --frames` in observables.csv.
  virtual std::vector<Invariant> observables() const { return {}; }

  // Particle view for frame output (`solve --frames N --out DIR` writes VTK files from it).
  virtual bool has_particles() const { return false; }
  virtual ParticleFrame particles(double /*t*/, CVecRef /*y*/) const { return {}; }

  // Grid view for frame output (`solve --frames N --out DIR` writes VTK image data from it).
  virtual bool has_grid() const { return false; }
  virtual GridFrame grid_frame(double /*t*/, CVecRef /*y*/) const { return {}; }
  // Profiles written beside the frames (see Profile).
  virtual std::vector<Profile> profiles(double /*t*/, CVecRef /*y*/) const { return {}; }
};

// The mathematics of y' = f(t, y) — dimension, initial value, f and its Jacobian, the optional
// IMEX split, exact solution, invariants, stiffness, constraints — and, as capability
// interfaces inherited beside it, the problem's metadata (ProblemMetadata) and its frame output
// (FrameOutput). A system overrides the hooks it has under the same names as before the split.
class OdeSystem : public ProblemMetadata, public FrameOutput {
 public:
  ~OdeSystem() override = default;

  virtual std::string name() const = 0;
  virtual Index dimension() const = 0;
  virtual double initial_time() const { return 0.0; }
  virtual Vec initial_state() const = 0;

  // y' = f(t, y). Counted as one f evaluation.
  void rhs(double t, CVecRef y, VecRef dydt) const {
    count_f_eval();
    eval_rhs(t, y, dydt);
  }

  // Optional analytic Jacobian J = ∂f/∂y as a sparse matrix whose pattern does not change
  // between calls (implicit solvers analyse it once). Counted as one Jacobian evaluation.
  virtual bool has_jacobian() const { return false; }
  void jacobian(double t, CVecRef y, SparseMat& jac) const {
    ++counters_.jac_evals;
    eval_jacobian(t, y, jac);
  }

  // Sparsity pattern of ∂f/∂y (values irrelevant), for column-grouped finite differences.
  // By default the structure of the analytic Jacobian at the initial state, when there is one.
  virtual bool has_jacobian_pattern() const { return has_jacobian(); }
  virtual SparseMat jacobian_pattern() const;

  // Optional additive split f = f_E + f_I for IMEX, operator-splitting and multirate methods
  // (f_E non-stiff, treated explicitly; f_I stiff, treated implicitly, with its own Jacobian).
  // A model with several splits chooses one by its `split` parameter; imex_split() names the
  // active one. f_E + f_I = f up to rounding (tests/models check it for every split model).
  // Each part's call counts as one f evaluation, and in fe_evals or fi_evals. Without a split,
  // methods that need one refuse the model (BadInput naming it).
  virtual bool has_imex_split() const { return false; }
  virtual std::optional<SplitInfo> imex_split() const { return std::nullopt; }
  void rhs_explicit_part(double t, CVecRef y, VecRef fe) const {
    count_split_eval(true);
    eval_rhs_explicit_part(t, y, fe);
  }
  void rhs_implicit_part(double t, CVecRef y, VecRef fi) const {
    count_split_eval(false);
    eval_rhs_implicit_part(t, y, fi);
  }
  // Analytic Jacobian J_I = ∂f_I/∂y, sparse with a fixed pattern (the implicit stages' Newton
  // matrices are built from it). Counted as one Jacobian evaluation.
  virtual bool has_implicit_part_jacobian() const { return false; }
  void implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const {
    ++counters_.jac_evals;
    eval_implicit_part_jacobian(t, y, jac);
  }
  // The model's estimate of the spectrum of ∂f_E/∂y (what limits the step of the explicit part:
  // `stability` predicts an IMEX method's limit from it when the exact spectrum of J - J_I is not
  // computed). Empty when the model cannot say.
  virtual std::optional<SpectrumEstimate> explicit_part_spectrum(double /*t*/,
                                                                 CVecRef /*y*/) const {
    return std::nullopt;
  }

  // True when f does not depend on t explicitly (Rosenbrock methods then skip ∂f/∂t).
  virtual bool autonomous() const { return false; }

  // Optional exact solution y(t) of the initial value problem.
  virtual bool has_exact() const { return false; }
  virtual void exact(double t, VecRef y) const;

  // Conserved or monitored quantities (energy first where there is one).
  virtual std::vector<Invariant> invariants() const { return {}; }

  // Estimate of the spectral radius of ∂f/∂y at (t, y): the stiffness that linear stability
  // theory compares with h. Empty when the model cannot say.
  virtual std::optional<double> stiffness(double /*t*/, CVecRef /*y*/) const {
    return std::nullopt;
  }

  // Optional holonomic constraints C(y) = 0 enforced strictly, not by forces. The fixed-step
  // driver calls project() after every accepted step of every integrator except those that
  // enforce the constraints themselves (Requirements::constraints: rattle); the model projects
  // y back onto the constraint manifold (positions, then velocities onto its tangent space)
  // with the method its header documents. constraint_residual() is max |C| (an observable).
  virtual bool has_constraints() const { return false; }
  virtual void project(double /*t*/, VecRef /*y*/) const {}
  virtual double constraint_residual(CVecRef /*y*/) const { return 0.0; }

  // Non-null for systems with y = [x; v].
  virtual const MechanicalSystem* as_mechanical() const { return nullptr; }

  // Non-null for mass-spring networks that list their springs (core/springs.hpp).
  virtual const SpringNetworkView* spring_network() const { return nullptr; }
  // Non-null for Eulerian grid fluids that expose their operators to splitting schemes
  // (core/grid_fluid.hpp; stable_fluids requires it).
  virtual const GridFluid* as_grid_fluid() const { return nullptr; }

  const EvalCounters& counters() const { return counters_; }
  void reset_counters() const { counters_ = {}; }

 protected:
  virtual void eval_rhs(double t, CVecRef y, VecRef dydt) const = 0;
  virtual void eval_jacobian(double t, CVecRef y, SparseMat& jac) const;
  // The split's parts (only called when has_imex_split()) and the Jacobian of f_I (only when
  // has_implicit_part_jacobian(); the default throws BadInput).
  virtual void eval_rhs_explicit_part(double, CVecRef, VecRef) const {}
  virtual void eval_rhs_implicit_part(double, CVecRef, VecRef) const {}
  virtual void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const;
  // Every f evaluation passes here, so this is also where a run over its wall-clock limit or an
  // interrupted one is stopped (core/run_control.hpp).
  void count_f_eval() const {
    ++counters_.f_evals;
    poll_run_control();
  }
  void count_neighbour_build() const { ++counters_.neighbour_builds; }
  void count_split_eval(bool explicit_part) const {
    count_f_eval();
    ++(explicit_part ? counters_.fe_evals : counters_.fi_evals);
  }

 private:
  mutable EvalCounters counters_;
};

// y = [x; v] with x' = v, v' = a(t, x, v); x and v each have dofs() entries.
// Symplectic and Baraff–Witkin style schemes use this split; general schemes see only the
// OdeSystem face.
class MechanicalSystem : public OdeSystem {
 public:
  virtual Index dofs() const = 0;
  Index dimension() const final { return 2 * dofs(); }
  const MechanicalSystem* as_mechanical() const final { return this; }

  // a(t, x, v). Counted as one f evaluation (it costs what rhs() costs).
  void acceleration(double t, CVecRef x, CVecRef v, VecRef a) const {
    count_f_eval();
    eval_acceleration(t, x, v, a);
  }

  // The same a(t, x, v), and done(b, e) for ranges [b, e) of dofs that together cover
  // [0, dofs()) once each. done(b, e) is called once a_b .. a_{e-1} hold their final values and
  // the evaluation will not read entries [b, e) of x and v again, so it may overwrite them (and
  // read and write entries [b, e) of any other vector): the explicit Runge-Kutta methods form
  // their next stage there while the entries are still in cache. done may run on several threads
  // at once for disjoint ranges and must not start OpenMP parallel regions itself. The values of
  // a do not depend on what done does or on the ranges. Counted as one f evaluation.
  void acceleration_in_ranges(double t, CVecRef x, CVecRef v, VecRef a, DofRangeFn done) const {
    count_f_eval();
    eval_acceleration_in_ranges(t, x, v, a, done);
  }

  // Optional: a as a chain of blocks (AccelerationChain, core/fused_evaluation.hpp); nullptr (the
  // default) when the system offers none. It must describe the same a as eval_acceleration().
  virtual const AccelerationChain* acceleration_chain() const { return nullptr; }
  // Counts one evaluation made through acceleration_chain() as one f evaluation (and polls the
  // run's limits, core/run_control.hpp, so it may throw: call it before the evaluation).
  void count_chained_evaluation() const { count_f_eval(); }

  // Whether a depends on v (damping). Leapfrog and the Verlet family require it not to, and the
  // explicit Runge-Kutta methods form no stage velocities when it is false (they pass the step's
  // v instead; integrators/explicit/explicit_rk.hpp), so it must not be false when a reads v.
  virtual bool velocity_dependent() const = 0;

  // Diagonal of the mass matrix, one entry per dof.
  virtual Vec masses() const { return Vec::Ones(dofs()); }

  // Optional blocks K = ∂a/∂x and D = ∂a/∂v, sparse with fixed patterns. When present, the
  // first-order Jacobian [[0, I], [K, D]] is assembled from them.
  virtual bool has_force_jacobians() const { return false; }
  virtual void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const;
  virtual void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const;

  // K and D together, written in place: when k and d already hold the model's pattern (from a
  // previous call) only their values change, so implicit solvers call this every step without
  // allocating or rebuilding a matrix. A model computes both in one pass where it can; the
  // default calls stiffness_block and damping_block. Not counted by the system (callers add one
  // Jacobian evaluation to their SolveStats).
  virtual void force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k, SparseMat& d) const;

  // Dofs that never move (pinned points): a_i ≡ 0, v_i = 0 at the start, rows i of K and D zero.
  // Implicit solvers eliminate them from the reduced Newton system, which keeps it symmetric.
  virtual std::vector<Index> fixed_dofs() const { return {}; }

  // True when M K and M D are symmetric (forces from a potential, symmetric dampers), so the
  // reduced Newton matrix M - c_D M D - c_K M K of the implicit methods is symmetric (and
  // positive definite where -M K and -M D are semi-definite): CG and LDLT apply.
  virtual bool symmetric_force_jacobians() const { return false; }

  bool has_jacobian() const override { return has_force_jacobians(); }

  // Optional holonomic constraints g(x) = 0 as equations (core/constraints.hpp), for methods that
  // enforce them themselves; nullptr when the model offers none.
  virtual const HolonomicConstraints* holonomic_constraints() const { return nullptr; }

  // Additive split of a mechanical system, made at the level of the acceleration:
  // a = a_E + a_I, and then f_E = [0; a_E], f_I = [v; a_I] (x' = v belongs to the implicit part,
  // so the stiff forces and the motion they cause are solved together). A split model overrides
  // has_imex_split(), imex_split(), the two eval_acceleration_*_part() and, when it has force
  // Jacobians, implicit_force_jacobians() (K_I = ∂a_I/∂x, D_I = ∂a_I/∂v with fixed patterns,
  // written in place like force_jacobians()); J_I = [[0, I], [K_I, D_I]] is assembled from them,
  // and the implicit part of a mechanical model is itself a MechanicalSystem for the implicit
  // methods' velocity-form solves (core/split_views.hpp).
  void acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const {
    count_split_eval(true);
    eval_acceleration_explicit_part(t, x, v, a);
  }
  void acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const {
    count_split_eval(false);
    eval_acceleration_implicit_part(t, x, v, a);
  }
  virtual void implicit_force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k,
                                        SparseMat& d) const;
  // Whether a_I depends on v (dashpots in the implicit part); by default velocity_dependent().
  virtual bool implicit_part_velocity_dependent() const { return velocity_dependent(); }
  // True when M K_I and M D_I are symmetric; by default symmetric_force_jacobians().
  virtual bool symmetric_implicit_force_jacobians() const { return symmetric_force_jacobians(); }
  bool has_implicit_part_jacobian() const override {
    return has_imex_split() && has_force_jacobians();
  }

 protected:
  virtual void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const = 0;
  // By default eval_acceleration(), then done over contiguous ranges (on OpenMP threads for
  // large systems). A model that finishes a in parts overrides it to call done on each part as it
  // finishes (MassSpringNetwork: each partition of points).
  virtual void eval_acceleration_in_ranges(double t, CVecRef x, CVecRef v, VecRef a,
                                           DofRangeFn done) const;
  void eval_rhs(double t, CVecRef y, VecRef dydt) const final;
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override;
  virtual void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const;
  virtual void eval_acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const;
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const final;
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const final;
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const final;
};

// Central-difference increment for component j: eps^(1/3)·max(|y_j|, 1e-3‖y‖∞), or eps^(1/3)
// when y = 0 (balances the O(δ²) truncation against the O(eps/δ) rounding). Scaling by the
// component keeps the truncation error relative for small components of badly scaled systems
// (Robertson's y2 ~ 1e-5 next to y1 ~ 1: a forward difference with increment √eps·max(1, |y_j|)
// was off by 2e-4 relative in the 3e7·y2² derivative); the floor keeps increments that rounding
// would swamp away from components that are (nearly) zero.
double fd_increment(double yj, double y_norm);

// Dense finite-difference Jacobian (central differences, two f evaluations per column), counted
// at the boundary like every other evaluation. For tests, GSL without an analytic Jacobian and
// small systems.
Mat finite_difference_jacobian(const OdeSystem& sys, double t, CVecRef y);

// min(‖J‖₁, ‖J‖∞) ≥ ρ(J): every eigenvalue lies in a Gershgorin disc of J (rows) and of Jᵀ
// (columns), and each disc lies within the largest absolute row (column) sum of the origin.
// A cheap stiffness bound for models with a sparse Jacobian.
double gershgorin_bound(const SparseMat& jac);

// Max-norm of a - b (convenience for errors).
double max_abs_diff(CVecRef a, CVecRef b);

}  // namespace stiffbench
