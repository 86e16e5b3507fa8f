// The command-line contract, run on the real binary: exit codes, one-line messages naming the
// bad value, and the output files' column names.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>

#include "tests/cli_support.hpp"

namespace {

using Outcome = stiffbench::testing_support::CliOutcome;
Outcome run(const std::string& args) { return stiffbench::testing_support::run_cli(args); }

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

struct BadCase {
  const char* label;
  std::string args;
  std::string must_name;  // the message must contain this
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.args; }

class BadInputTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInputTest, ExitsTwoWithOneMessageNamingTheValue) {
  const Outcome o = run(GetParam().args);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find(GetParam().must_name), std::string::npos) << o.err;
  EXPECT_EQ(lines(o.err), 1) << o.err;
  EXPECT_TRUE(o.out.empty()) << o.out;
}

const std::string kSolve = "solve --model harmonic_oscillator --integrator rk4 --h 0.1 --t-end 1";
const std::string kConv =
    "convergence --model harmonic_oscillator --integrators euler --t-end 1 --h 0.1 --out "
    "/tmp/sbtest";

INSTANTIATE_TEST_SUITE_P(
    Cli, BadInputTest,
    ::testing::Values(
        BadCase{"unknown_model", "solve --model nosuchmodel --integrator rk4 --h 0.1 --t-end 1",
                "nosuchmodel"},
        BadCase{"unknown_integrator",
                "solve --model kepler --integrator nosuchmethod --h 0.1 --t-end 1", "nosuchmethod"},
        BadCase{"unknown_integrator_in_list",
                "convergence --model kepler --integrators rk4,bogus --t-end 1 --h 0.1 --out "
                "/tmp/sbtest",
                "bogus"},
        BadCase{"unknown_param", kSolve + " --param stiffnes=3", "stiffnes"},
        BadCase{"param_not_a_number", kSolve + " --param k=abc", "abc"},
        BadCase{"param_malformed", kSolve + " --param k", "k"},
        BadCase{"h_zero", "solve --model kepler --integrator rk4 --h 0 --t-end 1", "h"},
        BadCase{"h_negative", "solve --model kepler --integrator rk4 --h -0.5 --t-end 1", "-0.5"},
        BadCase{"t_end_zero", "solve --model kepler --integrator rk4 --h 0.1 --t-end 0", "t-end"},
        BadCase{"t_end_negative", kConv + " --t-end -2", "t-end"},
        BadCase{"h_zero_convergence", kConv + " --h 0", "--h"},
        BadCase{"levels_one", kConv + " --levels 1", "--levels"},
        BadCase{"symplectic_on_first_order",
                "solve --model dahlquist --integrator velocity_verlet --h 0.1 --t-end 1",
                "dahlquist"},
        BadCase{"leapfrog_on_damped",
                "solve --model harmonic_oscillator --param gamma=0.1 --integrator leapfrog --h 0.1 "
                "--t-end 1",
                "leapfrog"},
        BadCase{"rattle_on_unconstrained",
                "solve --model pendulum_chain --integrator rattle --h 0.01 --t-end 0.1",
                "holonomic constraints"},
        BadCase{"model_param_out_of_range",
                "solve --model kepler --param e=1.5 --integrator rk4 --h 0.1 --t-end 1", "'e'"},
        BadCase{"missing_flag", "solve --model kepler --integrator rk4 --h 0.1", "--t-end"},
        BadCase{"unknown_subcommand", "frobnicate", "frobnicate"},
        BadCase{"unknown_list_kind", "list widgets", "widgets"},
        BadCase{"describe_unknown", "describe nosuchthing", "nosuchthing"},
        BadCase{"no_h_and_no_suggested_step", "solve --model kepler --integrator rk4 --t-end 1",
                "--h"},
        BadCase{"convergence_no_h_and_no_suggested_step",
                "convergence --model kepler --integrators rk4 --t-end 1 --out /tmp/sbtest", "--h"},
        BadCase{"frames_without_out",
                "solve --model sph_drop_2d --integrator rk4 --t-end 0.01 --frames 2", "--frames"},
        BadCase{"sph_singular_density_kernel",
                "solve --model sph_drop_2d --param density_kernel=viscosity --integrator rk4 "
                "--t-end 0.01",
                "viscosity"},
        BadCase{"sph_support_below_spacing",
                "solve --model sph_drop_2d --param support=0.9 --integrator rk4 --t-end 0.01",
                "support"},
        // An adaptive run's trajectory has --outputs + 1 rows: 10^12 rows of 5 numbers (up to
        // 114 TiB) exceed any disk, refused before the run.
        BadCase{"trajectory_larger_than_the_disk",
                "solve --model kepler --integrator dopri5 --t-end 1 --outputs 1000000000000 "
                "--out /tmp/sbtest_huge_trajectory.csv",
                "a smaller --outputs"},
        BadCase{"sph_verlet_on_viscous_dam_break",
                "solve --model sph_dam_break_2d --integrator velocity_verlet --t-end 0.01",
                "velocity_verlet"}),
    [](const auto& param_info) { return std::string(param_info.param.label); });

