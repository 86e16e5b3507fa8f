#include "experiments/studies/audit.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include "core/driver.hpp"
#include "core/theory/additive_conditions.hpp"
#include "core/theory/method_analysis.hpp"
#include "experiments/framework/catalog.hpp"
#include "integrators/implicit/dirk.hpp"

namespace stiffbench {

namespace {

std::atomic<long> g_failed_checks{0};

// ---- The counting wrapper -------------------------------------------------------------------

// The hooks every system has, forwarded to the wrapped one; Base is OdeSystem or
// MechanicalSystem.
template <class Base>
class CountingBase : public Base {
 public:
  CountingBase(const OdeSystem& inner, CallCounts& counts) : inner_(inner), counts_(counts) {}

  std::string name() const override { return inner_.name(); }
  double initial_time() const override { return inner_.initial_time(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool has_jacobian() const override { return inner_.has_jacobian(); }
  bool has_jacobian_pattern() const override { return inner_.has_jacobian_pattern(); }
  SparseMat jacobian_pattern() const override { return inner_.jacobian_pattern(); }
  bool has_imex_split() const override { return inner_.has_imex_split(); }
  std::optional<SplitInfo> imex_split() const override { return inner_.imex_split(); }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override {
    return inner_.explicit_part_spectrum(t, y);
  }
  bool autonomous() const override { return inner_.autonomous(); }
  bool has_exact() const override { return inner_.has_exact(); }
  void exact(double t, VecRef y) const override { inner_.exact(t, y); }
  std::vector<Invariant> invariants() const override { return inner_.invariants(); }
  std::optional<double> stiffness(double t, CVecRef y) const override {
    return inner_.stiffness(t, y);
  }
  bool has_constraints() const override { return inner_.has_constraints(); }
  void project(double t, VecRef y) const override { inner_.project(t, y); }
  double constraint_residual(CVecRef y) const override { return inner_.constraint_residual(y); }
  const SpringNetworkView* spring_network() const override { return inner_.spring_network(); }
  // Forwarded so that a grid-fluid method runs, but its operators are not counted (no system of
  // the audit is a grid fluid; stable_fluids is skipped).
  const GridFluid* as_grid_fluid() const override { return inner_.as_grid_fluid(); }
  // ProblemMetadata and FrameOutput.
  std::optional<double> end_time() const override { return inner_.end_time(); }
  std::optional<ProblemMetadata::PublishedSolution> published_solution() const override {
    return inner_.published_solution();
  }
  std::optional<SuggestedStep> suggested_step() const override { return inner_.suggested_step(); }
  std::vector<Invariant> observables() const override { return inner_.observables(); }
  bool has_particles() const override { return inner_.has_particles(); }
  ParticleFrame particles(double t, CVecRef y) const override { return inner_.particles(t, y); }
  bool has_grid() const override { return inner_.has_grid(); }
  GridFrame grid_frame(double t, CVecRef y) const override { return inner_.grid_frame(t, y); }
  std::vector<Profile> profiles(double t, CVecRef y) const override {
    return inner_.profiles(t, y);
  }

 protected:
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.jacobian(t, y, jac);
  }

  const OdeSystem& inner_;
  CallCounts& counts_;
};

class CountingOde final : public CountingBase<OdeSystem> {
 public:
  using CountingBase::CountingBase;
  Index dimension() const override { return inner_.dimension(); }
  bool has_implicit_part_jacobian() const override { return inner_.has_implicit_part_jacobian(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override {
    ++counts_.f;
    inner_.rhs(t, y, dydt);
  }
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const override {
    ++counts_.f;
    inner_.rhs_explicit_part(t, y, fe);
  }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override {
    ++counts_.f;
    inner_.rhs_implicit_part(t, y, fi);
  }
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.implicit_part_jacobian(t, y, jac);
  }
};

// MechanicalSystem's own eval_rhs (final) calls eval_acceleration, which counts.
class CountingMechanical final : public CountingBase<MechanicalSystem> {
 public:
  CountingMechanical(const MechanicalSystem& inner, CallCounts& counts)
      : CountingBase(inner, counts), mech_(inner) {}
  Index dofs() const override { return mech_.dofs(); }
  bool velocity_dependent() const override { return mech_.velocity_dependent(); }
  Vec masses() const override { return mech_.masses(); }
  bool has_force_jacobians() const override { return mech_.has_force_jacobians(); }
  bool has_jacobian() const override { return mech_.has_jacobian(); }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override {
    ++counts_.jac;
    mech_.stiffness_block(t, x, v, k);
  }
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override {
    mech_.damping_block(t, x, v, d);  // with K, one Jacobian (counted there)
  }
  void force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k, SparseMat& d) const override {
    ++counts_.jac;
    mech_.force_jacobians(t, x, v, k, d);
  }
  std::vector<Index> fixed_dofs() const override { return mech_.fixed_dofs(); }
  bool symmetric_force_jacobians() const override { return mech_.symmetric_force_jacobians(); }
  const HolonomicConstraints* holonomic_constraints() const override {
    return mech_.holonomic_constraints();
  }
  void implicit_force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k,
                                SparseMat& d) const override {
    ++counts_.jac;
    mech_.implicit_force_jacobians(t, x, v, k, d);
  }
  bool implicit_part_velocity_dependent() const override {
    return mech_.implicit_part_velocity_dependent();
  }
  bool symmetric_implicit_force_jacobians() const override {
    return mech_.symmetric_implicit_force_jacobians();
  }

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration(t, x, v, a);
  }
  void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration_explicit_part(t, x, v, a);
  }
  void eval_acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration_implicit_part(t, x, v, a);
  }
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.jacobian(t, y, jac);
  }

 private:
  const MechanicalSystem& mech_;
};

}  // namespace

