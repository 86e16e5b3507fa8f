// Adaptive references in convergence/local-error studies (--reference METHOD with
// --reference-rtol/--reference-atol), their cache in the output folder, and solve's output
// times (--times, --log-outputs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/output/output.hpp"
#include "experiments/studies/convergence.hpp"
#include "tests/cli_support.hpp"
#include "tests/experiments/method_file_copy.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

std::string heun_file(const std::string& name) {
  return testing_support::renamed_method_file("heun", name);
}

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) { return testing_support::fresh_dir("refcache", name); }

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream f(p);
  std::vector<std::string> out;
  for (std::string line; std::getline(f, line);) out.push_back(line);
  return out;
}

std::vector<std::vector<double>> csv_numbers(const fs::path& p) {
  std::vector<std::vector<double>> rows;
  const auto lines = lines_of(p);
  for (std::size_t i = 1; i < lines.size(); ++i) {  // line 0: the column header
    std::vector<double> row;
    std::stringstream ss(lines[i]);
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// The BadInput message of f(), or "" when it does not throw BadInput.
template <class F>
std::string bad_input_message(F f) {
  try {
    f();
  } catch (const BadInput& e) {
    return e.what();
  }
  return "";
}

// Van der Pol in the classical form with mu = 1 (not stiff): no exact solution.
ConvergenceSpec vdp_spec(const fs::path& dir) {
  ConvergenceSpec s;
  s.model = "van_der_pol";
  s.params = Params::from_assignments({"form=mu", "mu=1"});
  s.integrators = {"rk4", "backward_euler"};
  s.t_end = 1.0;
  s.h = 0.1;
  s.levels = 4;
  s.reference = "cvode_bdf";
  s.cache_dir = dir.string();
  return s;
}

// First run computes and writes DIR/reference/<hash>.csv; the second run reads it. Proof that
// the values really come from the file: a perturbed state written into it with a matching
// content line shifts the second run's errors by that perturbation. A file that does not hold
// what its content line records (one digit edited, cut inside its last number, rows missing) is
// never used: it is recomputed and rewritten.
TEST(ReferenceCache, WrittenOnceThenReusedAndVerified) {
  const fs::path dir = fresh_dir("reuse");
  ConvergenceSpec spec = vdp_spec(dir);
  const auto first = run_convergence(spec, nullptr);
  EXPECT_FALSE(first.reference_from_cache);
  ASSERT_FALSE(first.reference_cache.empty());
  const fs::path file = first.reference_cache;
  EXPECT_EQ(file.parent_path(), dir / "reference");
  ASSERT_TRUE(fs::exists(file));
  EXPECT_EQ(first.reference_description, "cvode_bdf adaptive, rtol = 1e-12, atol = 1e-14");

  // Header: the key (with model, parameters, reference, rtol, atol, t0 and times), a readable
  // line, the content line (row count and the FNV-1a hash of the lines below it), the columns
  // and one row at t_end.
  const auto lines = lines_of(file);
  ASSERT_EQ(lines.size(), 5u);
  for (const char* part : {"\"model\":\"van_der_pol\"", "\"mu\":\"1\"", "\"form\":\"mu\"",
                           "\"reference\":\"cvode_bdf\"", "\"rtol\":\"1e-12\"",
                           "\"atol\":\"1e-14\"", "\"t0\":\"0\"", "\"times\":[\"1\"]"})
    EXPECT_NE(lines[0].find(part), std::string::npos) << part << " in " << lines[0];
  const auto content = [](const std::string& data) {
    return "# content: 1 rows, fnv1a64 " + hex16(fnv1a64(data));
  };
  EXPECT_EQ(lines[2], content(lines[3] + "\n" + lines[4] + "\n"));
  EXPECT_EQ(lines[3], "t,y0,y1");
  EXPECT_EQ(lines[4].rfind("1,", 0), 0u);

  const auto mtime = fs::last_write_time(file);
  const auto second = run_convergence(spec, nullptr);
  EXPECT_TRUE(second.reference_from_cache);
  EXPECT_EQ(second.reference_cache, first.reference_cache);
  EXPECT_EQ(fs::last_write_time(file), mtime);
  ASSERT_EQ(second.rows.size(), first.rows.size());
  for (std::size_t i = 0; i < first.rows.size(); ++i)
    EXPECT_EQ(second.rows[i].error, first.rows[i].error);  // bit-identical reference

  // Shift y0(t_end) in the file by 1e-3 and record the new content: rk4's errors (< 1e-5)
  // become 1e-3 to within 1e-5.
  std::stringstream row(lines[4]);
  std::string t, y0, y1;
  std::getline(row, t, ',');
  std::getline(row, y0, ',');
  std::getline(row, y1, ',');
  char shifted[40];
  std::snprintf(shifted, sizeof shifted, "%.17g", std::stod(y0) + 1e-3);
  const std::string shifted_data = lines[3] + "\n" + t + "," + shifted + "," + y1 + "\n";
  const auto write = [&](const std::string& content_line, const std::string& data) {
    std::ofstream f(file, std::ios::trunc | std::ios::binary);
    f << lines[0] << "\n" << lines[1] << "\n" << content_line << "\n" << data;
  };
  write(content(shifted_data), shifted_data);
  const auto tampered = run_convergence(spec, nullptr);
  EXPECT_TRUE(tampered.reference_from_cache);
  for (const auto& r : tampered.rows)
    if (r.integrator == "rk4") {
      EXPECT_NEAR(r.error, 1e-3, 1e-5);
    }

  // The same edit without its content line, the file cut inside its last number, and the row
  // gone: each is detected, recomputed (the progress says why) and rewritten.
  const std::string original = lines[3] + "\n" + lines[4] + "\n";
  for (const std::string& data :
       {shifted_data, original.substr(0, original.size() - 4), lines[3] + "\n"}) {
    write(lines[2], data);
    std::ostringstream progress;
    const auto rewritten = run_convergence(spec, &progress);
    EXPECT_FALSE(rewritten.reference_from_cache) << data;
    EXPECT_NE(progress.str().find("truncated or edited; recomputing"), std::string::npos)
        << progress.str();
    const auto now = lines_of(file);  // line 1 also says how long the computation took
    ASSERT_EQ(now.size(), lines.size());
    for (std::size_t k : {0, 2, 3, 4}) EXPECT_EQ(now[k], lines[k]) << k;
    EXPECT_EQ(rewritten.rows.front().error, first.rows.front().error);
  }
  fs::remove_all(dir);
}

// Everything that changes the reference changes the file: rtol, atol, a model parameter, the
// reference method, t_end. Adding an integrator under study does not.
TEST(ReferenceCache, KeyFollowsTheReferenceSpec) {
  const fs::path dir = fresh_dir("key");
  ConvergenceSpec spec = vdp_spec(dir);
  spec.integrators = {"rk4"};
  spec.levels = 2;
  const auto base = run_convergence(spec, nullptr);
  std::set<std::string> files{base.reference_cache};

  auto changed = [&](ConvergenceSpec s) {
    const auto r = run_convergence(s, nullptr);
    EXPECT_FALSE(r.reference_from_cache);
    EXPECT_TRUE(files.insert(r.reference_cache).second) << r.reference_cache;
  };
  ConvergenceSpec s = spec;
  s.reference_rtol = 1e-11;
  changed(s);
  s = spec;
  s.reference_atol = 1e-15;
  changed(s);
  s = spec;
  s.params = Params::from_assignments({"form=mu", "mu=2"});
  changed(s);
  s = spec;
  s.reference = "arkode_dirk";
  changed(s);
  s = spec;
  s.t_end = 0.5;
  changed(s);

  s = spec;
  s.integrators = {"rk4", "heun"};
  s.levels = 3;  // the global study's reference depends on t_end only
  const auto reused = run_convergence(s, nullptr);
  EXPECT_TRUE(reused.reference_from_cache);
  EXPECT_EQ(reused.reference_cache, base.reference_cache);
  // The explicit default tolerances are the same reference.
  s = spec;
  s.reference_rtol = 1e-12;
  s.reference_atol = 1e-14;
  EXPECT_TRUE(run_convergence(s, nullptr).reference_from_cache);
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "reference")) ++n;
  // Six references, each beside its check run (10 times tighter, its own key: the floor
  // check of the reference's accuracy).
  EXPECT_EQ(n, 12u);
  fs::remove_all(dir);
}