TEST(Cli, HelpExitsZero) {
  const Outcome o = run("--help");
  EXPECT_EQ(o.code, 0);
  EXPECT_NE(o.out.find("convergence"), std::string::npos);
}

TEST(Cli, ListIntegratorsShowsTheClassicalMethodsWithFamilyAndOrder) {
  const Outcome o = run("list integrators");
  ASSERT_EQ(o.code, 0);
  for (const char* row :
       {"| euler | explicit | explicit RK | 1 |", "| heun | explicit | explicit RK | 2 |",
        "| midpoint | explicit | explicit RK | 2 |", "| ralston | explicit | explicit RK | 2 |",
        "| kutta3 | explicit | explicit RK | 3 |", "| ssprk3 | explicit | explicit RK (SSP) | 3 |",
        "| rk4 | explicit | explicit RK | 4 |", "| rk38 | explicit | explicit RK | 4 |",
        "| symplectic_euler | symplectic | splitting | 1 |",
        "| symplectic_euler_x | symplectic | splitting | 1 |",
        "| verlet | symplectic | two-step (Stormer-Verlet) | 2 |",
        "| velocity_verlet | symplectic | splitting | 2 |",
        "| leapfrog | symplectic | splitting (staggered) | 2 |"})
    EXPECT_NE(o.out.find(row), std::string::npos) << row;
}

// solve compares with the published HIRES solution (IVP test set) when the run ends at its
// time: radau5 and rodas4 at rtol 1e-10 reach it to about 12 digits, cvode_bdf to about 7
// (tolerance proportionality; the same figures as the work-precision table).
TEST(Cli, SolvePrintsMescdAgainstThePublishedSolution) {
  for (const auto& [method, least] : std::vector<std::pair<std::string, double>>{
           {"radau5", 10.0}, {"rodas4", 10.0}, {"cvode_bdf", 6.0}}) {
    const Outcome o = run("solve --model hires --integrator " + method +
                          " --param rtol=1e-10 --param atol=1e-12");
    ASSERT_EQ(o.code, 0) << o.err;
    const auto at = o.out.find("mescd ");
    ASSERT_NE(at, std::string::npos) << o.out;
    EXPECT_GE(std::stod(o.out.substr(at + 6)), least) << method << "\n" << o.out;
  }
  // Not at the published time: no comparison.
  const Outcome early = run("solve --model hires --integrator radau5 --t-end 100");
  ASSERT_EQ(early.code, 0);
  EXPECT_EQ(early.out.find("published solution"), std::string::npos);
}

TEST(Cli, DescribeListsParametersWithDefaults) {
  const Outcome o = run("describe kepler");
  ASSERT_EQ(o.code, 0);
  EXPECT_NE(o.out.find("| e | real | 0 |"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("angular_momentum"), std::string::npos);
}

// The circular Kepler orbit returns to its initial state after one period 2π; rk4 with
// h = 1e-3 has a global error ~1e-13 there (measured), far inside 1e-9.
TEST(Cli, SolveKeplerOnePeriodReturnsToStart) {
  const auto csv = std::filesystem::temp_directory_path() /
                   ("sb_kepler_traj_" + std::to_string(::getpid()) + ".csv");
  const Outcome o =
      run("solve --model kepler --integrator rk4 --h 0.001 --t-end 6.283185307179586 --outputs 10 "
          "--out " +
          csv.string());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("status       ok"), std::string::npos);
  // Final state lines "  yI = value".
  const double expected[4] = {1, 0, 0, 1};
  for (int i = 0; i < 4; ++i) {
    const std::string key = "  y" + std::to_string(i) + " = ";
    const auto pos = o.out.find(key);
    ASSERT_NE(pos, std::string::npos);
    EXPECT_NEAR(std::stod(o.out.substr(pos + key.size())), expected[i], 1e-9);
  }
  std::ifstream f(csv);
  std::string header;
  std::getline(f, header);
  EXPECT_EQ(header, "t,y0,y1,y2,y3");
  int rows = 0;
  for (std::string line; std::getline(f, line);) ++rows;
  EXPECT_EQ(rows, 11);
  std::filesystem::remove(csv);
}

