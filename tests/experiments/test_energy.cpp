// The energy-drift experiment (experiments/studies/energy.hpp): closed forms on the harmonic
// oscillator, the Kepler acceptance numbers, the sampler's max-since-last rows, failures and
// bad input, the output files (the command line: tests/cli/test_energy_cli.cpp).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include <unistd.h>

#include "core/driver.hpp"
#include "experiments/studies/energy.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

using testing_support::make;
using testing_support::model;

EnergySpec spec_for(const std::string& m, const std::vector<std::string>& params,
                    const std::vector<std::string>& integrators, double h, double t_end,
                    long samples = 100) {
  EnergySpec s;
  s.model = m;
  s.params = Params::from_assignments(params);
  s.integrators = integrators;
  s.h = h;
  s.t_end = t_end;
  s.samples = samples;
  return s;
}

const EnergyRun& run_of(const EnergyResult& r, const std::string& name) {
  for (const auto& run : r.runs)
    if (run.integrator == name) return run;
  throw std::logic_error("no run of " + name);
}

std::string first_line(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

// The acceptance numbers: Kepler e = 0.5, h = 0.01, 1000 orbits (T = 2π).
// Symplectic methods keep a modified energy exactly up to exponentially small terms, so their
// energy error is a bounded oscillation reached in the first orbit: growth ≈ 1. rk4 is not
// symplectic: its error grows linearly (3.0e-6 after 1000 orbits, 3.1e-7 after 100, so growth
// ≈ 10). Explicit Euler gains energy every step: E rises from -0.5 towards 0, so the relative
// error passes 0.5 long before 1000 orbits (the orbit spirals outward).
TEST(EnergyKepler, SymplecticMethodsBoundedRk4DriftsEulerFails) {
  const double t_end = 1000 * 2 * std::numbers::pi;
  const EnergyResult r =
      run_energy(spec_for("kepler", {"e=0.5"},
                          {"euler", "rk4", "velocity_verlet", "symplectic_euler"}, 0.01, t_end),
                 nullptr);
  ASSERT_EQ(r.runs.size(), 4u);
  for (const char* name : {"velocity_verlet", "symplectic_euler"}) {
    const EnergyRun& run = run_of(r, name);
    EXPECT_EQ(run.stats.status, Status::ok) << name;
    ASSERT_TRUE(run.growth_ratio) << name;
    EXPECT_LT(*run.growth_ratio, 1.1) << name;
    EXPECT_GE(*run.growth_ratio, 1.0) << name;
  }
  const EnergyRun& rk4 = run_of(r, "rk4");
  ASSERT_TRUE(rk4.growth_ratio);
  EXPECT_GT(*rk4.growth_ratio, 5.0);
  // Linear drift: final ≈ max, and the slope times the span gives the final error.
  EXPECT_NEAR(rk4.final_rel_error / rk4.max_rel_error, 1.0, 0.05);
  EXPECT_NEAR(rk4.drift_rate * t_end / rk4.final_rel_error, 1.0, 0.15);
  EXPECT_GT(run_of(r, "euler").max_rel_error, 0.5);
  // Kepler also conserves angular momentum; velocity Verlet conserves it exactly (a central
  // force gives kicks parallel to q), so its error is round-off only.
  const auto& vv = run_of(r, "velocity_verlet").other_max_rel_error;
  ASSERT_EQ(vv.size(), 1u);
  EXPECT_EQ(vv[0].first, "angular_momentum");
  EXPECT_LT(vv[0].second, 1e-9);
}

// Explicit Euler on x'' = -x (m = k = 1): (x, v) ← (x + h v, v - h x) multiplies x² + v² by
// exactly 1 + h² per step, so e_k = (1 + h²)^k - 1 at t_k = k h: monotone (max = final), growth
// e_N / e_{N/10}, and the least-squares slope computed here directly from the closed form.
TEST(EnergyOscillator, ExplicitEulerMatchesClosedForm) {
  const double h = 0.01;
  const long n = 2000;
  const EnergyResult r = run_energy(
      spec_for("harmonic_oscillator", {"x0=1", "v0=0"}, {"euler"}, h, h * n, 50), nullptr);
  const EnergyRun& run = r.runs.at(0);
  ASSERT_EQ(run.stats.status, Status::ok);
  ASSERT_EQ(run.steps, n);
  auto e = [&](long k) { return std::pow(1 + h * h, static_cast<double>(k)) - 1; };
  EXPECT_NEAR(run.final_rel_error, e(n), 1e-12 * e(n) * n);
  EXPECT_DOUBLE_EQ(run.max_rel_error, run.final_rel_error);
  ASSERT_TRUE(run.growth_ratio);
  EXPECT_NEAR(*run.growth_ratio, e(n) / e(n / 10), 1e-9 * *run.growth_ratio);
  double st = 0, se = 0, stt = 0, ste = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) * h;
    st += t;
    se += e(k);
    stt += t * t;
    ste += t * e(k);
  }
  const double m = static_cast<double>(n + 1);
  const double slope = (m * ste - st * se) / (m * stt - st * st);
  EXPECT_NEAR(run.drift_rate, slope, 1e-8 * slope);
  EXPECT_EQ(r.other_invariants.size(), 0u);
}