// Global orders on problems without an exact solution against cvode_bdf at rtol 1e-12 (theory:
// the global error of a method of order p is O(h^p)). Van der Pol, mu = 1, t_end = 1: rk4 -> 4,
// backward Euler -> 1. HIRES (stiff), t_end = 1: backward Euler -> 1, sdirk3 -> 3 (measured
// 4.05, 1.007, 0.998, 2.990).
// y' = -rate * y from y(0) = 1, always named "decay": a user who edits the right-hand side and
// keeps the name must not get the reference of the old system.
class Decay final : public OdeSystem {
 public:
  explicit Decay(double rate) : rate_(rate) {}
  std::string name() const override { return "decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -rate_ * y[0]; }

 private:
  double rate_;
};

// The cache key carries a fingerprint of f: the same name, initial state, reference and times
// with another rate compute a new reference (whose value is exp(-2), not exp(-1), at t = 1: rk4
// at h = 0.1/16 is accurate to ~1e-12 there), and the same system again reuses its file.
TEST(ReferenceCache, ChangedRightHandSideIsNotServedAStaleReference) {
  const fs::path dir = fresh_dir("fingerprint");
  ConvergenceSpec spec;
  spec.integrators = {"rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  spec.reference = "rk4";
  spec.cache_dir = dir.string();
  auto run = [&](double rate) {
    return run_convergence(
        inputs_of(spec, StudyObjects{[rate] { return std::make_unique<Decay>(rate); }, {}}), spec,
        nullptr);
  };
  const ConvergenceResult a = run(1.0);
  EXPECT_FALSE(a.reference_from_cache);
  const ConvergenceResult b = run(2.0);
  EXPECT_FALSE(b.reference_from_cache) << "reused " << b.reference_cache;
  EXPECT_NE(a.reference_cache, b.reference_cache);
  // rk4 at h = 0.05 on y' = -2y: its error is the reference's (exp(-2)) distance, ~1e-7, not
  // exp(-1) - exp(-2) = 0.23 as a stale reference would give.
  EXPECT_LT(b.rows.back().error, 1e-6);
  const ConvergenceResult c = run(2.0);
  EXPECT_TRUE(c.reference_from_cache);
  EXPECT_EQ(c.reference_cache, b.reference_cache);
  fs::remove_all(dir);
}

TEST(ReferenceCache, ObservedOrdersAgainstAnAdaptiveReference) {
  ConvergenceSpec spec = vdp_spec(fs::path());
  spec.cache_dir.clear();
  const auto vdp = run_convergence(spec, nullptr);
  ASSERT_EQ(vdp.rows.size(), 8u);
  for (const auto& r : vdp.rows) ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_NEAR(*last_observed_order(vdp.rows, "rk4"), 4.0, 0.2);
  EXPECT_NEAR(*last_observed_order(vdp.rows, "backward_euler"), 1.0, 0.1);
  EXPECT_TRUE(vdp.reference_cache.empty());

  // The reference itself against an independent one, rk4 with h = 5e-5 (error ~ C·6e-18):
  // | |y - a| - |y - b| | <= |a - b|, so equal errors bound the references' difference.
  ConvergenceSpec fine = spec;
  fine.reference = "rk4";
  fine.h = 0.0016;  // rk4 runs at 0.0016 and 0.0008; the rk4 reference at 0.0008/16 = 5e-5
  fine.levels = 2;
  fine.integrators = {"rk4"};
  const auto a = run_convergence(fine, nullptr);
  fine.reference = "cvode_bdf";
  const auto b = run_convergence(fine, nullptr);
  // Same rk4 run, two references: the errors differ by at most the references' difference.
  EXPECT_NEAR(a.rows.back().error, b.rows.back().error, 1e-10);

  ConvergenceSpec hires;
  hires.model = "hires";
  hires.integrators = {"backward_euler", "sdirk3"};
  hires.t_end = 1.0;
  hires.h = 0.05;
  hires.levels = 4;
  hires.reference = "cvode_bdf";
  const auto h = run_convergence(hires, nullptr);
  EXPECT_NEAR(*last_observed_order(h.rows, "backward_euler"), 1.0, 0.1);
  EXPECT_NEAR(*last_observed_order(h.rows, "sdirk3"), 3.0, 0.2);
}

// Local error against an adaptive reference stopping exactly at every t0 + h_k (all in one
// cached file): rk4's one-step error is O(h^5), heun's O(h^3) (measured 4.996, 3.001).
TEST(ReferenceCache, LocalErrorReferenceHasEveryStep) {
  const fs::path dir = fresh_dir("local");
  ConvergenceSpec spec = vdp_spec(dir);
  spec.integrators = {"rk4", "heun"};
  const auto r = run_local_error(spec, nullptr);
  EXPECT_NEAR(*last_observed_order(r.rows, "rk4"), 5.0, 0.2);
  EXPECT_NEAR(*last_observed_order(r.rows, "heun"), 3.0, 0.2);
  // Rows after the comment lines: 4 times 0.0125, 0.025, 0.05, 0.1.
  std::vector<double> ts;
  for (const auto& line : lines_of(fs::path(r.reference_cache)))
    if (!line.empty() && line[0] != '#' && line[0] != 't') ts.push_back(std::stod(line));
  ASSERT_EQ(ts.size(), 4u);
  EXPECT_EQ(ts[0], 0.1 / 8);
  EXPECT_EQ(ts[3], 0.1);
  EXPECT_TRUE(run_local_error(spec, nullptr).reference_from_cache);
  fs::remove_all(dir);
}

TEST(ReferenceCache, MisuseNamesTheFlag) {
  ConvergenceSpec spec = vdp_spec(fs::path());
  spec.cache_dir.clear();
  auto msg = [](const ConvergenceSpec& s) {
    return bad_input_message([&] { run_convergence(s, nullptr); });
  };
  ConvergenceSpec s = spec;
  s.reference = "rk4";  // fixed-step: runs at (finest h)/16, a tolerance does not apply
  s.reference_rtol = 1e-10;
  EXPECT_NE(msg(s).find("--reference-rtol applies to an adaptive --reference only"),
            std::string::npos)
      << msg(s);
  s.reference_rtol.reset();
  s.reference_atol = 1e-12;
  EXPECT_NE(msg(s).find("--reference-atol"), std::string::npos) << msg(s);
  s = spec;
  s.reference_rtol = 0;
  EXPECT_NE(msg(s).find("--reference-rtol must be > 0"), std::string::npos) << msg(s);
  s.reference_rtol = -1e-8;
  EXPECT_NE(msg(s).find("--reference-rtol must be > 0"), std::string::npos) << msg(s);
  s = spec;
  s.reference = "no_such_method";
  EXPECT_NE(msg(s).find("--reference 'no_such_method'"), std::string::npos) << msg(s);
  s = spec;
  s.reference = "velocity_verlet";  // needs a mechanical system
  EXPECT_NE(msg(s).find("--reference: integrator 'velocity_verlet'"), std::string::npos) << msg(s);
  s = spec;
  s.reference = "auto";  // van der Pol has no exact solution
  EXPECT_NE(msg(s).find("pass --reference METHOD"), std::string::npos) << msg(s);

  // The exact solution is the default where there is one: a tolerance does not apply.
  ConvergenceSpec ho;
  ho.model = "harmonic_oscillator";
  ho.integrators = {"rk4"};
  ho.levels = 2;
  ho.reference_rtol = 1e-10;
  EXPECT_NE(msg(ho).find("--reference-rtol applies to an adaptive --reference only"),
            std::string::npos)
      << msg(ho);
  // ... but an adaptive reference can be asked for, and agrees with the exact solution.
  ho.reference = "cvode_bdf";
  const auto with_cvode = run_convergence(ho, nullptr);
  ho.reference = "auto";
  ho.reference_rtol.reset();
  const auto exact = run_convergence(ho, nullptr);
  EXPECT_EQ(exact.reference_description, "exact");
  for (std::size_t i = 0; i < exact.rows.size(); ++i)
    EXPECT_NEAR(with_cvode.rows[i].error, exact.rows[i].error, 1e-7);
}

// A parameter only the reference integrator declares (cvode_bdf's max_steps) is accepted.
TEST(ReferenceCache, ReferenceOnlyParameterIsAccepted) {
  ConvergenceSpec spec = vdp_spec(fs::path());
  spec.cache_dir.clear();
  spec.levels = 2;
  spec.params.set("max_steps", "200000");
  EXPECT_NO_THROW(run_convergence(spec, nullptr));
  spec.params.set("no_such_key", "1");
  EXPECT_NE(bad_input_message([&] {
              run_convergence(spec, nullptr);
            }).find("unknown parameter 'no_such_key'"),
            std::string::npos);
}

// --- solve --times / --log-outputs ------------------------------------------------------------

struct SolveRun {
  std::string out, err;
  std::vector<std::vector<double>> rows;  // the trajectory CSV
};

SolveRun solve(SolveOptions opt, const std::string& name) {
  const fs::path csv = fresh_dir(name + ".csv");
  opt.out_csv = csv.string();
  std::ostringstream out, err;
  cmd_solve(opt, out, err);
  SolveRun r{out.str(), err.str(), csv_numbers(csv)};
  fs::remove(csv);
  return r;
}

// Adaptive integrators stop exactly at the requested times: the CSV's t column is exactly them,
// and the states match the exact solution x = cos t, v = -sin t of the default oscillator
// (k = m = 1, x0 = 1, v0 = 0) to a small multiple of the tolerance (rtol 1e-10, atol 1e-12;
// measured max errors: cvode_bdf 1.2e-8, gsl_rkf45 1.1e-10, arkode_erk 1.0e-11).
TEST(SolveTimes, AdaptiveStopsExactlyAtRequestedTimes) {
  const std::vector<double> times{0.1, 0.5, 1.7, 3.14159, 7.25};
  for (const std::string integ : {"cvode_bdf", "arkode_erk", "gsl_rkf45"}) {
    SolveOptions opt;
    opt.model = "harmonic_oscillator";
    opt.integrator = integ;
    opt.params = Params::from_assignments({"rtol=1e-10", "atol=1e-12"});
    opt.times = times;  // no --t-end: the run ends at the last time
    const SolveRun r = solve(opt, "adaptive_" + integ);
    ASSERT_EQ(r.rows.size(), times.size()) << integ << r.out;
    for (std::size_t k = 0; k < times.size(); ++k) {
      EXPECT_EQ(r.rows[k][0], times[k]) << integ;
      EXPECT_NEAR(r.rows[k][1], std::cos(times[k]), 1e-7) << integ << " t = " << times[k];
      EXPECT_NEAR(r.rows[k][2], -std::sin(times[k]), 1e-7) << integ << " t = " << times[k];
    }
    EXPECT_NE(r.out.find("final state at t = 7.25"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("adaptive: the integrator stops exactly at each"), std::string::npos);
  }
}

// A fixed-step run reports the nearest step: rk4 with h = 0.3 on [0, 2] takes N = round(6.67) =
// 7 steps of 2/7; 0.1 -> step 0 (t = 0), 0.5 -> step 2, 1.7 -> step 6, 2 -> step 7.
TEST(SolveTimes, FixedStepReportsNearestStep) {
  SolveOptions opt;
  opt.model = "harmonic_oscillator";
  opt.integrator = "rk4";
  opt.h = 0.3;
  opt.t_end = 2;
  opt.times = {0.1, 0.5, 1.7, 2.0};
  const SolveRun r = solve(opt, "fixed");
  ASSERT_EQ(r.rows.size(), 4u);
  const double h = 2.0 / 7;
  const int steps[] = {0, 2, 6, 7};
  for (int k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(r.rows[k][0], steps[k] * h);
    // rk4's global error at h = 2/7 over t <= 2 is below 2e-4 (measured 1.1e-4 at t = 2).
    EXPECT_NEAR(r.rows[k][1], std::cos(steps[k] * h), 2e-4);
  }
  EXPECT_EQ(r.rows[0][1], 1.0);  // the initial state itself
  EXPECT_NE(r.out.find("nearest step"), std::string::npos);
}

TEST(SolveTimes, LogOutputTimes) {
  // One per decade by default, exact decades on [0, 1e11].
  const auto d = log_output_times(0, 1e11, 12);
  ASSERT_EQ(d.size(), 12u);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(d[k], std::pow(10.0, k));
  // Geometric from --log-first: ratio (10/1e-3)^(1/4) = 10.
  const auto g = log_output_times(0, 10, 5, 1e-3);
  ASSERT_EQ(g.size(), 5u);
  EXPECT_EQ(g.front(), 1e-3);
  EXPECT_EQ(g.back(), 10.0);
  for (std::size_t k = 1; k < g.size(); ++k) EXPECT_NEAR(g[k] / g[k - 1], 10.0, 1e-12);
  // Offsets from t0 are log-spaced.
  const auto o = log_output_times(1.0, 3.0, 3);
  ASSERT_EQ(o.size(), 3u);
  EXPECT_DOUBLE_EQ(o[0], 1.02);
  EXPECT_DOUBLE_EQ(o[1], 1.2);
  EXPECT_EQ(o[2], 3.0);
  EXPECT_EQ(log_output_times(0, 5, 1), std::vector<double>{5.0});
  EXPECT_THROW(log_output_times(0, 5, 0), BadInput);
  EXPECT_THROW(log_output_times(0, 5, 3, 6.0), BadInput);
  EXPECT_THROW(log_output_times(0, 5, 3, 0.0), BadInput);
  EXPECT_THROW(log_output_times(0, 5, 400), BadInput);  // 10^-399 underflows: not increasing
}

// Robertson with --log-outputs 6 on [0, 1e5]: 6 increasing rows, exactly at 1, 10, ..., 1e5,
// conserving y1 + y2 + y3 = 1 (the model's mass invariant) to the tolerance.
TEST(SolveTimes, LogOutputsOnRobertson) {
  SolveOptions opt;
  opt.model = "robertson";
  opt.integrator = "cvode_bdf";
  opt.params = Params::from_assignments({"rtol=1e-8", "atol=1e-14"});
  opt.t_end = 1e5;
  opt.log_outputs = 6;
  const SolveRun r = solve(opt, "robertson");
  ASSERT_EQ(r.rows.size(), 6u) << r.out;
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(r.rows[k][0], std::pow(10.0, static_cast<double>(k)));
    EXPECT_NEAR(r.rows[k][1] + r.rows[k][2] + r.rows[k][3], 1.0, 1e-10);
  }
  // y1 decreases monotonically (A -> B -> C), y3 increases.
  for (std::size_t k = 1; k < 6; ++k) {
    EXPECT_LT(r.rows[k][1], r.rows[k - 1][1]);
    EXPECT_GT(r.rows[k][3], r.rows[k - 1][3]);
  }
}

TEST(SolveTimes, MisuseNamesTheFlag) {
  SolveOptions base;
  base.model = "harmonic_oscillator";
  base.integrator = "cvode_bdf";
  base.t_end = 2;
  auto msg = [](const SolveOptions& o) {
    std::ostringstream out, err;
    return bad_input_message([&] { cmd_solve(o, out, err); });
  };
  SolveOptions o = base;
  o.times = {1.0, 0.5};
  EXPECT_NE(msg(o).find("--times must be strictly increasing"), std::string::npos) << msg(o);
  o.times = {0.0, 1.0};
  EXPECT_NE(msg(o).find("--times: 0 is not after the model's initial time"), std::string::npos)
      << msg(o);
  o.times = {1.0, 3.0};
  EXPECT_NE(msg(o).find("--times: 3 is after --t-end 2"), std::string::npos) << msg(o);
  o.times = {1.0, std::nan("")};
  EXPECT_NE(msg(o).find("--times: nan is not a finite time"), std::string::npos) << msg(o);
  o.times = {1.0};
  o.log_outputs = 3;
  EXPECT_NE(msg(o).find("--times and --log-outputs"), std::string::npos) << msg(o);
  o = base;
  o.log_first = 0.1;
  EXPECT_NE(msg(o).find("--log-first needs --log-outputs"), std::string::npos) << msg(o);
  o = base;
  o.times = {1.0};
  o.frames = 3;
  o.out_csv = "unused";
  EXPECT_NE(msg(o).find("--times cannot be combined with --frames"), std::string::npos) << msg(o);
  EXPECT_NE(
      bad_input_message([] { parse_times("1,x"); }).find("--times: 'x' is not a finite number"),
      std::string::npos);
  EXPECT_EQ(parse_times("0.5,1e3,2"), (std::vector<double>{0.5, 1e3, 2}));
}

// The driver itself: stops at the given times (observer sees exactly them, then t_end) and
// refuses times that are not increasing.
TEST(SolveTimes, DriverStopsAtGivenTimes) {
  auto sys = testing_support::model("dahlquist", {"lambda_re=-1", "lambda_im=0"});
  auto integ = testing_support::make("cvode_bdf", {"rtol=1e-10", "atol=1e-12"});
  AdaptiveOptions opt;
  opt.t_end = 3;
  opt.times = {0.25, 1.0, 2.0};
  std::vector<double> seen;
  const RunResult r =
      run_adaptive(*sys, *integ, opt, [&](double t, CVecRef) { seen.push_back(t); });
  ASSERT_EQ(r.stats.status, Status::ok);
  EXPECT_EQ(seen, (std::vector<double>{0.0, 0.25, 1.0, 2.0, 3.0}));
  EXPECT_EQ(r.t, 3.0);
  opt.times = {1.0, 1.0};
  EXPECT_THROW(run_adaptive(*sys, *integ, opt), BadInput);
  opt.times = {1.0, 4.0};
  EXPECT_THROW(run_adaptive(*sys, *integ, opt), BadInput);
}

// The study runs on resolved inputs: a method file and a variant in the integrator list are
// registered by resolve_inputs and appear in the rows under their labels, in the given order.
TEST(ConvergenceInputs, MethodFileAndVariantRunUnderTheirLabels) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 3;
  StudyTarget t;
  t.model = spec.model;
  t.integrators = {"rk4", heun_file("conv_heun"),
                   "radau5{linear_solver=dense_lu,label=radau5_dense_conv}"};
  const StudyInputs in = resolve_inputs(t);
  const ConvergenceResult r = run_convergence(in, spec, nullptr);
  ASSERT_EQ(r.rows.size(), 9u);
  const std::vector<std::string> labels = {"rk4", "conv_heun", "radau5_dense_conv"};
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    EXPECT_EQ(r.rows[k].integrator, labels[k / 3]) << k;
    EXPECT_EQ(r.rows[k].stats.status, Status::ok) << r.rows[k].stats.message;
  }
  ASSERT_EQ(r.fits.size(), 3u);
  EXPECT_EQ(r.fits[1].integrator, "conv_heun");
  ASSERT_TRUE(last_observed_order(r.rows, "conv_heun"));
  EXPECT_NEAR(*last_observed_order(r.rows, "conv_heun"), 2.0, 0.1);  // Heun is order 2
}

}  // namespace
}  // namespace stiffbench