// Explicit Euler on the stiff Prothero-Robinson problem is reported as unstable, exit code 0:
// the run itself is a valid result.
TEST(Cli, UnstableRunExitsZeroAndSaysSo) {
  const Outcome o = run(
      "solve --model prothero_robinson --param lambda=-1e6 --integrator rk4 --h 0.1 --t-end 10");
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("status       unstable"), std::string::npos) << o.out;
}

TEST(Cli, ConvergenceWritesContractFiles) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_conv_test") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("convergence --model harmonic_oscillator --integrators euler,rk4 --t-end 1 --h 0.1 "
          "--levels 3 --out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  std::ifstream f(dir / "convergence.csv");
  std::string header;
  std::getline(f, header);
  // The contract columns first; the solver counters and the floors after them.
  EXPECT_EQ(header,
            "model,integrator,order,h,steps,error,observed_order,f_evals,jac_evals,lin_solves,wall_"
            "s,status,newton_iters,newton_conv_failures,error_test_failures,linear_setups,linear_"
            "iters,fe_evals,fi_evals,roundoff_floor,reference_floor,floor_used,floor_source");
  int rows = 0;
  for (std::string line; std::getline(f, line);) ++rows;
  EXPECT_EQ(rows, 6);
  EXPECT_TRUE(std::filesystem::exists(dir / "convergence.md"));
  EXPECT_TRUE(std::filesystem::exists(dir / "convergence.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "convergence_orders.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "convergence.csv.tmp"));
  const Outcome l =
      run("local-error --model harmonic_oscillator --integrators heun --h 0.1 --levels 2 --out " +
          dir.string());
  ASSERT_EQ(l.code, 0) << l.err;
  std::ifstream g(dir / "local_error.csv");
  std::getline(g, header);
  EXPECT_EQ(header,
            "model,integrator,order,h,local_error,observed_order,status,f_evals,jac_evals,lin_"
            "solves,newton_iters,newton_conv_failures,error_test_failures,linear_setups,linear_"
            "iters,fe_evals,fi_evals,roundoff_floor,reference_floor,floor_used,floor_source");
  EXPECT_TRUE(std::filesystem::exists(dir / "local_error_orders.csv"));
  std::filesystem::remove_all(dir);
}