// The final change keeps its sign: on x'' = -x explicit Euler multiplies x² + v² by 1 + h² per
// step and backward Euler by 1/(1 + h²) (|R(ih)|² of R = 1 + z and R = 1/(1 - z)), so after N
// steps the energy changed by (1 + h²)^N - 1 > 0 (a gain) and (1 + h²)^(-N) - 1 < 0 (a loss);
// the unsigned final error is the absolute value of each. energy.md writes the sign in words.
TEST(EnergyOscillator, FinalChangeTellsAGainFromALoss) {
  const double h = 0.05;
  const long n = 400;
  EnergySpec spec =
      spec_for("harmonic_oscillator", {"x0=1", "v0=0"}, {"euler", "backward_euler"}, h, h * n, 50);
  const EnergyResult r = run_energy(spec, nullptr);
  const double gain = std::pow(1 + h * h, static_cast<double>(n)) - 1;
  const double loss = std::pow(1 + h * h, -static_cast<double>(n)) - 1;
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_NEAR(r.runs[0].final_change, gain, 1e-11 * gain * n);
  EXPECT_NEAR(r.runs[1].final_change, loss, 1e-11 * std::abs(loss) * n);
  EXPECT_DOUBLE_EQ(r.runs[0].final_rel_error, std::abs(r.runs[0].final_change));
  EXPECT_DOUBLE_EQ(r.runs[1].final_rel_error, std::abs(r.runs[1].final_change));
  const Table t = energy_markdown_table(r);
  const auto col = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), "final change") - t.columns.begin());
  ASSERT_LT(col, t.columns.size());
  EXPECT_NE(t.rows[0][col].find("(gain)"), std::string::npos) << t.rows[0][col];
  EXPECT_NE(t.rows[1][col].find("(loss)"), std::string::npos) << t.rows[1][col];
}

// Symplectic Euler (velocity first) on x'' = -x conserves the quadratic form
// Q = x² + v² + h x v exactly (det of the step map is 1 and Q is its invariant), an ellipse
// whose axes have Q-eigenvalues 1 ± h/2. From (1, 0), Q = 1, so E = ½(x² + v²) sweeps
// [½/(1 + h/2), ½/(1 - h/2)]: the largest relative error is 1/(1 - h/2) - 1 = h/(2 - h), and it
// is already reached in the first tenth (growth ≈ 1). Over 100 periods the step angle (≈ h)
// is not commensurate with 2π, so the visited points come within ~1e-3 rad of the axis.
TEST(EnergyOscillator, SymplecticEulerBandMatchesModifiedEnergy) {
  const double h = 0.1;
  const EnergyResult r = run_energy(spec_for("harmonic_oscillator", {"x0=1", "v0=0"},
                                             {"symplectic_euler"}, h, 100 * 2 * std::numbers::pi),
                                    nullptr);
  const EnergyRun& run = r.runs.at(0);
  ASSERT_EQ(run.stats.status, Status::ok);
  const double band = h / (2 - h);
  EXPECT_NEAR(run.max_rel_error, band, 1e-4 * band);
  ASSERT_TRUE(run.growth_ratio);
  EXPECT_GE(*run.growth_ratio, 1.0);
  EXPECT_LT(*run.growth_ratio, 1.001);
  // No secular drift: the slope over 100 periods is a small fraction of band / t_end.
  EXPECT_LT(std::abs(run.drift_rate) * 100 * 2 * std::numbers::pi, 0.05 * band);
}

