// Method files on the command line: a path wherever an integrator name is taken
// (--integrators, solve --integrator, spec files), the search path (--methods DIR,
// STIFFBENCH_METHOD_PATH) in `list` and `describe`, and bad files (exit 2, one message naming
// the file). gtest_discover_tests runs every test in its own process, so the registrations of one
// test do not reach another.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_main.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/output/csv.hpp"
#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;
using testing_support::fresh_dir;
using testing_support::run_cli;
using testing_support::shell_quote;
using testing_support::slurp;

const char* kHeun3 = R"toml(name = "heun3"
kind = "explicit_rk"
order = ORDER
description = "Heun's third-order method"
A = [[0, 0, 0], ["1/3", 0, 0], [0, "2/3", 0]]
b = ["1/4", 0, "3/4"]
c = [0, "1/3", "2/3"]
)toml";

// Writes dir/file with heun3's coefficients under `name`, claiming `order`.
fs::path write_heun3(const fs::path& dir, const std::string& file, int order = 3,
                     const std::string& name = "heun3") {
  fs::create_directories(dir);
  std::string text = kHeun3;
  text.replace(text.find("ORDER"), 5, std::to_string(order));
  text.replace(text.find("heun3"), 5, name);
  const fs::path p = dir / file;
  std::ofstream(p) << text;
  return p;
}

int cli(std::vector<std::string> args) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return cli_main(static_cast<int>(argv.size()), argv.data());
}

// Kepler with e = 0.5 over one period (exact solution), h = 0.05 / 2^k: heun3's error falls by
// 2³ per halving (observed 3.04, 3.02 and 3.01 from the first to the last pair; the circular
// orbit, e = 0, hides the h³ term over a whole period and is not used).
TEST(MethodFilesCli, ConvergenceByPath) {
  const fs::path dir = fresh_dir("methods", "convergence");
  const fs::path file = write_heun3(dir, "heun3.toml");
  const fs::path out = dir / "out";
  ASSERT_EQ(cli({"convergence", "--model", "kepler", "--integrators", file.string() + ",rk4",
                 "--param", "e=0.5", "--t-end", "6.283185307179586", "--h", "0.05", "--levels", "4",
                 "--out", out.string()}),
            0);
  const std::string md = slurp(out / "convergence.md");
  EXPECT_NE(md.find("| kepler | heun3 | 3 |"), std::string::npos) << md;
  std::istringstream csv(slurp(out / "convergence.csv"));
  std::string line;
  std::getline(csv, line);
  const std::vector<std::string> header = parse_csv_line(line);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  double last = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> row = parse_csv_line(line);
    if (row.at(col("integrator")) == "heun3" && !row.at(col("observed_order")).empty())
      last = std::stod(row.at(col("observed_order")));
  }
  EXPECT_NEAR(last, 3.0, 0.1);
  // The spec records the file and its text's hash, so that a changed file is a different spec.
  const std::string json = slurp(out / "convergence.json");
  EXPECT_NE(json.find("\"method_files\""), std::string::npos);
  EXPECT_NE(json.find(file.string()), std::string::npos);
  // The same file given again (here by the same path) is registered once.
  EXPECT_EQ(resolve_integrator_tokens({file.string()}).front(), "heun3");
}

TEST(MethodFilesCli, OverclaimedOrderExitsTwoNamingTheFile) {
  const fs::path dir = fresh_dir("methods", "overclaimed");
  const fs::path file = write_heun3(dir, "heun3.toml", 4);
  const auto r =
      run_cli("convergence --model kepler --t-end 1 --integrators " + shell_quote(file.string()) +
              " --out " + shell_quote((dir / "out").string()));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(file.string() + ":3: key 'order'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("order 4 claimed but the condition of tree [t^3]"), std::string::npos)
      << r.err;
  // One message (one line), and nothing was written.
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "convergence.csv"));
}