// The cells of every line of a CSV file (no quoting: stiffbench's numeric tables).
std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& file) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream f(file);
  for (std::string line; std::getline(f, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

std::string join_cells(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
  return line;
}

// Robertson at rtol = atol = 1e-4 (t_end 1e11): radau5 reaches y1 ≈ -4.7e7 (outside the model's
// non-negative concentrations: invalid_state); dopri5, explicit on a stiff problem, blows up and
// its step falls to 10·u·t near t = 0.008 (step_size_too_small). Both are numerical outcomes of
// the method, like unstable: exit 0, the status on stdout and in the CSV's status column.
TEST(Cli, WrongAnswersEndWithTheirStatusAndExitZero) {
  const std::string robertson =
      "solve --model robertson --param rtol=1e-4 --param atol=1e-4 --outputs 1 --integrator ";
  const Outcome radau = run(robertson + "radau5");
  EXPECT_EQ(radau.code, 0) << radau.err;
  EXPECT_NE(radau.out.find("status       invalid_state"), std::string::npos) << radau.out;
  EXPECT_NE(radau.out.find("component y[0] = -4"), std::string::npos) << radau.out;
  const Outcome dopri = run(robertson + "dopri5");
  EXPECT_EQ(dopri.code, 0) << dopri.err;
  EXPECT_NE(dopri.out.find("status       step_size_too_small"), std::string::npos) << dopri.out;
  EXPECT_NE(dopri.out.find("step size too small: h = "), std::string::npos) << dopri.out;

  const auto dir = stiffbench::testing_support::fresh_dir("cli", "wrong_answers");
  const Outcome wp =
      run("work-precision --model robertson --integrators radau5,dopri5 --reference published "
          "--tol-levels 2 --rtol-max 1e-3 --atol-factor 1 --repeats 1 --out " +
          dir.string());
  ASSERT_EQ(wp.code, 0) << wp.err;
  const auto rows = read_csv(dir / "work_precision.csv");
  ASSERT_EQ(rows.size(), 5u);
  const auto status = static_cast<std::size_t>(std::find(rows[0].begin(), rows[0].end(), "status") -
                                               rows[0].begin());
  ASSERT_LT(status, rows[0].size());
  std::map<std::string, std::string> by_row;
  for (std::size_t i = 1; i < rows.size(); ++i)
    by_row[rows[i][1] + " " + rows[i][2]] = rows[i][status];
  EXPECT_NE(by_row["radau5 rtol=1e-03"], "ok");
  EXPECT_EQ(by_row["radau5 rtol=1e-04"], "invalid_state");
  EXPECT_EQ(by_row["dopri5 rtol=1e-03"], "step_size_too_small");
  EXPECT_EQ(by_row["dopri5 rtol=1e-04"], "step_size_too_small");
  std::filesystem::remove_all(dir);
}

// Implicit rows of convergence.csv carry their Jacobian and linear-solve counts.
TEST(Cli, ConvergenceRowsOfImplicitMethodsCountJacobiansAndSolves) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_conv_implicit") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("convergence --model harmonic_oscillator --integrators "
          "backward_euler,sdirk3,bdf2,rosenbrock2 --t-end 1 "
          "--h 0.1 --levels 2 --out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto table = read_csv(dir / "convergence.csv");
  int rows = 0;
  for (std::size_t r = 1; r < table.size(); ++r) {
    const auto& cells = table[r];
    const std::string line = join_cells(cells);
    // 12 contract columns, the 7 solver counters, the 2 floors and the floor in use with its
    // source.
    ASSERT_EQ(cells.size(), 23u) << line;
    EXPECT_GT(std::stol(cells[8]), 0) << line;  // jac_evals
    EXPECT_GT(std::stol(cells[9]), 0) << line;  // lin_solves
    ++rows;
  }
  EXPECT_EQ(rows, 8);
  std::filesystem::remove_all(dir);
}

// A work-precision run on HIRES with the default ladders (h from (t_end - t0)/16000,
// rtol from 1e-5): within every method, sorted by f evaluations, the error at t_end falls.
// (--repeats only changes the wall-time column, so 1 repeat checks the same numbers.)
TEST(Cli, WorkPrecisionOnHiresErrorFallsAsWorkRises) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_wp_hires") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("work-precision --model hires --integrators "
          "cvode_bdf,arkode_dirk,gsl_msbdf,gsl_bsimp,sdirk3,bdf2 "
          "--repeats 1 --out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto table = read_csv(dir / "work_precision.csv");
  ASSERT_FALSE(table.empty());
  // The original contract columns, then the solver counters and the timing spread.
  EXPECT_EQ(join_cells(table.front()),
            "model,integrator,setting,error,f_evals,jac_evals,lin_solves,steps,wall_s,status,mescd,"
            "newton_iters,newton_conv_failures,error_test_failures,linear_setups,linear_iters,fe_"
            "evals,fi_evals,"
            "wall_s_median,wall_s_min,wall_s_ci_low,wall_s_ci_high,repeats,flag,reference_error");
  std::map<std::string, std::vector<std::pair<long, double>>> by_method;
  for (std::size_t r = 1; r < table.size(); ++r) {
    const auto& c = table[r];
    const std::string line = join_cells(c);
    ASSERT_EQ(c.size(), 25u) << line;
    ASSERT_EQ(c[9], "ok") << line;
    // The reference is HIRES's published solution (good to ~1e-18): no error here is near it.
    EXPECT_EQ(c[23], "") << line;
    EXPECT_EQ(c[22], "1") << line;    // --repeats 1
    EXPECT_EQ(c[8], c[18]) << line;   // wall_s is the median
    EXPECT_EQ(c[18], c[19]) << line;  // one run: median = min = both interval ends
    EXPECT_EQ(c[18], c[20]) << line;
    EXPECT_EQ(c[18], c[21]) << line;
    // Every method here is implicit; all but GSL's (whose odeiv2 reports no Newton counts)
    // count their Newton iterations.
    if (c[1].rfind("gsl_", 0) != 0) {
      EXPECT_GT(std::stol(c[11]), 0) << line;
    }
    by_method[c[1]].emplace_back(std::stol(c[4]), std::stod(c[3]));
  }
  EXPECT_EQ(by_method.size(), 6u);
  for (auto& [method, points] : by_method) {
    std::sort(points.begin(), points.end());
    EXPECT_GE(points.size(), 4u) << method;
    for (std::size_t i = 1; i < points.size(); ++i)
      EXPECT_LT(points[i].second, points[i - 1].second)
          << method << " at f_evals " << points[i].first;
  }
  std::filesystem::remove_all(dir);
}