// The sampler: rows every ceil(N/samples) steps plus the first and the last; the largest
// max_rel_error_since_last equals the maximum over every step, computed here independently by a
// plain driver run that evaluates the energy at each step. On an eccentric orbit (e = 0.9) the
// symplectic Euler error peaks at each pericentre passage only, between sample times that
// avoid pericentre (3.3 periods in 5 samples: every 0.66 T), so the sampled values themselves
// miss most of the peak while max_rel_error_since_last keeps it.
TEST(EnergySampler, MaxSinceLastCarriesEveryPeak) {
  const double period = 2 * std::numbers::pi;
  const double h = 0.001, t_end = 3.3 * period;
  const long samples = 5;
  const EnergyResult r =
      run_energy(spec_for("kepler", {"e=0.9"}, {"symplectic_euler"}, h, t_end, samples), nullptr);
  const EnergyRun& run = r.runs.at(0);
  ASSERT_EQ(run.stats.status, Status::ok);

  const long n = run.steps;
  const long stride = (n + samples - 1) / samples;
  const long expected_rows = n / stride + 1 + (n % stride != 0 ? 1 : 0);
  ASSERT_EQ(static_cast<long>(run.samples.size()), expected_rows);
  EXPECT_EQ(run.samples.front().t, 0.0);
  EXPECT_EQ(run.samples.front().max_rel_error_since_last, 0.0);
  EXPECT_EQ(run.samples.back().t, t_end);

  double max_since = 0, max_sampled = 0;
  for (const auto& s : run.samples) {
    EXPECT_GE(s.max_rel_error_since_last, s.rel_error);
    max_since = std::max(max_since, s.max_rel_error_since_last);
    max_sampled = std::max(max_sampled, s.rel_error);
  }
  EXPECT_EQ(max_since, run.max_rel_error);

  // Independent maximum over every step.
  const auto sys = model("kepler", {"e=0.9"});
  const auto integ = make("symplectic_euler");
  const Invariant energy = sys->invariants().at(0);
  const double e0 = energy.value(0, sys->initial_state());
  double direct = 0;
  FixedStepOptions opt;
  opt.h = h;
  opt.t_end = t_end;
  opt.outputs = n;
  run_fixed_step(*sys, *integ, opt, [&](double t, CVecRef y) {
    direct = std::max(direct, std::abs(energy.value(t, y) - e0) / std::abs(e0));
  });
  EXPECT_DOUBLE_EQ(run.max_rel_error, direct);
  EXPECT_LT(max_sampled, 0.5 * run.max_rel_error);
}

// A blow-up ends that integrator's rows with status unstable; the others still run. Explicit
// Euler at hω = 10 (k = 100·100, h = 0.1) multiplies the energy by 1 + h²ω² = 101 per step, so
// the state passes the driver's bound 1e10·max(1, ‖y0‖) within about ten steps and the rows stop
// at the last good step k with error 101^k - 1. Backward Euler divides the energy by 101 per
// step: the error tends to 1 and the run is fine.
TEST(EnergyFailures, BlowUpEndsOneIntegratorOnly) {
  const double h = 0.1;
  const EnergyResult r = run_energy(spec_for("harmonic_oscillator", {"k=10000", "x0=1", "v0=0"},
                                             {"euler", "backward_euler"}, h, 10.0, 20),
                                    nullptr);
  const EnergyRun& euler = run_of(r, "euler");
  EXPECT_EQ(euler.stats.status, Status::unstable);
  EXPECT_LT(euler.t_reached, 1.5);
  const double k = std::round(euler.t_reached / h);
  EXPECT_NEAR(euler.final_rel_error, std::pow(101.0, k) - 1, 1e-12 * std::pow(101.0, k));
  EXPECT_EQ(euler.samples.back().t, euler.t_reached);
  const EnergyRun& be = run_of(r, "backward_euler");
  EXPECT_EQ(be.stats.status, Status::ok);
  EXPECT_NEAR(be.final_rel_error, 1.0, 1e-12);
  EXPECT_EQ(be.samples.back().t, 10.0);
  // The summary table says which one failed.
  const Table t = energy_summary_table(r);
  const auto status = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), "status") - t.columns.begin());
  ASSERT_LT(status, t.columns.size());
  EXPECT_EQ(t.rows.at(0).at(status), "unstable");
  EXPECT_EQ(t.rows.at(1).at(status), "ok");
}