// A method file studied by work-precision cannot also be its reference: given by path in both
// flags, or by path in one and by its registered name in the other, the method is the same.
// Exit 2, one message naming --reference, nothing written. As a reference of other methods the
// file is accepted.
TEST(MethodFilesCli, WorkPrecisionRefusesAMethodFileAsItsOwnReference) {
  const fs::path dir = fresh_dir("methods", "wp_self_reference");
  const fs::path file = write_heun3(dir, "heun3.toml");
  const std::string path = shell_quote(file.string());
  const std::string common =
      "work-precision --model harmonic_oscillator --t-end 1 --h 0.1 "
      "--levels 2 --repeats 1 --out " +
      shell_quote((dir / "out").string());
  for (const std::string& pair : {"--integrators " + path + " --reference " + path,
                                  "--integrators rk4," + path + " --reference heun3",
                                  "--integrators heun3.toml --reference " + path}) {
    const auto r = run_cli(common + " " + pair, dir);
    EXPECT_EQ(r.code, 2) << pair << "\n" << r.err;
    EXPECT_NE(r.err.find("is also one of --integrators"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out" / "work_precision.csv")) << pair;
  }
  const auto ok = run_cli(common + " --integrators rk4 --reference " + path, dir);
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(slurp(dir / "out" / "work_precision.json").find("\"kind\": \"numerical\""),
            std::string::npos);
  fs::remove_all(dir);
}

// A Rosenbrock file with its [constants] first (ROS2 of Verwer et al. 1999, γ = 1 + 1/√2)
// analysed by path: it loads, and its W-order 2 (by hand: bᵀα1 = 1/2, bᵀΓ1 = γ − γ = 0) is
// printed with its claim. The same file with a key of another kind after the header exits 2
// with one message naming the table, and nothing is written.
TEST(MethodFilesCli, ConstantsFirstRosenbrockByPathAndMisplacedKey) {
  const fs::path dir = fresh_dir("methods", "constants_first");
  fs::create_directories(dir);
  const std::string text = R"toml([constants]
g = "1 + 1/sqrt(2)"

name = "my_ros2"
kind = "rosenbrock"
order = 2
w_order = 2
description = "ROS2, constants first"
gamma = "g"
alpha = [[0, 0], [1, 0]]
gamma_offdiag = [[0, 0], ["-2*g", 0]]
b = ["1/2", "1/2"]
)toml";
  const fs::path file = dir / "ros2.toml";
  std::ofstream(file) << text;
  const auto ok = run_cli("analyze " + shell_quote(file.string()) + " --out " +
                          shell_quote((dir / "out").string()));
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find("| my_ros2 | rosenbrock | 2 | 2 |"), std::string::npos) << ok.out;

  const fs::path bad = dir / "bad.toml";
  std::ofstream(bad) << text << "fsal = true\n";
  const auto r = run_cli("analyze " + shell_quote(bad.string()) + " --out " +
                         shell_quote((dir / "out_bad").string()));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(bad.string() + ":13: key 'fsal' is inside the table [constants]"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out_bad" / "analyze.csv"));
}

TEST(MethodFilesCli, SearchPathInListAndDescribe) {
  const fs::path dir = fresh_dir("methods", "search");
  write_heun3(dir, "heun3.toml");
  const auto list = run_cli("--methods " + shell_quote(dir.string()) + " list integrators");
  EXPECT_EQ(list.code, 0) << list.err;
  EXPECT_NE(list.out.find("| heun3 |"), std::string::npos) << list.out;
  EXPECT_NE(list.out.find("from method files: heun3 (" + (dir / "heun3.toml").string() + ")"),
            std::string::npos)
      << list.out;
  ::setenv("STIFFBENCH_METHOD_PATH", ("/nonexistent_stiffbench:" + dir.string()).c_str(), 1);
  const auto bad_folder = run_cli("describe heun3");
  EXPECT_EQ(bad_folder.code, 2);
  EXPECT_NE(
      bad_folder.err.find("STIFFBENCH_METHOD_PATH: '/nonexistent_stiffbench' is not a folder"),
      std::string::npos)
      << bad_folder.err;
  ::setenv("STIFFBENCH_METHOD_PATH", (":" + dir.string() + ":").c_str(), 1);
  const auto describe = run_cli("describe heun3");
  EXPECT_EQ(describe.code, 0) << describe.err;
  EXPECT_NE(describe.out.find("source: " + (dir / "heun3.toml").string()), std::string::npos)
      << describe.out;
  // A bad file on the search path: exit 2 naming it, whatever the command.
  write_heun3(dir, "zz_bad.toml", 4, "heun3_bad");
  const auto bad = run_cli("list models");
  ::unsetenv("STIFFBENCH_METHOD_PATH");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find((dir / "zz_bad.toml").string() + ":3:"), std::string::npos) << bad.err;
}