// A deliberately loose reference (cvode_bdf at rtol 1e-11) on HIRES: radau5's rows near the
// reference's own error (its distance from the published solution, ~1e-11; radau5 at rtol 1e-10
// is far more accurate, tests/experiments/test_work_precision.cpp) carry flag reference_floor in
// the CSV, the loosest does not, the JSON counts them, and `plot DIR` redraws the figure (the
// flagged rows hollow) from the CSV alone.
TEST(Cli, WorkPrecisionFlagsRowsAtTheReferenceFloorAndPlotRedrawsThem) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_wp_floor") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o = run(
      "work-precision --model hires --integrators radau5 --reference cvode_bdf --reference-rtol "
      "1e-11 --reference-atol 1e-14 --repeats 1 --out " +
      dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto table = read_csv(dir / "work_precision.csv");
  ASSERT_EQ(table.size(), 7u);  // header and rtol 1e-5 ... 1e-10
  const auto& header = table.front();
  const auto flag =
      static_cast<std::size_t>(std::find(header.begin(), header.end(), "flag") - header.begin());
  ASSERT_LT(flag, header.size());
  EXPECT_EQ(table[1][2], "rtol=1e-05");
  EXPECT_EQ(table[1][flag], "");
  EXPECT_EQ(table[6][2], "rtol=1e-10");
  EXPECT_EQ(table[6][flag], "reference_floor");
  long flagged = 0;
  for (std::size_t r = 1; r < table.size(); ++r) flagged += table[r][flag] == "reference_floor";
  std::ifstream js(dir / "work_precision.json");
  const std::string json((std::istreambuf_iterator<char>(js)), {});
  EXPECT_NE(json.find("\"rows_at_reference_floor\": " + std::to_string(flagged)), std::string::npos)
      << json;
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    ASSERT_TRUE(std::filesystem::exists(dir / "work_precision.png"));
    std::filesystem::remove(dir / "work_precision.png");
    const Outcome p = run("plot " + dir.string());
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "work_precision.png")) << p.out << p.err;
  }
  std::filesystem::remove_all(dir);
}

// The five SPH scenes are listed, and describe prints every parameter and the
// suggested step.
TEST(Cli, ListsAndDescribesTheSphScenes) {
  const Outcome l = run("list models");
  ASSERT_EQ(l.code, 0) << l.err;
  for (const char* m :
       {"sph_dam_break_2d", "sph_dam_break_3d", "sph_tank_2d", "sph_tank_3d", "sph_drop_2d"})
    EXPECT_NE(l.out.find(std::string("| ") + m + " |"), std::string::npos) << m;
  const Outcome d = run("describe sph_dam_break_2d");
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_NE(d.out.find("suggested step (defaults): 1.906"), std::string::npos) << d.out;
  for (const char* key : {"| a |", "| n |", "| support |", "| c0 |", "| eos |", "| clamp |",
                          "| form |", "| density_kernel |", "| gradient_kernel |", "| viscosity |",
                          "| alpha |", "| mu |", "| boundary |", "| masses |"})
    EXPECT_NE(d.out.find(key), std::string::npos) << key;
}

// Solve on the cavity writes VTK image data frames (one .vti per frame in
// frames.pvd, no trajectory), observables.csv and centreline.csv (y, u: n rows).
TEST(Cli, SolveCavityWritesImageDataFramesAndCentreline) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("sb_cavity_frames_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("solve --model fluid_2d --param scene=cavity --param n=8 --integrator rk4 --h 0.01 "
          "--t-end 0.1 --frames 5 --out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  for (int k = 0; k <= 5; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.vti", k);
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "trajectory.csv"));
  EXPECT_NE(o.out.find("centreline.csv"), std::string::npos) << o.out;
  const auto rows = read_csv(dir / "centreline.csv");
  ASSERT_EQ(rows.size(), 9u);
  EXPECT_EQ(rows.front(), (std::vector<std::string>{"y", "u"}));
  EXPECT_DOUBLE_EQ(std::stod(rows[1][0]), 0.0625);  // the first cell centre, Δx/2
  const auto obs = read_csv(dir / "observables.csv");
  ASSERT_EQ(obs.size(), 7u);
  EXPECT_EQ(obs.front(), (std::vector<std::string>{"t", "kinetic_energy", "max_divergence"}));
  std::filesystem::remove_all(dir);
}