// energy_summary.csv carries each run's counters after the original columns (a contract:
// docs/formats.md). An explicit method solves no equations, so its five solver counters are 0;
// backward Euler solves one nonlinear system per step, so it makes at least one Newton
// iteration per step and at least one matrix set-up, and each iteration solves one linear
// system (the counters are the run's SolveStats, printed as they are).
TEST(EnergyOutputs, SummaryCarriesTheCounters) {
  const EnergyResult r = run_energy(spec_for("harmonic_oscillator", {"k=4", "x0=1", "v0=0"},
                                             {"rk4", "backward_euler"}, 0.01, 1.0, 10),
                                    nullptr);
  const Table t = energy_summary_table(r);
  const std::vector<std::string> before = {
      "model",  "integrator", "h",     "t_end",   "max_rel_error", "final_rel_error", "drift_rate",
      "growth", "status",     "steps", "f_evals", "jac_evals",     "lin_solves"};
  std::vector<std::string> expected = before;
  for (const auto& c : SolveStats::counter_names()) expected.push_back(c);
  ASSERT_EQ(t.columns, expected);
  const auto value = [&](std::size_t row, const std::string& col) {
    const auto c = static_cast<std::size_t>(std::find(t.columns.begin(), t.columns.end(), col) -
                                            t.columns.begin());
    return std::stol(t.rows.at(row).at(c));
  };
  ASSERT_EQ(t.rows.size(), 2u);
  for (const auto& c : SolveStats::counter_names()) EXPECT_EQ(value(0, c), 0) << "rk4 " << c;
  EXPECT_EQ(value(0, "steps"), 100);
  EXPECT_EQ(value(0, "f_evals"), 400);  // four stages per step
  const SolveStats& be = run_of(r, "backward_euler").stats;
  EXPECT_EQ(value(1, "steps"), 100);
  EXPECT_GE(value(1, "newton_iters"), 100);
  EXPECT_GE(value(1, "linear_setups"), 1);
  EXPECT_EQ(value(1, "newton_iters"), be.newton_iters);
  EXPECT_EQ(value(1, "linear_setups"), be.linear_setups);
  EXPECT_EQ(value(1, "lin_solves"), be.lin_solves);
  EXPECT_EQ(value(1, "newton_conv_failures"), 0);
  EXPECT_EQ(value(1, "error_test_failures"), 0);  // fixed steps: no error test
}

TEST(EnergyFailures, BadInputNamesWhatIsWrong) {
  try {
    run_energy(spec_for("dahlquist", {}, {"rk4"}, 0.1, 1.0), nullptr);
    FAIL() << "a model without invariants was accepted";
  } catch (const BadInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("dahlquist"), std::string::npos) << msg;
    EXPECT_NE(msg.find("none"), std::string::npos) << msg;
  }
  EnergySpec ang = spec_for("kepler", {}, {"rk4"}, 0.1, 1.0);
  ang.invariant = "momentum";
  try {
    run_energy(ang, nullptr);
    FAIL() << "an unknown invariant was accepted";
  } catch (const BadInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("energy, angular_momentum"), std::string::npos) << msg;
  }
  // velocity_verlet needs a velocity-independent acceleration (damped oscillator has not).
  EXPECT_THROW(
      run_energy(spec_for("harmonic_oscillator", {"gamma=0.1"}, {"velocity_verlet"}, 0.1, 1.0),
                 nullptr),
      BadInput);
  try {
    run_energy(spec_for("kepler", {}, {"rk4", "gsl_msbdf"}, 0.1, 1.0), nullptr);
    FAIL() << "an adaptive-only integrator was accepted";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("gsl_msbdf"), std::string::npos) << e.what();
  }
  EXPECT_THROW(run_energy(spec_for("kepler", {}, {"rk4"}, -0.1, 1.0), nullptr), BadInput);
  EXPECT_THROW(run_energy(spec_for("kepler", {}, {"rk4"}, 0.1, 1.0, 0), nullptr), BadInput);
  // Kepler has no suggested step and no literature end time.
  EXPECT_THROW(run_energy(spec_for("kepler", {}, {"rk4"}, std::nan(""), 1.0), nullptr), BadInput);
  EXPECT_THROW(run_energy(spec_for("kepler", {}, {"rk4"}, 0.1, std::nan("")), nullptr), BadInput);
}

// Angular momentum as the measured invariant: rk4 does not conserve it exactly, velocity
// Verlet does (to round-off), and energy then appears among the other invariants.
TEST(EnergyInvariants, OtherInvariantCanBeMeasured) {
  EnergySpec s = spec_for("kepler", {"e=0.5"}, {"rk4", "velocity_verlet"}, 0.01, 20.0);
  s.invariant = "angular_momentum";
  const EnergyResult r = run_energy(s, nullptr);
  ASSERT_EQ(r.other_invariants, std::vector<std::string>{"energy"});
  EXPECT_GT(run_of(r, "rk4").max_rel_error, 1e-12);
  EXPECT_LT(run_of(r, "velocity_verlet").max_rel_error, 1e-12);
}

