// `stiffbench profile`: performance and data profiles from hand-made cost tables whose
// values are derived by hand below, the cost table from work-precision rows, the suite checks
// (no per-problem tuning, bad input refused before anything runs) and a tiny suite end to end
// through the command line. No assertion depends on how long anything took.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/cli_main.hpp"
#include "core/types.hpp"
#include "experiments/commands/profile.hpp"
#include "integrators/embedded_methods.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Four problems, three methods (inf: unsolved):
//        A    B    C
//   p1  10   20  inf      cheapest A; ratios A 1, B 2
//   p2  30   15   60      cheapest B; ratios A 2, B 1, C 4
//   p3   5  inf  inf      cheapest A; ratio  A 1
//   p4 inf  inf  inf      nobody: every ratio inf
// By hand: rho_A(1) = 2/4 (p1, p3), rho_A(2) = 3/4, rho_A(alpha) = 3/4 for every alpha >= 2;
// rho_B(1) = 1/4 (p2), rho_B(2) = 2/4; rho_C(alpha) = 0 below 4, 1/4 from 4 on.
// Data profile in raw units: d_A(kappa) = 0 below 5, 1/4 on [5, 10), 2/4 on [10, 30), 3/4 from 30;
// d_B = 1/4 on [15, 20), 2/4 from 20; d_C = 1/4 from 60.
// Area over log2 alpha up to alpha_max = 4 (log2 = 2): A (2-0)+(2-1)+(2-0) = 5 -> 5/4;
// B (2-1)+(2-0) = 3 -> 3/4; C (2-2) = 0. Ranking: A, B, C (A is cheapest on most problems).
CostTable hand_table() {
  CostTable t;
  t.problems = {"p1", "p2", "p3", "p4"};
  t.methods = {"B", "A", "C"};  // not in ranking order, so the ranking has work to do
  t.cost = {{20, 10, kInf}, {15, 30, 60}, {kInf, 5, kInf}, {kInf, kInf, kInf}};
  t.note.assign(4, std::vector<std::string>(3));
  return t;
}
constexpr std::size_t kB = 0, kA = 1, kC = 2;