// Solve without --h runs at the suggested step, says so, and writes
// 21 VTK frames (+ CSV copies) and observables.csv with the front, which starts at a = 0.146.
TEST(Cli, SolveDamBreakWritesFramesAtTheSuggestedStep) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_sph_frames") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("solve --model sph_dam_break_2d --integrator symplectic_euler --t-end 0.25 --frames 20 "
          "--out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.err.find("suggested step h = 0.000190"), std::string::npos) << o.err;
  EXPECT_NE(o.out.find("the model's suggested step: CFL 0.4 h/c"), std::string::npos) << o.out;
  int vtu = 0, csv = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("frame_", 0) == 0 && e.path().extension() == ".vtu") ++vtu;
    if (name.rfind("frame_", 0) == 0 && e.path().extension() == ".csv") ++csv;
  }
  EXPECT_EQ(vtu, 21);
  EXPECT_EQ(csv, 21);
  EXPECT_TRUE(std::filesystem::exists(dir / "frames.pvd"));
  const auto rows = read_csv(dir / "observables.csv");
  ASSERT_EQ(rows.size(), 22u);
  const auto& header = rows.front();
  const auto front = std::find(header.begin(), header.end(), "front");
  ASSERT_NE(front, header.end());
  EXPECT_EQ(header.front(), "t");
  const std::size_t col = static_cast<std::size_t>(front - header.begin());
  EXPECT_DOUBLE_EQ(std::stod(rows[1][col]), 0.146);  // a: the column's right face
  EXPECT_DOUBLE_EQ(std::stod(rows.back()[0]), 0.25);
  EXPECT_GT(std::stod(rows.back()[col]), 0.3);  // the surge has moved right
  std::filesystem::remove_all(dir);
}

// Convergence on a smaller drop (12 particles across, so that the sanitizer build
// stays quick): without --h the study starts at the suggested step, and the last observed orders
// of heun, rk4 and velocity Verlet are within 0.3 of 2, 4, 2 (measured at the default 20 across:
// 2.08, 3.96, 2.03).
TEST(Cli, SphDropConvergenceFromTheSuggestedStep) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_sph_conv") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o =
      run("convergence --model sph_drop_2d --param n=12 --integrators heun,rk4,velocity_verlet "
          "--reference rk4 --t-end 0.1 --levels 4 --out " +
          dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.err.find("starting from the model's suggested step"), std::string::npos) << o.err;
  const auto rows = read_csv(dir / "convergence.csv");
  ASSERT_EQ(rows.size(), 13u);
  std::map<std::string, double> last;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i][11], "ok");
    if (!rows[i][6].empty()) last[rows[i][1]] = std::stod(rows[i][6]);
  }
  EXPECT_NEAR(last["heun"], 2.0, 0.3);
  EXPECT_NEAR(last["rk4"], 4.0, 0.3);
  EXPECT_NEAR(last["velocity_verlet"], 2.0, 0.3);
  std::filesystem::remove_all(dir);
}

// CVODE on an SPH scene: linear_solver=auto takes matrix-free SPGMR above 100 unknowns for a
// model without a Jacobian (the 16-across dam break has 512 particles, 2048 unknowns), and the
// run reports its counters.
TEST(Cli, CvodeOnSphRunsMatrixFree) {
  const Outcome o =
      run("solve --model sph_dam_break_2d --param n=16 --integrator cvode_bdf --param rtol=1e-4 "
          "--param atol=1e-6 --t-end 0.002");
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("status       ok"), std::string::npos) << o.out;
  // SPGMR's Jacobian-vector products are counted by CVODE; a dense solver would have none.
  const auto pos = o.out.find("Jac-times evals");
  ASSERT_NE(pos, std::string::npos) << o.out;
  const std::string line = o.out.substr(pos, o.out.find('\n', pos) - pos);
  EXPECT_GT(std::stol(line.substr(line.find('=') + 1)), 0) << line;
}