std::unique_ptr<OdeSystem> make_counting_system(const OdeSystem& inner, CallCounts& counts) {
  if (const MechanicalSystem* m = inner.as_mechanical())
    return std::make_unique<CountingMechanical>(*m, counts);
  return std::make_unique<CountingOde>(inner, counts);
}

namespace {

// ---- The audit's own systems ---------------------------------------------------------------

// The split of the audit's own systems for methods that need one (IMEX pairs, operator
// splitting): f_E = f_I = f/2, both parts carrying half of every term. The methods' own split
// behaviour is tested on the split models; here the split only lets them run, so that what they
// report can be compared with what they do.
SplitInfo halves_split() { return SplitInfo{"halves", "half of f", "half of f"}; }

// The 1×1 Jacobian [v] of the audit's scalar systems (v = 0 is stored too: the pattern is fixed).
void scalar_jacobian(SparseMat& jac, double v) {
  jac.resize(1, 1);
  jac.setZero();
  jac.insert(0, 0) = v;
  jac.makeCompressed();
}

// y' = λy, λ = -1, y(0) = 1: the scalar linear system of the count checks (split: each part
// -y/2).
class ScalarLinear final : public OdeSystem {
 public:
  explicit ScalarLinear(bool split = false) : split_(split) {}
  std::string name() const override { return split_ ? "scalar_linear(split)" : "scalar_linear"; }
  bool has_imex_split() const override { return split_; }
  std::optional<SplitInfo> imex_split() const override {
    return split_ ? std::optional<SplitInfo>(halves_split()) : std::nullopt;
  }
  bool has_implicit_part_jacobian() const override { return split_; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override { dydt[0] = -y[0]; }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override { scalar_jacobian(jac, -1.0); }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const override { fe[0] = -0.5 * y[0]; }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const override { fi[0] = -0.5 * y[0]; }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    scalar_jacobian(jac, -0.5);
  }

 private:
  bool split_;
};

// y' = t^q (q = 0: y' = 1), y(0) = 0, exact y = t^(q+1)/(q+1); Jacobian 0 (one stored zero).
// Split: each part t^q/2, so that a pair whose two tables have order p integrates it exactly.
class Monomial final : public OdeSystem {
 public:
  explicit Monomial(int q, bool split = false) : q_(q), split_(split) {}
  bool has_imex_split() const override { return split_; }
  std::optional<SplitInfo> imex_split() const override {
    return split_ ? std::optional<SplitInfo>(halves_split()) : std::nullopt;
  }
  bool has_implicit_part_jacobian() const override { return split_; }
  std::string name() const override {
    return (q_ == 0 ? "y'=1" : "y'=t^" + std::to_string(q_)) + (split_ ? " (split)" : "");
  }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Zero(1); }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return q_ == 0; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::pow(t, q_ + 1) / (q_ + 1); }

 protected:
  void eval_rhs(double t, CVecRef, VecRef dydt) const override { dydt[0] = power(t); }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override { scalar_jacobian(jac, 0.0); }
  void eval_rhs_explicit_part(double t, CVecRef, VecRef fe) const override {
    fe[0] = 0.5 * power(t);
  }
  void eval_rhs_implicit_part(double t, CVecRef, VecRef fi) const override {
    fi[0] = 0.5 * power(t);
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    scalar_jacobian(jac, 0.0);
  }

 private:
  double power(double t) const { return q_ == 0 ? 1.0 : std::pow(t, q_); }
  int q_;
  bool split_;
};

// The three systems of the count checks, with the span of a run on each.
struct CountSystem {
  std::string label;
  std::unique_ptr<OdeSystem> sys;
  double span;  // fixed-step and adaptive runs cover [t0, t0 + span]
};

// Methods that need an additive split (`split`: IMEX pairs, operator splitting, multirate) get
// split systems instead: the scalar one in halves, Kaps' problem (ε = 1e-3, its 1/ε terms
// implicit; kepler has no split) and the cloth with split=springs.
std::vector<CountSystem> count_systems(bool split = false) {
  std::vector<CountSystem> out;
  out.push_back({split ? "scalar_linear(split)" : "scalar_linear",
                 std::make_unique<ScalarLinear>(split), 1.0});
  if (split) {
    Params kaps;
    kaps.set("eps", "1e-3");
    out.push_back({"kaps(eps=1e-3)", model_registry().create("kaps", kaps), 0.5});
  } else {
    Params kepler;
    kepler.set("e", "0.5");
    out.push_back({"kepler(e=0.5)", model_registry().create("kepler", kepler), 0.5});
  }
  Params cloth;
  cloth.set("n", "8");
  if (split) cloth.set("split", "springs");
  // 8×8 points; structural ω = √(k/m) ≈ 35, so h = 2.5e-4 is far inside every explicit
  // method's stability limit.
  out.push_back({split ? "cloth(n=8,split=springs)" : "cloth(n=8)",
                 model_registry().create("cloth", cloth), 0.004});
  return out;
}