TEST(Profile, HandMadeTablePerformanceProfile) {
  const CostTable t = hand_table();
  EXPECT_DOUBLE_EQ(performance_profile(t, kA, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(performance_profile(t, kA, 1.99), 0.5);
  EXPECT_DOUBLE_EQ(performance_profile(t, kA, 2.0), 0.75);
  EXPECT_DOUBLE_EQ(performance_profile(t, kA, 1e9), 0.75);
  EXPECT_DOUBLE_EQ(performance_profile(t, kB, 1.0), 0.25);
  EXPECT_DOUBLE_EQ(performance_profile(t, kB, 2.0), 0.5);
  EXPECT_DOUBLE_EQ(performance_profile(t, kB, 1e9), 0.5);
  EXPECT_DOUBLE_EQ(performance_profile(t, kC, 3.99), 0.0);
  EXPECT_DOUBLE_EQ(performance_profile(t, kC, 4.0), 0.25);
  EXPECT_DOUBLE_EQ(performance_area(t, kA), 5.0 / 4);
  EXPECT_DOUBLE_EQ(performance_area(t, kB), 3.0 / 4);
  EXPECT_DOUBLE_EQ(performance_area(t, kC), 0.0);
  EXPECT_EQ(profile_ranking(t), (std::vector<std::size_t>{kA, kB, kC}));
}

TEST(Profile, HandMadeTableDataProfile) {
  const CostTable t = hand_table();
  EXPECT_DOUBLE_EQ(data_profile(t, kA, 4.99), 0.0);
  EXPECT_DOUBLE_EQ(data_profile(t, kA, 5), 0.25);
  EXPECT_DOUBLE_EQ(data_profile(t, kA, 10), 0.5);
  EXPECT_DOUBLE_EQ(data_profile(t, kA, 29.9), 0.5);
  EXPECT_DOUBLE_EQ(data_profile(t, kA, 30), 0.75);
  EXPECT_DOUBLE_EQ(data_profile(t, kB, 15), 0.25);
  EXPECT_DOUBLE_EQ(data_profile(t, kB, 20), 0.5);
  EXPECT_DOUBLE_EQ(data_profile(t, kC, 59), 0.0);
  EXPECT_DOUBLE_EQ(data_profile(t, kC, 60), 0.25);
  // The curve's breakpoints: every finite cost of the table (5, 10, 15, 20, 30, 60).
  const auto d = data_curve(t, kA);
  ASSERT_EQ(d.size(), 6u);
  EXPECT_DOUBLE_EQ(d.front().x, 5);
  EXPECT_DOUBLE_EQ(d.back().x, 60);
  EXPECT_DOUBLE_EQ(d.back().fraction, 0.75);
  // Performance breakpoints: 1 and the finite ratios (1, 2, 4).
  const auto p = performance_curve(t, kC);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_DOUBLE_EQ(p[0].x, 1);
  EXPECT_DOUBLE_EQ(p[2].x, 4);
  EXPECT_DOUBLE_EQ(p[2].fraction, 0.25);
}

// Monotone in alpha and kappa, within [0, 1], on random tables (a quarter of the entries
// unsolved); the method cheapest on the most problems has the largest rho(1): rho_m(1) is
// exactly (number of problems where m is cheapest)/|P|, counted here independently.
TEST(Profile, CurvesAreMonotoneAndTheMostOftenCheapestStartsHighest) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    CostTable t;
    const std::size_t np = 3 + trial % 5, nm = 2 + trial % 3;
    for (std::size_t m = 0; m < nm; ++m) t.methods.push_back("m" + std::to_string(m));
    std::vector<int> cheapest(nm, 0);
    for (std::size_t p = 0; p < np; ++p) {
      t.problems.push_back("p" + std::to_string(p));
      std::vector<double> row;
      for (std::size_t m = 0; m < nm; ++m)
        row.push_back(u(rng) < 0.25 ? kInf : std::floor(1 + 100 * u(rng)));
      double best = kInf;
      for (double c : row) best = std::min(best, c);
      for (std::size_t m = 0; m < nm; ++m) cheapest[m] += std::isfinite(best) && row[m] == best;
      t.cost.push_back(row);
    }
    t.note.assign(np, std::vector<std::string>(nm));
    for (std::size_t m = 0; m < nm; ++m) {
      EXPECT_DOUBLE_EQ(performance_profile(t, m, 1.0), cheapest[m] / static_cast<double>(np));
      for (const auto& c : {performance_curve(t, m), data_curve(t, m)})
        for (std::size_t i = 0; i < c.size(); ++i) {
          EXPECT_GE(c[i].fraction, 0.0);
          EXPECT_LE(c[i].fraction, 1.0);
          if (i > 0) {
            EXPECT_GT(c[i].x, c[i - 1].x);
            EXPECT_GE(c[i].fraction, c[i - 1].fraction);
          }
        }
    }
    const std::size_t first = profile_ranking(t).front();
    for (std::size_t m = 0; m < nm; ++m) EXPECT_GE(cheapest[first], cheapest[m]);
  }
}

// The cost at tau: the least cost among runs with status ok and error <= tau, not the finest
// run's; a method never below tau, or only failed, is unsolved with the reason noted.
TEST(Profile, CostTableFromWorkPrecisionRows) {
  Table rows{{"integrator", "setting", "error", "f_evals", "lin_solves", "wall_s_median", "status"},
             {{"a", "rtol=1e-3", "5e-4", "100", "10", "0.5", "ok"},
              {"a", "rtol=1e-4", "2e-7", "300", "30", "0.9", "ok"},
              {"a", "rtol=1e-5", "1e-7", "250", "40", "1.5", "ok"},  // cheaper in f_evals
              {"b", "rtol=1e-3", "2e-3", "50", "5", "0.1", "ok"},
              {"b", "rtol=1e-4", "", "0", "0", "0.1", "unstable"},
              {"c", "h=0.1", "", "0", "0", "0", "failed"}}};
  const CostTable f = cost_table({"p"}, {"a", "b", "c"}, {rows}, 1e-6, "f_evals");
  EXPECT_DOUBLE_EQ(f.cost[0][0], 250);
  EXPECT_FALSE(std::isfinite(f.cost[0][1]));
  EXPECT_EQ(f.note[0][1], "best error 2.00e-03");
  EXPECT_FALSE(std::isfinite(f.cost[0][2]));
  EXPECT_EQ(f.note[0][2], "failed");
  EXPECT_DOUBLE_EQ(cost_table({"p"}, {"a"}, {rows}, 1e-6, "wall").cost[0][0], 0.9);
  EXPECT_DOUBLE_EQ(cost_table({"p"}, {"a"}, {rows}, 1e-6, "linear_solves").cost[0][0], 30);
  const CostTable loose = cost_table({"p"}, {"a", "b"}, {rows}, 2e-3, "f_evals");
  EXPECT_DOUBLE_EQ(loose.cost[0][0], 100);
  EXPECT_DOUBLE_EQ(loose.cost[0][1], 50);
}