// The inviscid SPH drop (no walls, no gravity) conserves total momentum and angular momentum,
// which start at zero up to the round-off of a symmetric sum (~1e-17; the oscillation
// v = A(x, -y) has L = -2A Σ m x y = 0 on the symmetric lattice): their errors are reported as
// absolute, and the pairwise antisymmetric, central SPH forces keep them at round-off level (a
// relative error against the round-off initial value would have been ~20).
TEST(EnergyInvariants, RoundOffZeroInvariantGetsAbsoluteError) {
  const EnergyResult r =
      run_energy(spec_for("sph_drop_2d", {}, {"velocity_verlet"}, 1e-3, 0.02), nullptr);
  ASSERT_EQ(r.other_invariants,
            (std::vector<std::string>{"momentum_x", "momentum_y", "angular_momentum"}));
  const EnergyRun& run = r.runs.at(0);
  ASSERT_EQ(run.stats.status, Status::ok);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_TRUE(invariant_error_is_absolute(r.other_initial_values[i])) << r.other_invariants[i];
    EXPECT_LT(run.other_max_rel_error[i].second, 1e-12) << r.other_invariants[i];
  }
  const Table t = energy_markdown_table(r);
  EXPECT_NE(std::find(t.columns.begin(), t.columns.end(), "max abs. error momentum_x"),
            t.columns.end());
}

// A cloth under gravity: the energy's zero is arbitrary (Invariant::arbitrary_zero: the potential
// -m g.x is zero at the initial height), so the study reports the absolute error |E(t) - E0|
// and says why. Checked against an independent run of the same steps through the driver, whose
// observer takes max |E(t) - E0| itself; relative to |E0| (the small initial spring energy) the
// same run would have read as a relative error of order 1.
TEST(EnergyInvariants, ArbitraryZeroGetsAbsoluteError) {
  const EnergyResult r =
      run_energy(spec_for("cloth", {"n=4"}, {"symplectic_euler"}, 5e-3, 2.0), nullptr);
  EXPECT_NE(r.arbitrary_zero.find("gravity"), std::string::npos) << r.arbitrary_zero;
  const EnergyRun& run = r.runs.at(0);
  ASSERT_EQ(run.stats.status, Status::ok);

  auto sys = testing_support::model("cloth", {"n=4"});
  auto integ = testing_support::make("symplectic_euler", {});
  const auto energy = sys->invariants().at(0);
  ASSERT_EQ(energy.name, "energy");
  const double e0 = energy.value(0.0, sys->initial_state());
  double max_abs = 0.0;
  run_fixed_step(*sys, *integ, {2.0, 5e-3, 1L << 40}, [&](double t, CVecRef y) {
    max_abs = std::max(max_abs, std::abs(energy.value(t, y) - e0));
  });
  EXPECT_DOUBLE_EQ(run.max_rel_error, max_abs);
  ASSERT_GT(std::abs(e0), kZeroInvariant);  // so the round-off rule is not what applies
  EXPECT_GT(max_abs / std::abs(e0), 0.1);   // what dividing by |E0| would have shown
  const Table t = energy_markdown_table(r);
  EXPECT_EQ(t.columns.at(3), "max abs. error");
}

TEST(EnergyOutputs, FilesFollowTheContract) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("stiffbench_energy_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const EnergySpec s = spec_for("kepler", {"e=0.5"}, {"rk4", "symplectic_euler"}, 0.05, 30.0, 10);
  const EnergyResult r = run_energy(s, nullptr);
  std::ostringstream err;
  write_energy_outputs(dir, s, r, PlotOptions{}, err);
  EXPECT_EQ(first_line(dir / "energy.csv"),
            "model,integrator,h,t,energy,rel_error,max_rel_error_since_last");
  EXPECT_EQ(first_line(dir / "energy_summary.csv"),
            "model,integrator,h,t_end,max_rel_error,final_rel_error,drift_rate,growth,status,"
            "steps,f_evals,jac_evals,lin_solves,newton_iters,newton_conv_failures,"
            "error_test_failures,linear_setups,linear_iters,fe_evals,fi_evals");
  EXPECT_EQ(first_line(dir / "energy.md"), "# Energy drift: kepler");
  std::ifstream md(dir / "energy.md");
  const std::string text((std::istreambuf_iterator<char>(md)), {});
  EXPECT_NE(text.find("max rel. error angular_momentum"), std::string::npos);
  std::ifstream js(dir / "energy.json");
  const auto meta = nlohmann::json::parse(js);
  EXPECT_EQ(meta.at("invariant"), "energy");
  EXPECT_DOUBLE_EQ(meta.at("initial_value").get<double>(), -0.5);  // -GM/(2a)
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stiffbench