// y' = E y + I y with E = [[0, 1], [-1, 0]] (a rotation: the explicit part) and I = diag(-1, -2)
// (decay: the implicit part), y(0) = (1, 1/2). E and I do not commute (EI - IE =
// [[0, -1], [-1, 0]]), so a splitting's error is its own, not cancelled as on Kaps' problem,
// whose exact solution keeps f_I = 0 (y1 = y2²) and makes Lie and Strang look exact.
// Exact: y(t) = e^(Mt) y0, M = E + I = [[-1, 1], [-1, -2]], whose eigenvalues are s ± iω with
// s = tr/2 = -3/2 and ω = √(det − s²) = √(3 − 9/4); e^(Mt) = e^(st) (cos ωt · 1 + sin ωt/ω ·
// (M − s·1)) (Cayley–Hamilton).
class RotationDecay final : public OdeSystem {
 public:
  std::string name() const override { return "rotation_decay"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{1.0, 0.5}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override {
    return SplitInfo{"rotation_decay", "the rotation [[0, 1], [-1, 0]] y",
                     "the decay diag(-1, -2) y"};
  }
  bool has_implicit_part_jacobian() const override { return true; }
  void exact(double t, VecRef y) const override {
    const double s = -1.5, w = std::sqrt(0.75);
    const double c = std::cos(w * t), sn = std::sin(w * t) / w, e = std::exp(s * t);
    const double y1 = 1.0, y2 = 0.5;  // y0
    // (M − s·1) = [[0.5, 1], [-1, -0.5]]
    y[0] = e * (c * y1 + sn * (0.5 * y1 + y2));
    y[1] = e * (c * y2 + sn * (-y1 - 0.5 * y2));
  }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f[0] = y[1] - y[0];
    f[1] = -y[0] - 2.0 * y[1];
  }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override {
    const std::vector<Eigen::Triplet<double>> t{
        {0, 0, -1.0}, {0, 1, 1.0}, {1, 0, -1.0}, {1, 1, -2.0}};
    jac.resize(2, 2);
    jac.setFromTriplets(t.begin(), t.end());
  }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const override {
    fe[0] = y[1];
    fe[1] = -y[0];
  }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const override {
    fi[0] = -y[0];
    fi[1] = -2.0 * y[1];
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    const std::vector<Eigen::Triplet<double>> t{{0, 0, -1.0}, {1, 1, -2.0}};
    jac.resize(2, 2);
    jac.setFromTriplets(t.begin(), t.end());
  }
};

// ---- Helpers ------------------------------------------------------------------------------

std::string num(double x, int digits = 4) {
  std::ostringstream os;
  os.precision(digits);
  os << x;
  return os.str();
}

AuditRow row(const std::string& integ, const std::string& check, const std::string& system,
             const std::string& claimed, const std::string& measured, bool ok,
             const std::string& reason) {
  return {integ, check, system, claimed, measured, ok ? "ok" : "fail", reason};
}

AuditRow skip(const std::string& integ, const std::string& check, const std::string& system,
              const std::string& reason) {
  return {integ, check, system, "-", "-", "skip", reason};
}

std::unique_ptr<Integrator> create(const std::string& name) {
  return integrator_registry().create(name, Params{});
}

// The Butcher tableau of a method: its own butcher_tableau() (explicit, embedded, DIRK, fully
// implicit and Radau IIA steppers).
const ButcherTableau* tableau_of(const Integrator& integ) { return integ.butcher_tableau(); }

// Why the method cannot run on `sys`, or empty.
std::string incompatibility(const Integrator& integ, const OdeSystem& sys) {
  try {
    check_compatible(integ.info(), sys);
  } catch (const BadInput& e) {
    return e.what();
  }
  return {};
}

std::string run_note(const RunResult& r) {
  if (r.stats.status == Status::ok) return {};
  return "the run ended with status " + to_string(r.stats.status) +
         (r.stats.message.empty() ? "" : ": " + r.stats.message);
}

// One run on the counting wrapper around `sys`.
struct CountedRun {
  RunResult result;
  CallCounts counts;
  long reset_jac = 0;  // force-Jacobian calls inside reset() (pattern analysis, not counted)
};

// Force-Jacobian calls a fresh method makes inside reset() alone: structure (pattern)
// analysis, which the system boundary does not count as evaluations (like jacobian_pattern()).
long reset_jacobian_calls(const std::string& name, const OdeSystem& sys) {
  CallCounts c;
  const auto w = make_counting_system(sys, c);
  auto integ = create(name);
  const Vec y0 = w->initial_state();
  const long before_analytic = w->counters().jac_evals;
  integ->reset(*w, w->initial_time(), y0);
  // Analytic jacobian() calls at reset are counted at the boundary (and reported): keep them.
  return c.jac - (w->counters().jac_evals - before_analytic);
}

CountedRun counted_fixed(const std::string& name, const OdeSystem& sys, double span, long steps) {
  CountedRun out;
  out.reset_jac = reset_jacobian_calls(name, sys);
  const auto w = make_counting_system(sys, out.counts);
  auto integ = create(name);
  FixedStepOptions o;
  o.t_end = sys.initial_time() + span;
  o.h = span / static_cast<double>(steps);
  out.result = run_fixed_step(*w, *integ, o);
  return out;
}