// A method whose library keeps no count of the cost measure (an empty lin_solves field: GSL's
// implicit steppers) is unsolved in that measure with the reason noted, not the cheapest at 0;
// in f_evals, which it reports, it is ranked as usual.
TEST(Profile, AnUnreportedCostIsNotAZeroCost) {
  Table rows{{"integrator", "setting", "error", "f_evals", "lin_solves", "wall_s_median", "status"},
             {{"a", "rtol=1e-6", "1e-7", "300", "30", "0.9", "ok"},
              {"g", "rtol=1e-6", "1e-7", "200", "", "0.5", "ok"}}};
  const CostTable ls = cost_table({"p"}, {"a", "g"}, {rows}, 1e-6, "linear_solves");
  EXPECT_DOUBLE_EQ(ls.cost[0][0], 30);
  EXPECT_FALSE(std::isfinite(ls.cost[0][1]));
  EXPECT_EQ(ls.note[0][1], "lin_solves not reported by the library");
  EXPECT_DOUBLE_EQ(performance_profile(ls, 0, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(performance_profile(ls, 1, 1e9), 0.0);
  const CostTable fe = cost_table({"p"}, {"a", "g"}, {rows}, 1e-6, "f_evals");
  EXPECT_DOUBLE_EQ(fe.cost[0][1], 200);
  EXPECT_TRUE(fe.note[0][1].empty());
}

TEST(Profile, ShippedSuitesShareTheirSettings) {
  for (const std::string& name : builtin_profile_suites())
    for (const bool quick : {false, true}) {
      const ProfileSuite s = load_profile_suite(name, quick);
      EXPECT_GE(s.problems.size(), 5u) << name;
      for (const auto& p : s.problems) EXPECT_EQ(p.spec.integrators, s.methods) << p.name;
    }
}

int run_cli(std::vector<std::string> args, std::string* out, std::string* err) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out_s, err_s;
  auto* old_out = std::cout.rdbuf(out_s.rdbuf());
  auto* old_err = std::cerr.rdbuf(err_s.rdbuf());
  const int code = cli_main(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old_out);
  std::cerr.rdbuf(old_err);
  *out = out_s.str();
  *err = err_s.str();
  return code;
}

std::string slurp_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

const char* kTinySpec = R"(kind = "work-precision"
integrators = ["dopri5", "bs3"]
t_end = 1.0
rtol_max = 1e-3
tol_levels = 5
repeats = 2
[quick]
tol_levels = 4
repeats = 1
)";

fs::path tiny_suite(const std::string& tag, const std::string& second_extra = "") {
  const fs::path dir =
      fs::temp_directory_path() / ("profile_suite_" + tag + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "01_oscillator.toml") << "model = \"harmonic_oscillator\"\n" << kTinySpec;
  std::ofstream(dir / "02_decay.toml") << second_extra << "model = \"dahlquist\"\n"
                                       << kTinySpec << "[params]\nlambda_re = -2.0\n";
  return dir;
}