// The region command writes region.csv in the contract with
// the limits table on stdout (rk4's imaginary-axis limit 2√2 = 2.8284, docs/reference-values.md);
// an integrator without stability data is bad input naming it.
TEST(Cli, RegionWritesContractFiles) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_region_cli") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o = run("region --integrators rk4,heun,kutta3,sdirk3 --out " + dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto rows = read_csv(dir / "region.csv");
  ASSERT_GT(rows.size(), 100u);
  EXPECT_EQ(join_cells(rows.front()), "integrator,re,im");
  // rk4: real root of x³ − 4x² + 12x − 24 (R(−x) = 1) and 2√2, to the 10 decimals printed.
  EXPECT_NE(o.out.find("| rk4 | explicit Runge-Kutta | -2.7852935634 | 2.8284271247 |"),
            std::string::npos)
      << o.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "region_limits.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "region.md"));
  EXPECT_TRUE(std::filesystem::exists(dir / "region.json"));
  const Outcome bad = run("region --integrators rk4,cvode_bdf --out " + dir.string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("'cvode_bdf' has no fixed stability region"), std::string::npos)
      << bad.err;
  EXPECT_EQ(lines(bad.err), 1) << bad.err;
  std::filesystem::remove_all(dir);
}

// Adaptive references: the first run computes the cvode_bdf reference and writes
// OUT/reference/<hash>.csv, the second says it reuses it; a tolerance with a fixed-step reference
// and a decreasing --times are bad input naming the flag; --log-outputs writes one row per time.
TEST(Cli, AdaptiveReferenceCacheAndOutputTimes) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_refcache_cli") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string conv =
      "convergence --model van_der_pol --param form=mu --param mu=1 "
      "--integrators rk4 --t-end 1 --h 0.1 --levels 2 --reference cvode_bdf "
      "--out " +
      dir.string();
  const Outcome first = run(conv);
  ASSERT_EQ(first.code, 0) << first.err;
  EXPECT_NE(first.err.find("reference: computed cvode_bdf adaptive, rtol = 1e-12"),
            std::string::npos)
      << first.err;
  const Outcome second = run(conv);
  ASSERT_EQ(second.code, 0) << second.err;
  EXPECT_NE(second.err.find("reference: cached " + (dir / "reference").string() + "/"),
            std::string::npos)
      << second.err;
  // Into a folder of its own: dir holds results of another spec, which would be refused first.
  const Outcome bad = run(conv.substr(0, conv.find("--reference")) +
                          "--reference rk4 --reference-rtol 1e-10 --out " + (dir / "bad").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--reference-rtol"), std::string::npos) << bad.err;
  EXPECT_EQ(lines(bad.err), 1) << bad.err;
  const Outcome times = run(kSolve + " --times 0.5,0.25");
  EXPECT_EQ(times.code, 2);
  EXPECT_NE(times.err.find("--times"), std::string::npos) << times.err;
  const auto csv = dir / "robertson.csv";
  const Outcome log =
      run("solve --model robertson --integrator cvode_bdf --t-end 1000 "
          "--log-outputs 4 --out " +
          csv.string());
  ASSERT_EQ(log.code, 0) << log.err;
  const auto rows = read_csv(csv);
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(join_cells(rows.front()), "t,y0,y1,y2");
  const char* decades[] = {"1", "10", "100", "1000"};  // one per decade, ending at t_end
  for (std::size_t i = 1; i < rows.size(); ++i) EXPECT_EQ(rows[i][0], decades[i - 1]);
  std::filesystem::remove_all(dir);
}

}  // namespace