CountedRun counted_adaptive(const std::string& name, const OdeSystem& sys, double span) {
  CountedRun out;
  out.reset_jac = reset_jacobian_calls(name, sys);
  const auto w = make_counting_system(sys, out.counts);
  auto integ = create(name);
  AdaptiveOptions o;
  o.t_end = sys.initial_time() + span;
  out.result = run_adaptive(*w, *integ, o);
  return out;
}

void count_rows(std::vector<AuditRow>& rows, const std::string& name, const std::string& mode,
                const std::string& system, const CountedRun& run) {
  const std::string note = run_note(run.result);
  const long f = run.counts.f, jac = run.counts.jac - run.reset_jac;
  const SolveStats& s = run.result.stats;
  std::string why =
      "counting wrapper " + std::to_string(f) + " vs reported " + std::to_string(s.f_evals);
  // The counts are compared whatever the run's outcome (up to where it ended; the note says).
  rows.push_back(row(name, "f_evals_" + mode, system, std::to_string(s.f_evals), std::to_string(f),
                     f == s.f_evals,
                     f == s.f_evals ? note : why + (note.empty() ? "" : "; " + note)));
  why = "counting wrapper " + std::to_string(jac) + " (" + std::to_string(run.reset_jac) +
        " pattern call" + (run.reset_jac == 1 ? "" : "s") +
        " in reset() not counted) vs reported " + std::to_string(s.jac_evals);
  rows.push_back(row(
      name, "jac_evals_" + mode, system, std::to_string(s.jac_evals), std::to_string(jac),
      jac == s.jac_evals,
      jac == s.jac_evals ? (run.reset_jac ? why : note) : why + (note.empty() ? "" : "; " + note)));
}

// f_evals, jac_evals (fixed step and adaptive) and f_per_step on the three systems.
void count_checks(std::vector<AuditRow>& rows, const std::string& name) {
  const auto probe = create(name);
  const MethodInfo& info = probe->info();
  const bool per_step =
      (info.family == Family::explicit_rk || info.family == Family::symplectic) && info.stages > 0;
  std::vector<CountSystem> systems = count_systems(info.requires_.split);
  if (info.requires_.constraints) {
    // Methods that enforce holonomic constraints (rattle) run on none of the three: their counts
    // are checked on a constrained pendulum chain of 3 bobs instead.
    Params chain;
    chain.set("n", "3");
    chain.set("constrained", "true");
    systems.push_back(
        {"pendulum_chain(n=3,constrained)", model_registry().create("pendulum_chain", chain), 0.1});
  }
  for (const CountSystem& cs : systems) {
    if (const std::string why = incompatibility(*probe, *cs.sys); !why.empty()) {
      rows.push_back(skip(name, "f_evals", cs.label, why));
      continue;
    }
    if (probe->supports_fixed_step()) {
      const CountedRun r16 = counted_fixed(name, *cs.sys, cs.span, 16);
      count_rows(rows, name, "fixed", cs.label, r16);
      if (per_step) {
        const CountedRun r8 = counted_fixed(name, *cs.sys, cs.span / 2, 8);
        const long diff = r16.counts.f - r8.counts.f;
        const std::string note = run_note(r16.result) + run_note(r8.result);
        rows.push_back(row(name, "f_per_step", cs.label, std::to_string(info.stages),
                           num(static_cast<double>(diff) / 8.0),
                           diff == 8L * info.stages && note.empty(),
                           "f evaluations of 16 steps minus those of 8 (start-up cancels): " +
                               std::to_string(r16.counts.f) + " - " + std::to_string(r8.counts.f) +
                               (note.empty() ? "" : "; " + note)));
      }
    }
    if (probe->supports_adaptive())
      count_rows(rows, name, "adaptive", cs.label, counted_adaptive(name, *cs.sys, cs.span));
  }
  if (info.family == Family::reference)
    rows.push_back(skip(name, "library_f_evals", "-",
                        "the library's own count (library_f_evals) includes evaluations it makes "
                        "inside (difference quotients, restarts) and is not a claim about the "
                        "system boundary; f_evals above is checked instead"));
  else if (!per_step)
    rows.push_back(skip(name, "f_per_step", "-",
                        info.stages > 0
                            ? "f evaluations per step are not fixed: they follow the Newton "
                              "iterations or the Jacobian's source (finite differences)"
                            : "the method states no fixed number of evaluations per step"));
}

// ---- Local error slope ------------------------------------------------------------------------

constexpr double kSlopeTol = 0.3;
constexpr double kErrMax = 1e-3, kFloorMin = 1e-13, kFloorFactor = 100;
constexpr int kSlopePoints = 3, kLadderLevels = 28;