TEST(Profile, TinySuiteEndToEndAndReused) {
  const fs::path suite = tiny_suite("e2e");
  const fs::path out = fs::temp_directory_path() / ("profile_out_" + std::to_string(getpid()));
  fs::remove_all(out);
  std::string o, e;
  const std::vector<std::string> args = {"profile",
                                         suite.string(),
                                         "--quick",
                                         "--tau",
                                         "1e-3,1e-5",
                                         "--cost",
                                         "f_evals,wall,linear_solves",
                                         "--out",
                                         out.string()};
  ASSERT_EQ(run_cli(args, &o, &e), 0) << o << e;
  for (const char* f : {"profile.csv", "profile.md", "profile.json", "oscillator/run.json",
                        "decay/work_precision.csv"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  std::ifstream in(out / "profile.json");
  const nlohmann::json meta = nlohmann::json::parse(in);
  EXPECT_EQ(meta["per_problem_settings"], false);
  EXPECT_EQ(meta["ran"].size(), 2u);
  EXPECT_EQ(meta["shared_settings"]["rtol_max"], 1e-3);
  EXPECT_EQ(meta["problem_settings"]["decay"]["params"]["lambda_re"], -2.0);
  // Both methods reach 1e-3 on both problems at rtol 1e-3..1e-6, so at least one method is
  // cheapest on each problem: sum_m rho_m(1) >= 1 (ties count for every tied method).
  std::ifstream csv(out / "profile.csv");
  std::string line;
  double sum = 0;
  while (std::getline(csv, line))
    if (line.rfind("1e-03,f_evals,performance,", 0) == 0 && line.find(",1,") != std::string::npos)
      sum += std::stod(line.substr(line.rfind(',') + 1));
  EXPECT_GE(sum, 1.0);
  EXPECT_NE(o.find("tau = 1e-03"), std::string::npos) << o;
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(out / "profile_1e-05_linear_solves.png"));
  }
  // A second run computes nothing: both folders hold complete runs of the same specs.
  ASSERT_EQ(run_cli(args, &o, &e), 0) << o << e;
  std::ifstream in2(out / "profile.json");
  const nlohmann::json meta2 = nlohmann::json::parse(in2);
  EXPECT_EQ(meta2["reused"].size(), 2u);
  EXPECT_EQ(meta2["ran"].size(), 0u);
  // Full settings against the quick run's folders (profile.* removed): refused with exit 2
  // before any problem runs, the quick rows kept.
  for (const char* f : {"profile.json", "profile.csv", "profile.md", "profile_status.csv"})
    fs::remove(out / f);
  std::vector<std::string> full = args;
  full.erase(full.begin() + 2);  // --quick
  EXPECT_EQ(run_cli(full, &o, &e), 2) << e;
  EXPECT_NE(e.find("another spec"), std::string::npos) << e;
  std::ifstream run_json(out / "oscillator" / "run.json");
  EXPECT_EQ(nlohmann::json::parse(run_json)["spec"]["repeats"], 1);
  fs::remove_all(suite);
  fs::remove_all(out);
}

// The built-in method M's file as SUITE/my/my_M.toml (beside the specs, not among them), under
// the name my_M: the same coefficients as M under another name.
void write_renamed_method(const fs::path& suite, const std::string& m) {
  std::string text;
  for (const auto& [file, body] : embedded_method_files())
    if (file == m + ".toml") text = std::string(body);
  const std::string key = "name = \"" + m + "\"";
  ASSERT_NE(text.find(key), std::string::npos) << m;
  text.replace(text.find(key), key.size(), "name = \"my_" + m + "\"");
  fs::create_directories(suite / "my");
  std::ofstream(suite / "my" / ("my_" + m + ".toml")) << text;
}

// Both specs of tiny_suite with their integrator list replaced by `list`.
void set_suite_integrators(const fs::path& suite, const std::string& list) {
  for (const char* f : {"01_oscillator.toml", "02_decay.toml"}) {
    std::ifstream in(suite / f);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const std::string old = "integrators = [\"dopri5\", \"bs3\"]";
    ASSERT_NE(text.find(old), std::string::npos);
    text.replace(text.find(old), old.size(), "integrators = " + list);
    std::ofstream(suite / f) << text;
  }
}

