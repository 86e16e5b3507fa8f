// The stability-limit experiment (experiments/studies/stability.hpp): measured h_max on the
// fixed-fixed spring chain against the closed-form limits, the unstable-for-all-h and A-stable
// statuses (one run at the largest step for a method predicted stable for every step, the search
// with probe_unbounded, a contradicted prediction), a non-finite spectrum as no prediction, the
// k^(-1/2) and 1/|λ| scalings of a sweep, and the sweep parser.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

#include "core/integrator.hpp"
#include "core/ode_system.hpp"
#include "core/theory/linear_stability.hpp"
#include "core/theory/tableau.hpp"
#include "core/types.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/studies/stability.hpp"

namespace stiffbench {
namespace {

// Fixed-fixed chain, k = m = 1, N = 10: ω_max = 2 sin(10π/22) = 1.979643
// (docs/reference-values.md).
const double kOmegaMax = 2.0 * std::sin(10.0 * std::numbers::pi / 22.0);

const StabilityRow& row_of(const StabilityResult& r, const std::string& integrator,
                           double value = 0.0) {
  for (const auto& row : r.rows)
    if (row.integrator == integrator && row.value == value) return row;
  throw std::logic_error("no row for " + integrator);
}

// The study on a user's objects beside the spec's names (resolve_inputs with StudyObjects).
StabilityResult run_on_objects(const StabilitySpec& spec, StudyObjects objects) {
  const StudyInputs in = resolve_inputs(StudyTarget{.model = spec.model,
                                                    .params = spec.params,
                                                    .integrators = spec.integrators,
                                                    .objects = std::move(objects)});
  return run_stability(in, spec, nullptr);
}

TEST(Stability, SpringChainLimitsMatchLinearTheory) {
  ASSERT_NEAR(kOmegaMax, 1.979643, 1e-6);
  StabilitySpec spec;
  spec.model = "spring_chain";
  spec.integrators = {"symplectic_euler", "velocity_verlet", "rk4", "euler", "backward_euler"};
  const StabilityResult r = run_stability(spec, nullptr);
  // Symplectic Euler and Verlet: stable for hω <= 2; rk4: hω <= 2√2 (imaginary-axis limit).
  for (const char* name : {"symplectic_euler", "velocity_verlet"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(r, name);
    EXPECT_EQ(row.status, "ok");
    ASSERT_TRUE(row.h_measured);
    EXPECT_NEAR(*row.h_measured / (2.0 / kOmegaMax), 1.0, 0.02);
    ASSERT_TRUE(row.h_predicted);
    EXPECT_NEAR(*row.h_predicted, 2.0 / kOmegaMax, 1e-8);
  }
  const auto& rk4 = row_of(r, "rk4");
  EXPECT_EQ(rk4.status, "ok");
  ASSERT_TRUE(rk4.h_measured);
  EXPECT_NEAR(*rk4.h_measured / (2.0 * std::sqrt(2.0) / kOmegaMax), 1.0, 0.02);
  // Explicit Euler has |R(iy)| > 1 for every y > 0: no stable step on an undamped chain, with a
  // measured growth per period above 1.
  const auto& euler = row_of(r, "euler");
  EXPECT_EQ(euler.status, "unstable_for_all_h");
  EXPECT_FALSE(euler.h_measured);
  ASSERT_TRUE(euler.growth_per_period);
  EXPECT_GT(*euler.growth_per_period, 1.0);
  // Backward Euler is A-stable: no instability up to the largest step tried.
  const auto& be = row_of(r, "backward_euler");
  EXPECT_EQ(be.status, "stable_up_to");
  EXPECT_TRUE(be.predicted_unbounded);

  const Table t = stability_table(r);
  EXPECT_EQ(t.columns,
            (std::vector<std::string>{"model", "integrator", "param", "value", "h_max_measured",
                                      "h_max_predicted", "ratio", "status", "limit_kind",
                                      "newton_iters", "newton_conv_failures", "error_test_failures",
                                      "linear_setups", "linear_iters", "fe_evals", "fi_evals"}));
  // Counters of the largest stable run: backward Euler on a linear chain takes one Newton
  // update per step at least (the run has >= min_steps = 200 steps); euler none (no row).
  ASSERT_TRUE(be.counters);
  EXPECT_GE(be.counters->newton_iters, 200);
  EXPECT_FALSE(euler.counters);
  ASSERT_TRUE(rk4.counters);
  EXPECT_EQ(rk4.counters->newton_iters, 0);
}

TEST(Stability, ImaginaryLimitZeroIsPredictedUnstableForAllH) {
  // cash_karp and rkf45 have |R(iy)|² − 1 = c·y⁶ + ... with c > 0 (1/3600 and 5/936, see
  // tests/core/test_linear_stability.cpp): on the undamped chain no step is stable, predicted
  // (h_max_predicted 0) and measured alike; the trapezoidal rule is A-stable.
  StabilitySpec spec;
  spec.model = "spring_chain";
  spec.integrators = {"cash_karp", "rkf45", "trapezoidal"};
  const StabilityResult r = run_stability(spec, nullptr);
  for (const char* name : {"cash_karp", "rkf45"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(r, name);
    EXPECT_EQ(row.status, "unstable_for_all_h");
    ASSERT_TRUE(row.h_predicted);
    EXPECT_EQ(*row.h_predicted, 0.0);
  }
  EXPECT_EQ(row_of(r, "trapezoidal").status, "stable_up_to");
  EXPECT_TRUE(row_of(r, "trapezoidal").predicted_unbounded);
}

// A user's stiff nonlinear scalar problem y' = −k y³ (k = 1000, y0 = 1): its solution decays
// for every method that is stable on it, but Newton for backward Euler / the trapezoidal rule
// on z + c·h·k z³ = rhs starting from z = y converges only linearly (factor about 2/3 per update)
// until z is near the root (y/(chk))^(1/3): with hk in the thousands that takes more than the
// default 10 iterations, so large steps end in newton_failed, not in growth (measured:
// backward Euler fails at h ≈ 1.41, hk ≈ 1400; with newton_max_iter = 200 it runs up to the cap).
class CubicDecay final : public OdeSystem {
 public:
  std::string name() const override { return "cubic_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -1000.0 * y[0] * y[0] * y[0]; }
  bool has_jacobian() const override { return true; }
  void eval_jacobian(double, CVecRef y, SparseMat& jac) const override {
    jac.resize(1, 1);
    jac.coeffRef(0, 0) = -3000.0 * y[0] * y[0];
  }
};

TEST(Stability, NewtonFailureIsSolverLimitNotInstability) {
  StabilitySpec spec;
  spec.integrators = {"backward_euler", "trapezoidal"};
  spec.h_cap_factor = 1e5;  // steps up to 1e5 · 2/ω, ω = 3k·y0² = 3000: hk up to ~7e4
  spec.periods = 50;
  const StabilityResult r =
      run_on_objects(spec, StudyObjects{[] { return std::make_unique<CubicDecay>(); }, {}});
  for (const char* name : {"backward_euler", "trapezoidal"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(r, name);
    // A-stable (predicted unbounded): the row is solver_limit, never ok.
    EXPECT_TRUE(row.predicted_unbounded);
    EXPECT_EQ(row.status, "solver_limit") << row.message;
    EXPECT_NE(row.message.find("newton_failed at h = "), std::string::npos) << row.message;
    ASSERT_TRUE(row.h_measured) << row.message;
    ASSERT_TRUE(row.counters);
    EXPECT_GT(row.counters->newton_iters, 0);
  }
  // The same method with enough Newton iterations runs at the step where the default failed: it
  // was the solver, not the method's stability.
  const double h_fail = *row_of(r, "backward_euler").h_measured * (1.0 + 2.0 * spec.rel_tol);
  StabilitySpec more = spec;
  more.integrators = {"backward_euler"};
  more.params.set("newton_max_iter", "200");
  const StabilityResult r2 =
      run_on_objects(more, StudyObjects{[] { return std::make_unique<CubicDecay>(); }, {}});
  const auto& row2 = row_of(r2, "backward_euler");
  ASSERT_TRUE(row2.h_measured);
  EXPECT_GT(*row2.h_measured, h_fail);
}

TEST(Stability, SweepOverSpringStiffnessHasSlopeMinusOneHalf) {
  // ω_max ∝ √k, so h_max ∝ k^(-1/2) for a method with a finite imaginary-axis interval.
  StabilitySpec spec;
  spec.model = "spring_chain";
  spec.integrators = {"symplectic_euler"};
  parse_sweep("k=1:1000:4", spec.sweep_param, spec.sweep_values);
  const StabilityResult r = run_stability(spec, nullptr);
  ASSERT_EQ(r.rows.size(), 4u);
  ASSERT_EQ(r.fits.size(), 1u);
  EXPECT_EQ(r.fits[0].points, 4);
  ASSERT_TRUE(r.fits[0].measured_slope);
  EXPECT_NEAR(*r.fits[0].measured_slope, -0.5, 0.05);
  ASSERT_TRUE(r.fits[0].predicted_slope);
  EXPECT_NEAR(*r.fits[0].predicted_slope, -0.5, 1e-6);
}

TEST(Stability, DecaySweepOverLambdaHasSlopeMinusOne) {
  // Prothero–Robinson y' = λ(y − φ) + φ': explicit Euler is stable for h|λ| <= 2 (real axis).
  StabilitySpec spec;
  spec.model = "prothero_robinson";
  spec.integrators = {"euler"};
  parse_sweep("lambda=-10,-100,-1000", spec.sweep_param, spec.sweep_values);
  const StabilityResult r = run_stability(spec, nullptr);
  for (const auto& row : r.rows) {
    ASSERT_EQ(row.status, "ok");
    EXPECT_NEAR(*row.h_measured * std::abs(row.value) / 2.0, 1.0, 0.02);
  }
  ASSERT_TRUE(r.fits.at(0).measured_slope);
  EXPECT_NEAR(*r.fits[0].measured_slope, -1.0, 0.02);
}

TEST(Stability, SweepParser) {
  std::string name;
  std::vector<double> v;
  parse_sweep("k=1:1000:4", name, v);
  EXPECT_EQ(name, "k");
  ASSERT_EQ(v.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(v[static_cast<std::size_t>(i)], std::pow(10.0, i), 1e-9);
  parse_sweep("lambda=-1:-100:3", name, v);
  EXPECT_NEAR(v[1], -10.0, 1e-12);
  parse_sweep("k=2,5,9", name, v);
  EXPECT_EQ(v, (std::vector<double>{2, 5, 9}));
  for (const char* bad :
       {"k", "k=", "=1,2", "k=1:10", "k=0:10:3", "k=-1:10:3", "k=1,x", "k=1:10:1", "k=1,,2"})
    EXPECT_THROW(parse_sweep(bad, name, v), BadInput) << bad;
}

TEST(Stability, LogLogSlope) {
  // y = 3 x^(-1/2) exactly.
  const std::vector<double> x = {1, 10, 100}, y = {3, 3 / std::sqrt(10.0), 0.3};
  EXPECT_NEAR(*loglog_slope(x, y), -0.5, 1e-12);
  EXPECT_FALSE(loglog_slope({1}, {1}));
}

// A cloth under gravity: its energy's zero is arbitrary (the potential -m g.x is zero at x = 0,
// the cloth's initial height), so `auto` judges growth by the norm alone and says why. Before,
// symplectic Euler's bounded O(h) energy error, measured against the 8x8 cloth's small initial
// spring energy, read as growth and the row said unstable_for_all_h (Verlet: a ratio of 0.74).
// The expected limit is linear theory (hω <= 2 for both methods on the imaginary axis) with the
// stiffest state the hanging cloth passes through, not the initial one: ω_max along a trajectory
// (an independent computation, too slow for a unit test, so done once: rk4 at hω0 = 0.1 from the
// initial state, the model's stiffness() every 5 steps over the study's 500 periods) reached 78.2
// against ω0 = 70.7, which puts the limit at 0.904 of the prediction from ω0 (the table's
// h_max_predicted). Measured: 0.866 for both, 0.958 of that bound; the rest is stiffer states
// between the samples and the nonlinear terms.
TEST(Stability, ClothUnderGravityIsJudgedByTheNorm) {
  StabilitySpec spec;
  spec.model = "cloth";
  spec.params = Params::from_assignments({"n=8"});
  spec.integrators = {"symplectic_euler", "velocity_verlet"};
  const StabilityResult r = run_stability(spec, nullptr);
  EXPECT_EQ(r.criterion, "norm");
  EXPECT_NE(r.criterion_note.find("arbitrary"), std::string::npos) << r.criterion_note;
  for (const char* name : {"symplectic_euler", "velocity_verlet"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(r, name);
    ASSERT_EQ(row.status, "ok") << row.message;
    ASSERT_TRUE(row.h_measured && row.h_predicted);
    const double ratio = *row.h_measured / *row.h_predicted;
    EXPECT_LT(ratio, 0.904 * 1.02);  // the bound from ω_max, within the bisection's tolerance
    EXPECT_GT(ratio, 0.8);
  }
  // --criterion energy on this model is refused before anything runs.
  spec.criterion = "energy";
  EXPECT_THROW(run_stability(spec, nullptr), BadInput);
  // So is a sweep with one such value among others (gravity = 0 first).
  spec.sweep_param = "gravity";
  spec.sweep_values = {0.0, 1.0};
  EXPECT_THROW(run_stability(spec, nullptr), BadInput);
}

TEST(Stability, BadSpecIsRefused) {
  StabilitySpec spec;
  spec.model = "spring_chain";
  spec.integrators = {"rk4"};
  spec.rel_tol = 0;
  EXPECT_THROW(spec.validate(), BadInput);
  spec.rel_tol = 1e-3;
  spec.ray = "diagonal";
  EXPECT_THROW(spec.validate(), BadInput);
}

// A method predicted stable for every step (A-stable on the spectrum) is not searched: one run
// at the largest step, h_cap = h_cap_factor × 2/ω, is the whole row, stable_up_to h_cap. On
// dahlquist (λ = −1: ω = 1, 2/ω = 2) h_cap = 1000 × 2 = 2000. With probe_unbounded the method is
// searched like any other: doubling from 2/ω = 2 up to h_cap takes 1 + ceil(log2 1000) = 11 runs
// (2, 4, ..., 1024, then 2000), with the same answer. rk4 has a finite prediction and is searched
// either way: its real-axis limit is the root 2.785294 of |R(−x)| = 1 (Hairer–Wanner II, §IV.2).
TEST(Stability, PredictedUnboundedIsCheckedAtTheLargestStepOnly) {
  StabilitySpec spec;
  spec.model = "dahlquist";
  spec.integrators = {"backward_euler", "trapezoidal", "rk4"};
  const StabilityResult r = run_stability(spec, nullptr);
  for (const char* name : {"backward_euler", "trapezoidal"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(r, name);
    EXPECT_TRUE(row.predicted_unbounded);
    EXPECT_EQ(row.status, "stable_up_to") << row.message;
    EXPECT_EQ(limit_kind(row), "stable_up_to");
    EXPECT_TRUE(row.checked_at_cap);
    EXPECT_EQ(row.probes, 1);
    EXPECT_DOUBLE_EQ(row.h_cap, 2000.0);
    ASSERT_TRUE(row.h_measured);
    EXPECT_DOUBLE_EQ(*row.h_measured, 2000.0);
    ASSERT_TRUE(
        row.counters);  // of the run at h_cap: 200 steps (min_steps), one Newton update each
    EXPECT_GE(row.counters->newton_iters, 200);
  }
  const auto& rk4 = row_of(r, "rk4");
  EXPECT_EQ(rk4.status, "ok");
  EXPECT_EQ(limit_kind(rk4), "measured");
  EXPECT_FALSE(rk4.checked_at_cap);
  ASSERT_TRUE(rk4.h_measured);
  EXPECT_NEAR(*rk4.h_measured / 2.785294, 1.0, 0.01);

  spec.probe_unbounded = true;
  const StabilityResult p = run_stability(spec, nullptr);
  for (const char* name : {"backward_euler", "trapezoidal"}) {
    SCOPED_TRACE(name);
    const auto& row = row_of(p, name);
    EXPECT_EQ(row.status, "stable_up_to") << row.message;
    EXPECT_FALSE(row.checked_at_cap);
    EXPECT_EQ(row.probes, 11);
    ASSERT_TRUE(row.h_measured);
    EXPECT_DOUBLE_EQ(*row.h_measured, 2000.0);
  }
  // The search of a method with a finite prediction does not depend on the option.
  ASSERT_TRUE(row_of(p, "rk4").h_measured);
  EXPECT_EQ(*row_of(p, "rk4").h_measured, *rk4.h_measured);
  EXPECT_EQ(row_of(p, "rk4").probes, rk4.probes);
}

// An integrator whose stability data say A-stable (backward Euler's R(z) = 1/(1 − z)) but whose
// steps are explicit Euler's: the run at the largest step blows up, contradicting the prediction.
// The row is not stable_up_to: the search continues downward from h_cap and finds explicit
// Euler's limit on y' = −y, h = 2 (|1 − h| <= 1), and the message says the prediction was
// contradicted.
class MislabelledEuler final : public Integrator {
 public:
  MislabelledEuler() : Integrator(info_of()) {}
  void reset(const OdeSystem& sys, double, CVecRef) override { k_.resize(sys.dimension()); }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) override {
    sys.rhs(t, y, k_);
    y += h * k_;
    return Status::ok;
  }
  std::optional<LinearStability> linear_stability() const override {
    ButcherTableau be;
    be.a = Mat::Ones(1, 1);
    be.b = Vec::Ones(1);
    be.c = Vec::Ones(1);
    be.order = 1;
    return tableau_stability(be);
  }

 private:
  static MethodInfo info_of() {
    MethodInfo i;
    i.name = "mislabelled_euler";
    i.description = "explicit Euler claiming backward Euler's stability";
    i.family = Family::explicit_rk;
    i.order = 1;
    i.stages = 1;
    return i;
  }
  Vec k_;
};

TEST(Stability, InstabilityAtTheLargestStepContradictsThePrediction) {
  StabilitySpec spec;
  spec.model = "dahlquist";
  const StabilityResult r = run_on_objects(
      spec, StudyObjects{nullptr, {[] { return std::make_unique<MislabelledEuler>(); }}});
  const auto& row = row_of(r, "mislabelled_euler");
  EXPECT_TRUE(row.predicted_unbounded);
  EXPECT_TRUE(row.checked_at_cap);
  EXPECT_EQ(row.status, "ok") << row.message;
  EXPECT_EQ(limit_kind(row), "measured");
  EXPECT_NE(row.message.find("contradicts the prediction"), std::string::npos) << row.message;
  ASSERT_TRUE(row.h_measured);
  EXPECT_NEAR(*row.h_measured / 2.0, 1.0, 0.01);
}

// heat_2d with ν = 1e308: the spectral radius 8ν/Δx² overflows to inf (n = 32, above the dense
// limit: the stiffness() estimate; n = 4: inf entries in the analytic Jacobian, whose
// eigensolver output is meaningless). That is no spectrum, not "stable for every step": without
// --horizon the study is refused naming the cause; with one, no row has a prediction and each
// says why.
TEST(Stability, NonFiniteSpectrumIsNoPrediction) {
  StabilitySpec spec;
  spec.model = "heat_2d";
  spec.integrators = {"rk4", "backward_euler"};
  for (const char* n : {"n=32", "n=4"}) {
    SCOPED_TRACE(n);
    spec.params = Params::from_assignments({"nu=1e308", n});
    try {
      run_stability(spec, nullptr);
      ADD_FAILURE() << "not refused";
    } catch (const BadInput& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("not finite"), std::string::npos) << what;
      EXPECT_NE(what.find("--horizon"), std::string::npos) << what;
    }
  }
  spec.horizon = 1e-3;
  const StabilityResult r = run_stability(spec, nullptr);
  EXPECT_EQ(r.spectrum_source.rfind("none: not finite", 0), 0u) << r.spectrum_source;
  const Table t = stability_table(r);
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    SCOPED_TRACE(r.rows[k].integrator);
    EXPECT_FALSE(r.rows[k].predicted_unbounded);
    EXPECT_FALSE(r.rows[k].h_predicted);
    EXPECT_NE(r.rows[k].no_prediction.find("not finite"), std::string::npos);
    EXPECT_EQ(t.rows[k][5], "");  // h_max_predicted: empty, not "inf"
  }
}

// Ralston's method (methods/ralston.toml) written to a scratch folder under another name.
std::filesystem::path write_ralston_file(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("stiffbench_stability_methods_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / (name + ".toml");
  std::ofstream(path) << "name = \"" << name << "\"\n"
                      << "kind = \"explicit_rk\"\nclass = \"explicit RK\"\norder = 2\n"
                      << "stage_order = 1\ndescription = \"Ralston's method under another name\"\n"
                      << "A = [[0, 0], [\"2/3\", 0]]\nb = [\"1/4\", \"3/4\"]\n";
  return path;
}

// The study on inputs resolved once: a method file given by its path and a variant of a built-in
// method run under their labels, the variant with its fixed parameter.
TEST(Stability, RunsFromResolvedInputsWithAMethodFileAndAVariant) {
  const auto file = write_ralston_file("stability_ralston");
  StudyTarget t;
  t.model = "dahlquist";
  t.integrators = {file.string(), "backward_euler{newton_max_iter=30}"};
  const StudyInputs in = resolve_inputs(t);
  EXPECT_EQ(in.integrators,
            (std::vector<std::string>{"stability_ralston", "backward_euler{newton_max_iter=30}"}));
  const StabilityResult r = run_stability(in, StabilitySpec{}, nullptr);
  ASSERT_EQ(r.rows.size(), 2u);
  EXPECT_EQ(r.rows[0].integrator, "stability_ralston");
  EXPECT_EQ(r.rows[1].integrator, "backward_euler{newton_max_iter=30}");
  EXPECT_EQ(r.rows[0].model, "dahlquist");
  // Ralston on the real axis: stable for h|λ| <= 2, measured by bisection; backward Euler:
  // predicted stable for every step and stable at the largest one.
  EXPECT_EQ(r.rows[0].status, "ok") << r.rows[0].message;
  ASSERT_TRUE(r.rows[0].h_predicted);
  ASSERT_TRUE(r.rows[0].h_measured);
  EXPECT_NEAR(*r.rows[0].h_measured / *r.rows[0].h_predicted, 1.0, 0.01);
  EXPECT_TRUE(r.rows[1].predicted_unbounded);
  EXPECT_EQ(r.rows[1].status, "stable_up_to") << r.rows[1].message;
  std::filesystem::remove_all(file.parent_path());
}

}  // namespace
}  // namespace stiffbench