// The least-squares slope of ly against lx from the raw sums (n Σxy − Σx Σy)/(n Σxx − (Σx)²).
double slope_from_sums(const std::vector<double>& lx, const std::vector<double>& ly) {
  const double n = static_cast<double>(lx.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    sx += lx[i];
    sy += ly[i];
    sxx += lx[i] * lx[i];
    sxy += lx[i] * ly[i];
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

void slope_check(std::vector<AuditRow>& rows, const std::string& name) {
  const std::string check = "local_error_slope";
  auto probe = create(name);
  const MethodInfo& info = probe->info();
  // Kepler (e = 0.5); methods that need a split: RotationDecay, whose parts do not commute.
  const bool split = info.requires_.split;
  Params kp;
  kp.set("e", "0.5");
  const std::unique_ptr<OdeSystem> sys =
      split ? std::make_unique<RotationDecay>() : model_registry().create("kepler", kp);
  const std::string label = split ? "rotation_decay" : "kepler(e=0.5)";
  if (const std::string why = incompatibility(*probe, *sys); !why.empty())
    return rows.push_back(skip(name, check, label, why));
  if (info.order <= 0)
    return rows.push_back(skip(name, check, label, "variable order: no fixed slope"));
  if (!probe->supports_fixed_step())
    return rows.push_back(skip(name, check, label, "adaptive only: no fixed step h"));
  const double t0 = sys->initial_time();
  const Vec y0 = sys->initial_state();
  // h_k = 0.5 · 2^(-k/2): a fine ladder, so that even an order-8 method has several errors
  // between its pre-asymptotic range and its floor.
  std::vector<double> hs, errs;
  std::string note;
  for (int k = 0; k < kLadderLevels; ++k) {
    const double h = 0.5 * std::pow(2.0, -0.5 * k);
    auto integ = create(name);
    FixedStepOptions o;
    o.t_end = t0 + h;
    o.h = h;
    const RunResult r = run_fixed_step(*sys, *integ, o);
    if (r.stats.status != Status::ok) {
      if (note.empty()) note = "h = " + num(h, 3) + ": " + run_note(r);
      continue;
    }
    Vec exact(y0.size());
    sys->exact(o.t_end, exact);
    hs.push_back(h);
    errs.push_back(max_abs_diff(r.y, exact));
  }
  // The floor: 100 times the largest error among the four smallest steps, where a high-order
  // method's error is round-off or its solver's tolerance (Newton noise of 1e-12 stays out of
  // the fit), at least 1e-13. The slope is fitted on the three smallest h whose errors lie in
  // [floor, 1e-3]: the asymptotic end of the ladder, far above the floor.
  double noise = 0;
  for (std::size_t i = errs.size() >= 4 ? errs.size() - 4 : 0; i < errs.size(); ++i)
    noise = std::max(noise, errs[i]);
  const double floor = std::max(kFloorMin, kFloorFactor * noise);
  std::vector<double> lx, ly;
  for (std::size_t i = hs.size(); i-- > 0 && lx.size() < kSlopePoints;)
    if (errs[i] >= floor && errs[i] <= kErrMax) {
      lx.push_back(std::log(hs[i]));
      ly.push_back(std::log(errs[i]));
    }
  const int expected = info.order + 1;
  if (lx.size() < kSlopePoints) {
    std::string errs_text;
    for (std::size_t i = 0; i < hs.size(); i += 2) errs_text += (i ? ", " : "") + num(errs[i], 2);
    return rows.push_back(row(name, check, label, std::to_string(expected), "-", false,
                              "fewer than 3 errors lie in [" + num(floor, 2) +
                                  ", 1e-3] (errors at h = 0.5/2^k: " + errs_text + ")" +
                                  (note.empty() ? "" : "; " + note)));
  }
  const double slope = slope_from_sums(lx, ly);
  const double h_min = std::exp(*std::min_element(lx.begin(), lx.end()));
  const double h_max = std::exp(*std::max_element(lx.begin(), lx.end()));
  rows.push_back(row(name, check, label, std::to_string(expected), num(slope, 3),
                     std::abs(slope - expected) <= kSlopeTol,
                     "least-squares slope over " + std::to_string(lx.size()) + " steps h in [" +
                         num(h_min, 3) + ", " + num(h_max, 3) + "] (errors above the floor " +
                         num(floor, 2) + "), tolerance 0.3" + (note.empty() ? "" : "; " + note)));
}

// ---- Adaptive exactness -----------------------------------------------------------------------

constexpr long kFewSteps = 30;
constexpr double kExactTol = 1e-13;

void adaptive_checks(std::vector<AuditRow>& rows, const std::string& name) {
  auto probe = create(name);
  const MethodInfo& info = probe->info();
  if (!probe->supports_adaptive()) return;
  const bool split = info.requires_.split;  // then both parts carry half of t^q
  if (info.order <= 0) {
    const std::string why =
        "variable order: a polynomial is exact only at the order the method has reached";
    rows.push_back(skip(name, "adaptive_constant", "y'=1", why));
    rows.push_back(skip(name, "adaptive_polynomial", "y'=t^(p-1)", why));
    return;
  }
  const auto run = [&](const Monomial& sys) {
    auto integ = create(name);
    AdaptiveOptions o;
    o.t_end = 1.0;
    return run_adaptive(sys, *integ, o);
  };
  {
    const Monomial sys(0, split);
    const RunResult r = run(sys);
    const double err = std::abs(r.y[0] - 1.0);
    const bool ok = r.stats.status == Status::ok && err <= kExactTol && r.stats.steps <= kFewSteps;
    rows.push_back(
        row(name, "adaptive_constant", sys.name(), "error <= 1e-13 in <= 30 steps",
            "error " + num(err, 2) + " in " + std::to_string(r.stats.steps) + " steps", ok,
            ok                    ? ""
            : run_note(r).empty() ? "every error estimate should be zero up to round-off "
                                    "(embedded weights that do not sum to 1?)"
                                  : run_note(r)));
  }
  {
    const Monomial sys(info.order - 1, split);
    const RunResult r = run(sys);
    const double exact = 1.0 / info.order;
    const double err = std::abs(r.y[0] - exact);
    const bool ok = r.stats.status == Status::ok && err <= kExactTol;
    rows.push_back(row(
        name, "adaptive_polynomial", sys.name(), "error <= 1e-13",
        "error " + num(err, 2) + " in " + std::to_string(r.stats.steps) + " steps", ok,
        ok                    ? ""
        : run_note(r).empty() ? "an order-" + std::to_string(info.order) + " method integrates t^" +
                                    std::to_string(info.order - 1) + " exactly"
                              : run_note(r)));
  }
}

// ---- Tableau checks ----------------------------------------------------------------------------

// Claimed order p exact: conditions up to min(p, 6) hold, some of order p + 1 fails (p < 6).
AuditRow order_row(const std::string& name, const std::string& check, const ButcherTableau& t,
                   const Vec& weights, int claimed) {
  const int measured = t.satisfied_order(weights, 1e-12, 6);
  const std::string label = t.name;
  if (claimed >= 6)
    return row(name, check, label, std::to_string(claimed),
               measured >= 6 ? ">= 6" : std::to_string(measured), measured >= 6,
               "conditions up to order 6 checked (the rooted trees are generated up to order 6)");
  const bool ok = measured == claimed;
  std::string reason;
  if (measured < claimed)
    reason = "an order-" + std::to_string(measured + 1) + " condition fails by " +
             num(t.order_defect(weights, measured + 1), 3);
  else if (measured > claimed)
    reason = "every condition of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  return row(name, check, label, std::to_string(claimed), std::to_string(measured), ok, reason);
}

// The same for an additive pair: the conditions of both tables and the coupling ones
// (core/theory/additive_conditions.hpp) with the weights wE, wI, checked to order 6.
AuditRow additive_order_row(const std::string& name, const std::string& check,
                            const AdditiveTableau& t, const Vec& wE, const Vec& wI, int claimed) {
  constexpr int kMax = 6;
  const int measured =
      additive_satisfied_order(t.explicit_table, t.implicit_table, wE, wI, kMax, 1e-12);
  const std::string label = t.name + " (additive)";
  if (claimed >= kMax)
    return row(name, check, label, std::to_string(claimed),
               measured >= kMax ? ">= 6" : std::to_string(measured), measured >= kMax,
               "additive conditions up to order 6 checked");
  std::string reason;
  if (measured < claimed) {
    const auto conditions =
        additive_order_conditions(t.explicit_table, t.implicit_table, wE, wI, measured + 1, "b");
    if (const auto c = first_violated_additive_condition(conditions, measured + 1, false, 1e-12))
      reason = std::string(c->coupling ? "the coupling condition " : "the condition ") + c->name +
               " fails by " + num(c->residual, 3);
  } else if (measured > claimed) {
    reason = "every additive condition of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  }
  return row(name, check, label, std::to_string(claimed), std::to_string(measured),
             measured == claimed, reason);
}

// An additive pair's claims: its order and embedded order from the additive conditions (the
// tables' sizes and shared nodes are checked when the pair is built).
void additive_checks(std::vector<AuditRow>& rows, const std::string& name, const Integrator& integ,
                     const AdditiveTableau& t) {
  rows.push_back(additive_order_row(name, "tableau_order", t, t.explicit_table.b,
                                    t.implicit_table.b, integ.info().order));
  if (t.has_embedded())
    rows.push_back(additive_order_row(name, "embedded_order", t, t.explicit_table.b_embedded,
                                      t.implicit_table.b_embedded, t.embedded_order));
  rows.push_back(
      skip(name, "stage_order", t.name + " (additive)", "an additive pair claims no stage order"));
}

// A claimed order against the achieved one of a set of conditions (Rosenbrock: the classical
// conditions of core/theory/method_analysis.hpp to order 8, or the W-conditions to kMaxWOrder): the
// claim must be the order, no more and no less.
AuditRow conditions_row(const std::string& name, const std::string& check, const std::string& label,
                        const std::vector<OrderCondition>& conditions, int measured, int max_order,
                        int claimed, const std::string& what) {
  if (claimed >= max_order)
    return row(name, check, label, std::to_string(claimed),
               measured >= max_order ? ">= " + std::to_string(max_order) : std::to_string(measured),
               measured >= max_order,
               what + " up to order " + std::to_string(max_order) + " checked");
  std::string reason;
  if (measured < claimed) {
    if (const auto c = first_violated_condition(conditions, measured + 1))
      reason = "the " + what + " of tree " + c->name + " (order " + std::to_string(c->order) +
               ") fails by " + num(c->residual, 3);
  } else if (measured > claimed) {
    reason = "every " + what + " of order " + std::to_string(claimed + 1) +
             " holds as well: the claim is not the order";
  }
  return row(name, check, label, std::to_string(claimed), std::to_string(measured),
             measured == claimed, reason);
}

// A Rosenbrock method's claims: its order and embedded order from the order conditions of
// Hairer & Wanner II, IV.7 (rooted trees to order 8, β = α + Γ on a vertex with one son), its
// W-order when it claims one (the conditions with an arbitrary matrix in place of J).
void rosenbrock_checks(std::vector<AuditRow>& rows, const std::string& name,
                       const Integrator& integ, const RosenbrockTableau& t) {
  const MethodAnalysis m = analyze_rosenbrock(t);
  const std::string label = t.name + " (Rosenbrock)";
  rows.push_back(conditions_row(name, "tableau_order", label, m.conditions, m.order, 8,
                                integ.info().order, "order condition"));
  if (t.b_embedded.size() == t.stages()) {
    RosenbrockTableau embedded = t;
    embedded.b = t.b_embedded;
    const MethodAnalysis e = analyze_rosenbrock(embedded);
    rows.push_back(conditions_row(name, "embedded_order", label, e.conditions, e.order, 8,
                                  t.embedded_order, "order condition"));
  }
  if (t.w_order > 0)
    rows.push_back(conditions_row(name, "w_order", label, m.w_conditions, m.w_order, kMaxWOrder,
                                  t.w_order, "W-condition"));
  else
    rows.push_back(skip(
        name, "w_order", label,
        "no W-order claimed (the W-conditions hold to order " + std::to_string(m.w_order) + ")"));
  rows.push_back(skip(name, "stage_order", label, "a Rosenbrock method has no stage order"));
}

void tableau_checks(std::vector<AuditRow>& rows, const std::string& name) {
  auto integ = create(name);
  if (const AdditiveTableau* a = integ->additive_tableau())
    return additive_checks(rows, name, *integ, *a);
  if (const RosenbrockTableau* r = integ->rosenbrock_tableau())
    return rosenbrock_checks(rows, name, *integ, *r);
  const ButcherTableau* t = tableau_of(*integ);
  if (!t) {
    rows.push_back(skip(name, "tableau", "-", "not defined by a Butcher tableau"));
    return;
  }
  // Sizes and nodes first: the order conditions need them.
  if (const std::string d = t->defect();
      !d.empty() &&
      (t->c.size() != t->stages() || t->a.rows() != t->stages() || t->a.cols() != t->stages())) {
    rows.push_back(
        row(name, "tableau_order", t->name, std::to_string(integ->info().order), "-", false, d));
    return;
  }
  rows.push_back(order_row(name, "tableau_order", *t, t->b, integ->info().order));
  if (t->b_embedded.size() == t->stages())
    rows.push_back(order_row(name, "embedded_order", *t, t->b_embedded, t->embedded_order));
  const int q = t->satisfied_stage_order();
  if (t->stage_order > 0)
    rows.push_back(row(name, "stage_order", t->name, std::to_string(t->stage_order),
                       std::to_string(q), q >= t->stage_order,
                       q >= t->stage_order ? "" : "C(" + std::to_string(q + 1) + ") fails"));
  else
    rows.push_back(
        skip(name, "stage_order", t->name,
             "the tableau claims no stage order (C(q) holds for q = " + std::to_string(q) + ")"));
  const bool fsal = t->coefficients_fsal();
  rows.push_back(
      row(name, "fsal", t->name, t->fsal ? "yes" : "no", fsal ? "yes" : "no", !t->fsal || fsal,
          t->fsal && !fsal   ? "the last row of A is not b"
          : !t->fsal && fsal ? "the coefficients are FSAL; the method does not claim (or use) it"
                             : ""));
}

// Runs one group of checks; an exception (other than the model or method refusing the system,
// which the checks test first) is a failed row naming it.
template <class Fn>
void guarded(std::vector<AuditRow>& rows, const std::string& name, const std::string& check,
             Fn fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    rows.push_back({name, check, "-", "-", "-", "fail", std::string("exception: ") + e.what()});
  }
}

}  // namespace

std::vector<AuditRow> audit_integrator(const std::string& name) {
  std::vector<AuditRow> rows;
  guarded(rows, name, "counts", [&] { count_checks(rows, name); });
  guarded(rows, name, "local_error_slope", [&] { slope_check(rows, name); });
  guarded(rows, name, "adaptive", [&] { adaptive_checks(rows, name); });
  guarded(rows, name, "tableau", [&] { tableau_checks(rows, name); });
  return rows;
}

long AuditResult::count(const std::string& status) const {
  return std::count_if(rows.begin(), rows.end(),
                       [&](const AuditRow& r) { return r.status == status; });
}

void AuditSpec::validate() const {
  std::set<std::string> seen;
  for (const auto& name : integrators) {
    integrator_registry().at(name);  // BadInput naming an unknown integrator
    require_input(seen.insert(name).second, "--integrators: '" + name + "' is listed twice");
  }
}

nlohmann::json AuditSpec::to_json() const {
  return {{"integrators", integrators.empty() ? integrator_registry().names() : integrators}};
}

AuditResult run_audit(const AuditSpec& spec, std::ostream* progress) {
  spec.validate();
  const std::vector<std::string> names =
      spec.integrators.empty() ? integrator_registry().names() : spec.integrators;
  AuditResult res;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto start = std::chrono::steady_clock::now();
    auto rows = audit_integrator(names[k]);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    long failed = 0;
    for (const auto& r : rows) failed += r.status == "fail";
    if (progress)
      *progress << "audit " << names[k] << " (" << k + 1 << "/" << names.size()
                << "): " << (failed ? std::to_string(failed) + " failed" : std::string("ok"))
                << ", " << format_fixed(s, 2) << " s\n";
    res.rows.insert(res.rows.end(), rows.begin(), rows.end());
  }
  return res;
}