// A user's method given to the suite by the path of its method file: its rows carry the name
// inside the file, and the profile must find them under that name. The file below is dopri5's
// tableau under another name, so (independent check: the same coefficients give the same runs)
// its cost equals dopri5's on every problem; the profile once looked rows up by the path, found
// none and scored the method as solving nothing (rho = 0) with no error.
TEST(Profile, AMethodFileGivenByPathIsProfiledUnderItsName) {
  const fs::path suite = tiny_suite("method_file");
  write_renamed_method(suite, "dopri5");
  set_suite_integrators(suite, "[\"dopri5\", \"my/my_dopri5.toml\"]");
  const fs::path out = fs::temp_directory_path() / ("profile_mf_" + std::to_string(getpid()));
  fs::remove_all(out);
  std::string o, e;
  ASSERT_EQ(run_cli({"profile", suite.string(), "--quick", "--tau", "1e-3", "--cost", "f_evals",
                     "--out", out.string()},
                    &o, &e),
            0)
      << o << e;
  const ProfileSuite ps = load_profile_suite(suite.string(), true);
  EXPECT_EQ(ps.methods, (std::vector<std::string>{"dopri5", "my_dopri5"}));
  // Both solve both problems at the same cost: each is cheapest everywhere, rho(1) = 1.
  std::ifstream csv(out / "profile.csv");
  std::string line;
  int ones = 0;
  while (std::getline(csv, line))
    if (line == "1e-03,f_evals,performance,dopri5,1,1" ||
        line == "1e-03,f_evals,performance,my_dopri5,1,1")
      ++ones;
  EXPECT_EQ(ones, 2) << "profile.csv rows at alpha = 1 with rho = 1";
  fs::remove_all(suite);
  fs::remove_all(out);
}