// A method file whose name is not UTF-8, found on the search path: exit 2 before anything runs,
// the name shown with its bytes escaped (the run's JSON record could not hold it).
TEST(MethodFilesCli, ANonUtf8FileNameOnTheSearchPathIsBadInput) {
  const fs::path dir = fresh_dir("methods", "non_utf8");
  write_heun3(dir, std::string("heun3_\xff.toml"));
  const auto r = run_cli("--methods " + shell_quote(dir.string()) + " list integrators");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("heun3_\\xff.toml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not valid UTF-8"), std::string::npos) << r.err;
}

TEST(MethodFilesCli, NameClashesAreBadInput) {
  const fs::path dir = fresh_dir("methods", "clash");
  const fs::path rk4 = write_heun3(dir, "rk4.toml", 3, "rk4");
  std::string msg;
  try {
    resolve_integrator_tokens({rk4.string()});
  } catch (const BadInput& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find(rk4.string() + ": method 'rk4' is the name of a built-in integrator"),
            std::string::npos)
      << msg;
  // Two different files defining one name.
  const fs::path a = write_heun3(dir, "a.toml", 3, "heun3_clash");
  fs::create_directories(dir / "b");
  std::string other = slurp(a);
  other.replace(other.find("Heun's"), 6, "Another");
  std::ofstream(dir / "b" / "heun3.toml") << other;
  EXPECT_EQ(resolve_integrator_tokens({a.string(), "rk4"}),
            (std::vector<std::string>{"heun3_clash", "rk4"}));
  msg.clear();
  try {
    resolve_integrator_tokens({(dir / "b" / "heun3.toml").string()});
  } catch (const BadInput& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("method 'heun3_clash' is already defined by " + a.string()), std::string::npos)
      << msg;
}

// solve --integrator PATH, and a spec file naming a method file relative to its own folder.
TEST(MethodFilesCli, SolveAndSpecFiles) {
  const fs::path dir = fresh_dir("methods", "solve");
  const fs::path file = write_heun3(dir / "methods", "heun3.toml");
  const auto solve = run_cli("solve --model kepler --integrator " + shell_quote(file.string()) +
                             " --t-end 1 --h 0.01");
  EXPECT_EQ(solve.code, 0) << solve.err;
  EXPECT_NE(solve.out.find("integrator   heun3"), std::string::npos) << solve.out;
  std::ofstream(dir / "spec.toml") << "kind = \"convergence\"\nmodel = \"kepler\"\n"
                                      "integrators = [\"methods/heun3.toml\"]\n"
                                      "t_end = 1.0\nh = 0.05\nlevels = 2\n";
  const auto run = run_cli("run " + shell_quote((dir / "spec.toml").string()) + " --out " +
                           shell_quote((dir / "out").string()));
  EXPECT_EQ(run.code, 0) << run.err;
  EXPECT_NE(slurp(dir / "out" / "convergence.csv").find("heun3"), std::string::npos);
}

}  // namespace
}  // namespace stiffbench