Table audit_table(const AuditResult& r) {
  Table t{{"integrator", "check", "system", "claimed", "measured", "status", "reason"}, {}};
  for (const auto& a : r.rows)
    t.rows.push_back({a.integrator, a.check, a.system, a.claimed, a.measured, a.status, a.reason});
  return t;
}

Table audit_summary_table(const AuditResult& r) {
  Table t{{"integrator", "ok", "fail", "skip", "failed checks"}, {}};
  std::vector<std::string> order;
  std::map<std::string, std::array<long, 3>> counts;
  std::map<std::string, std::string> failed;
  for (const auto& a : r.rows) {
    if (!counts.count(a.integrator)) {
      order.push_back(a.integrator);
      counts[a.integrator] = {0, 0, 0};
    }
    auto& c = counts[a.integrator];
    if (a.status == "ok") ++c[0];
    if (a.status == "fail") {
      ++c[1];
      std::string& f = failed[a.integrator];
      f += (f.empty() ? "" : ", ") + a.check + (a.system == "-" ? "" : " (" + a.system + ")");
    }
    if (a.status == "skip") ++c[2];
  }
  for (const auto& name : order) {
    const auto& c = counts[name];
    t.rows.push_back({name, std::to_string(c[0]), std::to_string(c[1]), std::to_string(c[2]),
                      failed.count(name) ? failed[name] : "-"});
  }
  return t;
}