// A suite whose specs name two method files by path (dopri5's and bs3's tableaux under other
// names, beside the specs): the problems' identities are taken after the files are read, from
// their content, so a second run (with --html), and a third with another --tau, reuse every
// problem; an edited file makes the next run refuse, naming the file, and --force reruns.
TEST(Profile, AMethodFileSuiteIsReusedUntilAFileChanges) {
  const fs::path suite = tiny_suite("reuse_files");
  for (const char* m : {"dopri5", "bs3"}) write_renamed_method(suite, m);
  set_suite_integrators(suite, "[\"my/my_dopri5.toml\", \"my/my_bs3.toml\"]");
  const fs::path out = fs::temp_directory_path() / ("profile_reuse_" + std::to_string(getpid()));
  fs::remove_all(out);
  const auto profile = [&](std::vector<std::string> extra, std::string* o, std::string* e) {
    std::vector<std::string> args = {"profile", suite.string(), "--quick", "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_cli(args, o, e);
  };
  const auto json = [&](const char* f) {
    std::ifstream in(out / f);
    return nlohmann::json::parse(in);
  };
  std::string o, e;
  ASSERT_EQ(profile({"--tau", "1e-3"}, &o, &e), 0) << o << e;
  EXPECT_EQ(json("profile.json")["ran"].size(), 2u);
  const std::string rows = slurp_file(out / "oscillator" / "work_precision.csv");
  ASSERT_EQ(profile({"--tau", "1e-3", "--html"}, &o, &e), 0) << o << e;
  EXPECT_EQ(json("profile.json")["reused"].size(), 2u) << e;
  ASSERT_EQ(profile({"--tau", "1e-4"}, &o, &e), 0) << o << e;
  EXPECT_EQ(json("profile.json")["reused"].size(), 2u) << e;
  EXPECT_EQ(slurp_file(out / "oscillator" / "work_precision.csv"), rows);
  // profile_status.csv: every problem x method, all ok here.
  EXPECT_EQ(slurp_file(out / "profile_status.csv"),
            "problem,method,unit_status,unit_message\n"
            "oscillator,my_dopri5,ok,\noscillator,my_bs3,ok,\n"
            "decay,my_dopri5,ok,\ndecay,my_bs3,ok,\n");

  { std::ofstream(suite / "my" / "my_bs3.toml", std::ios::app) << "# edited\n"; }
  EXPECT_EQ(profile({"--tau", "1e-3"}, &o, &e), 2);
  EXPECT_NE(e.find("my_bs3.toml (method 'my_bs3') changed"), std::string::npos) << e;
  EXPECT_EQ(e.find("--quick"), std::string::npos) << e;
  EXPECT_EQ(slurp_file(out / "oscillator" / "work_precision.csv"), rows);
  ASSERT_EQ(profile({"--tau", "1e-3", "--force"}, &o, &e), 0) << o << e;
  EXPECT_EQ(json("profile.json")["ran"].size(), 2u) << e;
  fs::remove_all(suite);
  fs::remove_all(out);
}

// Units whose runs do not end ok are the profile's data (unsolved there), not its failure. With
// max_steps = 1 no run of dopri5 or bs3 reaches t_end = 1: the first step of an adaptive run is
// at most (0.01 / ||f(y0)||_w)^(1/(p+1)) (HNW I, Sect. II.4, the starting-step rule of
// integrators/adaptive/controller.cpp) with the weighted norm ||f(y0)||_w >= 1 / (atol + rtol)
// >= 500 for these problems (|f(y0)| >= |y0| = 1) at rtol <= 1e-3, so h <= 0.2 < 1. Every unit
// is then "failed"; the profile is written, exit 0, and profile_status.csv, profile.md and
// profile.json list each unit.
TEST(Profile, UnitsThatDidNotEndOkAreRecordedPerProblem) {
  const fs::path suite = tiny_suite("not_ok");
  // 02_decay.toml ends in its [params] table, 01_oscillator.toml in [quick].
  std::ofstream(suite / "01_oscillator.toml", std::ios::app) << "[params]\nmax_steps = 1\n";
  std::ofstream(suite / "02_decay.toml", std::ios::app) << "max_steps = 1\n";
  const fs::path out = fs::temp_directory_path() / ("profile_not_ok_" + std::to_string(getpid()));
  fs::remove_all(out);
  std::string o, e;
  ASSERT_EQ(run_cli({"profile", suite.string(), "--quick", "--tau", "1e-3", "--cost", "f_evals",
                     "--out", out.string()},
                    &o, &e),
            0)
      << o << e;
  const std::string status = slurp_file(out / "profile_status.csv");
  for (const char* row : {"oscillator,dopri5,failed,", "oscillator,bs3,failed,",
                          "decay,dopri5,failed,", "decay,bs3,failed,"})
    EXPECT_NE(status.find(row), std::string::npos) << row << "\n" << status;
  std::ifstream in(out / "profile.json");
  EXPECT_EQ(nlohmann::json::parse(in)["units_not_ok"].size(), 4u);
  EXPECT_NE(slurp_file(out / "profile.md").find("## Units that did not end ok"), std::string::npos);
  EXPECT_NE(e.find("counted as unsolved"), std::string::npos) << e;
  fs::remove_all(suite);
  fs::remove_all(out);
}

TEST(Profile, BadInputExitsTwoBeforeAnythingRuns) {
  const fs::path suite = tiny_suite("bad");
  const fs::path tuned = tiny_suite("tuned", "seed = 3\n");
  const fs::path tuned_param = tiny_suite("tuned_param", "");
  {  // an integrator parameter in one file only is a study setting
    std::ofstream(tuned_param / "02_decay.toml", std::ios::app) << "max_steps = 50000\n";
  }
  const fs::path with_method = tiny_suite("with_method");
  for (const auto& [file, text] : embedded_method_files())
    if (file == "rk4.toml") std::ofstream(with_method / "03_rk4.toml") << text;
  const fs::path empty = fs::temp_directory_path() / ("profile_empty_" + std::to_string(getpid()));
  fs::create_directories(empty);
  const fs::path out = fs::temp_directory_path() / ("profile_bad_" + std::to_string(getpid()));
  fs::remove_all(out);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{suite.string(), "--cost", "flops"}, "flops"},
      {{suite.string(), "--tau", "0"}, "--tau"},
      {{suite.string(), "--tau", "-1e-6"}, "--tau"},
      {{suite.string(), "--tau", "abc"}, "abc"},
      {{empty.string()}, "no spec file"},
      {{"no_such_suite"}, "no_such_suite"},
      {{tuned.string()}, "seed"},
      {{tuned_param.string()}, "params.max_steps"},
      {{with_method.string()}, "a method file (kind 'explicit_rk'), not a spec file"}};
  for (const auto& [args, named] : cases) {
    std::vector<std::string> a = {"profile"};
    a.insert(a.end(), args.begin(), args.end());
    a.insert(a.end(), {"--out", out.string()});
    std::string o, e;
    EXPECT_EQ(run_cli(a, &o, &e), 2) << e;
    EXPECT_NE(e.find(named), std::string::npos) << e;
    EXPECT_FALSE(fs::exists(out / "profile.csv"));
    EXPECT_FALSE(fs::exists(out / "decay"));
  }
  EXPECT_THROW(make_profile_suite("none", {}, false), BadInput);
  for (const auto& d : {suite, tuned, tuned_param, with_method, empty, out}) fs::remove_all(d);
}

}  // namespace
}  // namespace stiffbench