// Stability limits: the command writes the stability.csv contract with
// ratios near 1 (symplectic Euler: 2/ω_max, docs/reference-values.md) and Euler marked
// unstable_for_all_h; a malformed --sweep and an unwritable --out are bad input before any run.
TEST(Cli, StabilityWritesContractFiles) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_stability_cli") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const Outcome o = run(
      "stability --model spring_chain --integrators symplectic_euler,euler --out " + dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto rows = read_csv(dir / "stability.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(join_cells(rows[0]),
            "model,integrator,param,value,h_max_measured,h_max_predicted,ratio,status,limit_kind,"
            "newton_iters,newton_conv_failures,error_test_failures,linear_setups,linear_iters,fe_"
            "evals,fi_evals");
  EXPECT_EQ(rows[1][1], "symplectic_euler");
  EXPECT_NEAR(std::stod(rows[1][6]), 1.0, 0.02);
  EXPECT_EQ(rows[2][1], "euler");
  EXPECT_EQ(rows[2][7], "unstable_for_all_h");
  EXPECT_TRUE(rows[2][4].empty());
  for (const char* f : {"stability.md", "stability.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  const Outcome bad =
      run("stability --model spring_chain --integrators rk4 --sweep k=1:10 --out " + dir.string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--sweep"), std::string::npos) << bad.err;
  EXPECT_EQ(lines(bad.err), 1) << bad.err;
  const Outcome unwritable =
      run("stability --model spring_chain --integrators rk4 --out /proc/nonexistent/x");
  EXPECT_EQ(unwritable.code, 2);
  EXPECT_NE(unwritable.err.find("--out"), std::string::npos) << unwritable.err;
  std::filesystem::remove_all(dir);
}

// stability on dahlquist (λ = −1: 2/ω = 2, so the largest step tried is 1000 × 2 = 2000): the
// A-stable trapezoidal rule gets one run there and is reported stable_up_to 2000 (a lower bound:
// limit_kind stable_up_to), rk4 its measured limit near the root 2.785294 of |R(−x)| = 1
// (limit_kind measured). --probe-unbounded searches the trapezoidal rule too: doubling from 2 to
// 2000 is 11 runs. A value given to the flag that is not a boolean is bad input.
TEST(Cli, StabilityChecksUnboundedMethodsAtTheLargestStepOnly) {
  using stiffbench::testing_support::fresh_dir;
  using stiffbench::testing_support::slurp;
  const auto dir = fresh_dir("cli", "stability_unbounded");
  const Outcome o =
      run("stability --model dahlquist --integrators rk4,trapezoidal --out " + dir.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const auto rows = read_csv(dir / "stability.csv");
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_GT(rows[0].size(), 8u);
  EXPECT_EQ(rows[0][7], "status");
  EXPECT_EQ(rows[0][8], "limit_kind");
  EXPECT_EQ(rows[1][1], "rk4");
  EXPECT_EQ(rows[1][7], "ok");
  EXPECT_EQ(rows[1][8], "measured");
  EXPECT_NEAR(std::stod(rows[1][4]) / 2.785294, 1.0, 0.01);
  EXPECT_EQ(rows[2][1], "trapezoidal");
  EXPECT_EQ(rows[2][5], "inf");
  EXPECT_EQ(rows[2][7], "stable_up_to");
  EXPECT_EQ(rows[2][8], "stable_up_to");
  EXPECT_DOUBLE_EQ(std::stod(rows[2][4]), 2000.0);
  const std::string json = slurp(dir / "stability.json");
  EXPECT_NE(json.find("\"search\": \"check_at_h_cap\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"probe_unbounded\": false"), std::string::npos);
  EXPECT_NE(slurp(dir / "stability.md").find("| >= 2.0000e+03 |"), std::string::npos);

  const auto probed = fresh_dir("cli", "stability_probed");
  const Outcome p =
      run("stability --model dahlquist --integrators trapezoidal --probe-unbounded --out " +
          probed.string());
  ASSERT_EQ(p.code, 0) << p.err;
  const std::string pjson = slurp(probed / "stability.json");
  EXPECT_NE(pjson.find("\"probe_unbounded\": true"), std::string::npos) << pjson;
  EXPECT_NE(pjson.find("\"search\": \"bisection\""), std::string::npos) << pjson;
  EXPECT_NE(pjson.find("\"probes\": 11"), std::string::npos) << pjson;
  const auto prows = read_csv(probed / "stability.csv");
  ASSERT_EQ(prows.size(), 2u);
  EXPECT_EQ(prows[1][7], "stable_up_to");
  EXPECT_DOUBLE_EQ(std::stod(prows[1][4]), 2000.0);

  const auto bad_dir = fresh_dir("cli", "stability_bad_flag");
  const Outcome bad =
      run("stability --model dahlquist --integrators trapezoidal --probe-unbounded=maybe --out " +
          bad_dir.string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("probe_unbounded"), std::string::npos) << bad.err;
  EXPECT_EQ(lines(bad.err), 1) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(bad_dir / "stability.csv"));
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(probed);
  std::filesystem::remove_all(bad_dir);
}