namespace {

std::string markdown_report(const AuditResult& r) {
  std::ostringstream os;
  os << "# Audit of the methods' claims\n\n"
     << r.count("ok") << " checks passed, " << r.count("fail") << " failed, " << r.count("skip")
     << " did not apply (the reason says why). The checks and their tolerances are described in "
        "docs/commands/audit.md; every row is in `audit.csv`.\n\n"
     << "## Summary\n\n"
     << audit_summary_table(r).to_markdown() << "\n## Checks\n\n"
     << audit_table(r).to_markdown();
  return os.str();
}

class AuditJob : public StudyJob {
 public:
  explicit AuditJob(AuditSpec spec) : spec_(std::move(spec)) { spec_.validate(); }
  nlohmann::json spec_json() const override { return spec_.to_json(); }
  void run(std::ostream* progress) override {
    result_ = run_audit(spec_, progress);
    g_failed_checks += result_.count("fail");
  }
  Table unit_table() const override { return audit_table(result_); }
  bool write(const std::filesystem::path& dir, const std::string&, const PlotOptions&,
             std::ostream&) const override {
    write_file_atomic(dir / "audit.csv", audit_table(result_).to_csv());
    write_file_atomic(dir / "audit.md", markdown_report(result_));
    nlohmann::json meta = run_metadata("audit", spec_.to_json());
    meta["counts"] = {{"ok", result_.count("ok")},
                      {"fail", result_.count("fail")},
                      {"skip", result_.count("skip")}};
    write_file_atomic(dir / "audit.json", meta.dump(2) + "\n");
    return false;  // no plot
  }
  void print_summary(std::ostream& out) const override {
    out << audit_summary_table(result_).to_markdown() << "\n"
        << result_.count("ok") << " checks ok, " << result_.count("fail") << " failed, "
        << result_.count("skip") << " skipped\n";
  }
  std::string report_markdown(const std::string& note) const override {
    return note + "\n\n" + audit_summary_table(result_).to_markdown() + "\n";
  }
  std::string default_title() const override { return "Audit of the methods' claims"; }
  const AuditResult& result() const { return result_; }

 private:
  AuditSpec spec_;
  AuditResult result_;
};

}  // namespace

long audit_failed_checks() { return g_failed_checks.load(); }

StudyKind audit_study_kind() {
  StudyKind k;
  k.name = "audit";
  k.stem = "audit";
  k.summary =
      "checks every method's claims (evaluation counts against a counting wrapper, local-error "
      "slope, adaptive exactness on polynomials, tableau order, stage order and FSAL); writes "
      "audit.{csv,md,json}; exit code 3 when a check fails";
  k.takes_model = false;
  k.takes_params = false;
  k.integrators_required = false;
  k.unit_columns = audit_table(AuditResult{}).columns;
  k.make = [](const StudyInputs& t, const Params&, const StudyContext&) {
    AuditSpec s;
    s.integrators = t.integrators;
    return std::make_unique<AuditJob>(std::move(s));
  };
  return k;
}

const AuditResult& audit_result(const StudyJob& job) {
  return dynamic_cast<const AuditJob&>(job).result();
}

AuditResult audit_study(AuditSpec spec, const std::vector<IntegratorFactory>& integrators,
                        const std::filesystem::path& dir, const StudyContext& ctx) {
  std::string no_model;
  const ScopedStudyObjects scope(StudyObjects{nullptr, integrators}, no_model, spec.integrators);
  AuditJob job(std::move(spec));
  run_study_job(study_kind("audit"), job, dir, ctx);
  return job.result();
}

}  // namespace stiffbench
