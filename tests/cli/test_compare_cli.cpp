// `stiffbench compare OLD NEW` on real runs: a convergence study re-run with one coefficient of
// a method file perturbed (exit 1, the changed rows named), two identical work-precision runs
// (exit 0, wall times with both intervals and a verdict), bad input (exit 2, nothing written),
// and the run record's CPU model, thread count and seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/output/csv.hpp"
#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;
using testing_support::fresh_dir;
using testing_support::run_cli;
using testing_support::shell_quote;
using testing_support::slurp;

// Kutta's third-order method (b = 1/6, 2/3, 1/6) under its own name, with b1 and b3 as given.
// Moving δ from b3 to b1 keeps Σb = 1 but makes Σ b_i c_i = 1/2 - δ: the perturbed method has
// order 1 (and must claim it: method files are checked against their order), its error gaining
// a term proportional to δ·h.
fs::path write_kutta(const fs::path& dir, const std::string& b1, const std::string& b3, int order) {
  fs::create_directories(dir);
  const fs::path p = dir / "mykutta3.toml";
  std::ofstream(p) << "name = \"mykutta3\"\nkind = \"explicit_rk\"\norder = " << order << "\n"
                   << "description = \"Kutta's third-order method\"\n"
                   << "A = [[0, 0, 0], [\"1/2\", 0, 0], [-1, 2, 0]]\n"
                   << "b = [" << b1 << ", \"2/3\", " << b3 << "]\n"
                   << "c = [0, \"1/2\", 1]\n";
  return p;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::string at(std::size_t r, const std::string& col) const {
    const auto i = std::find(header.begin(), header.end(), col) - header.begin();
    return rows.at(r).at(static_cast<std::size_t>(i));
  }
};

Csv read_csv(const fs::path& p) {
  std::istringstream in(slurp(p));
  Csv c;
  std::string line;
  std::getline(in, line);
  c.header = parse_csv_line(line);
  while (std::getline(in, line))
    if (!line.empty()) c.rows.push_back(parse_csv_line(line));
  return c;
}

std::string convergence_args(const fs::path& method, const fs::path& out) {
  return "convergence --model harmonic_oscillator --integrators rk4," +
         shell_quote(method.string()) + " --t-end 1 --h 0.1 --levels 3 --out " +
         shell_quote(out.string());
}

TEST(CompareCli, PerturbedMethodFileExitsOneAndNamesTheRows) {
  const fs::path dir = fresh_dir("compare_cli", "perturbed");
  const fs::path kutta = write_kutta(dir / "m_old", "\"1/6\"", "\"1/6\"", 3);
  // δ = 1e-3: b1 = 1/6 + δ, b3 = 1/6 - δ.
  const fs::path perturbed =
      write_kutta(dir / "m_new", "0.16766666666666666", "0.16566666666666666", 1);
  ASSERT_EQ(run_cli(convergence_args(kutta, dir / "old")).code, 0);
  ASSERT_EQ(run_cli(convergence_args(perturbed, dir / "new")).code, 0);
  const auto o = run_cli("compare " + shell_quote((dir / "old").string()) + " " +
                         shell_quote((dir / "new").string()) + " --out " +
                         shell_quote((dir / "cmp").string()));
  EXPECT_EQ(o.code, 1) << o.err;
  // Every mykutta3 row is named on stderr with its error; the rk4 rows are not.
  for (const char* h : {"h=0.1", "h=0.05", "h=0.025"}) {
    const std::string name = std::string("integrator=mykutta3, ") + h;
    EXPECT_NE(o.err.find(name), std::string::npos) << name << "\n" << o.err;
  }
  EXPECT_EQ(o.err.find("integrator=rk4"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("error "), std::string::npos) << o.err;
  // The record names the changed method file (its hash in the spec).
  EXPECT_NE(o.out.find("spec.method_files.mykutta3.fnv1a64"), std::string::npos) << o.out;

  const Csv a = read_csv(dir / "old" / "convergence.csv");
  const Csv b = read_csv(dir / "new" / "convergence.csv");
  const Csv c = read_csv(dir / "cmp" / "compare.csv");
  std::map<std::string, double> ratio;  // h -> error ratio NEW/OLD of mykutta3
  for (std::size_t r = 0; r < c.rows.size(); ++r) {
    if (c.at(r, "file") != "convergence.csv") continue;  // convergence_orders.csv: the fits
    const std::string key = c.at(r, "row");
    const bool kutta_row = key.find("mykutta3") != std::string::npos;
    EXPECT_EQ(c.at(r, "status"), kutta_row ? "changed" : "same") << key;
    // Same stages and steps: f evaluations and every counter unchanged.
    EXPECT_EQ(c.at(r, "f_evals_ratio"), "1") << key;
    EXPECT_EQ(c.at(r, "counters"), "equal") << key;
    if (kutta_row) ratio[key.substr(key.find("h=") + 2)] = std::stod(c.at(r, "error_ratio"));
  }
  ASSERT_EQ(ratio.size(), 3u);
  // The ratio is the two tables' errors divided (an independent reading of both CSVs).
  for (std::size_t r = 0; r < a.rows.size(); ++r) {
    if (a.at(r, "integrator") != "mykutta3") continue;
    ASSERT_EQ(b.at(r, "h"), a.at(r, "h"));
    const double expected = std::stod(b.at(r, "error")) / std::stod(a.at(r, "error"));
    EXPECT_NEAR(ratio.at(a.at(r, "h")), expected, 1e-5 * expected);
  }
  // The original's error falls as h³, the perturbed one's O(δ·h) term as h: the ratio grows as
  // h shrinks.
  EXPECT_GT(ratio.at("0.05"), ratio.at("0.1"));
  EXPECT_GT(ratio.at("0.025"), ratio.at("0.05"));
  fs::remove_all(dir);
}

std::string wp_args(const fs::path& out) {
  return "work-precision --model harmonic_oscillator --integrators rk4,heun --t-end 1 --h 0.01 "
         "--levels 2 --repeats 5 --out " +
         shell_quote(out.string());
}

TEST(CompareCli, IdenticalWorkPrecisionRunsExitZeroWithTimingVerdicts) {
  const fs::path dir = fresh_dir("compare_cli", "identical");
  ASSERT_EQ(run_cli(wp_args(dir / "old")).code, 0);
  ASSERT_EQ(run_cli(wp_args(dir / "new")).code, 0);
  const auto o = run_cli("compare " + shell_quote((dir / "old").string()) + " " +
                         shell_quote((dir / "new").string()) + " --out " +
                         shell_quote((dir / "cmp").string()));
  EXPECT_EQ(o.code, 0) << o.err << o.out;
  EXPECT_NE(o.out.find("**Same results**"), std::string::npos) << o.out;
  const Csv a = read_csv(dir / "old" / "work_precision.csv");
  const Csv b = read_csv(dir / "new" / "work_precision.csv");
  const Csv c = read_csv(dir / "cmp" / "compare.csv");
  ASSERT_EQ(c.rows.size(), a.rows.size());
  ASSERT_EQ(a.rows.size(), 4u);  // 2 integrators x 2 levels
  for (std::size_t r = 0; r < c.rows.size(); ++r) {
    EXPECT_EQ(c.at(r, "status"), "same");
    EXPECT_EQ(c.at(r, "error_ratio"), "1");
    EXPECT_EQ(c.at(r, "time_column"), "wall_s_median");
    // Both intervals as the two work-precision tables recorded them.
    EXPECT_EQ(std::stod(c.at(r, "time_old_ci_low")), std::stod(a.at(r, "wall_s_ci_low")));
    EXPECT_EQ(std::stod(c.at(r, "time_new_ci_high")), std::stod(b.at(r, "wall_s_ci_high")));
    // The verdict follows from the intervals: disjoint ones (5 runs each) resolve, else not.
    const double ol = std::stod(a.at(r, "wall_s_ci_low")),
                 oh = std::stod(a.at(r, "wall_s_ci_high"));
    const double nl = std::stod(b.at(r, "wall_s_ci_low")),
                 nh = std::stod(b.at(r, "wall_s_ci_high"));
    const bool five = a.at(r, "repeats") == "5" && b.at(r, "repeats") == "5";
    const std::string expected = !five     ? c.at(r, "time_verdict")  // fewer runs: checked below
                                 : nh < ol ? "faster"
                                 : nl > oh ? "slower"
                                           : "not resolved (intervals overlap)";
    EXPECT_EQ(c.at(r, "time_verdict"), expected);
    if (!five) {
      EXPECT_EQ(c.at(r, "time_verdict").rfind("not resolved", 0), 0u);
    }
  }
  EXPECT_NE(o.out.find("OLD time [95% interval]"), std::string::npos) << o.out;

  // The run records: the CPU model as /proc/cpuinfo names it, the thread count and the seed.
  const auto rec = nlohmann::json::parse(slurp(dir / "old" / "work_precision.json"));
  EXPECT_EQ(rec.at("seed"), 1);
  EXPECT_TRUE(rec.at("threads").is_number_integer());
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown";
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  EXPECT_EQ(rec.at("cpu_model"), model);
  EXPECT_TRUE(rec.at("sundials_version").is_string());
  EXPECT_TRUE(rec.at("gsl_version").is_string());
  fs::remove_all(dir);
}

TEST(CompareCli, BadInputExitsTwoAndWritesNothing) {
  const fs::path dir = fresh_dir("compare_cli", "bad");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "b");
  std::ofstream(dir / "a" / "x.csv") << "model,error\nm,1\n";
  std::ofstream(dir / "b" / "y.csv") << "model,error\nm,1\n";
  std::ofstream(dir / "file.txt") << "not a folder\n";
  const auto q = [&](const std::string& s) { return shell_quote((dir / s).string()); };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"compare " + q("a") + " " + q("missing") + " --out " + q("out"), "missing"},
      {"compare " + q("file.txt") + " " + q("b") + " --out " + q("out"), "not a folder"},
      {"compare " + q("a") + " " + q("b") + " --out " + q("out"), "no CSV file"},
      {"compare " + q("a") + " " + q("b") + " --rtol -1 --out " + q("out"), "--rtol"},
      {"compare " + q("a") + " " + q("a") + " --out " + q("a/cmp"), "inside OLD"},
      {"compare " + q("a"), "new"}};
  for (const auto& [args, needle] : cases) {
    const auto o = run_cli(args);
    EXPECT_EQ(o.code, 2) << args << "\n" << o.err;
    EXPECT_NE(o.err.find(needle), std::string::npos) << args << "\n" << o.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << args;
    EXPECT_FALSE(fs::exists(dir / "a" / "cmp")) << args;
  }
  fs::remove_all(dir);
}

// A comparison already in --out is not replaced by one of other folders without --force.
TEST(CompareCli, OtherComparisonInOutIsKeptWithoutForce) {
  const fs::path dir = fresh_dir("compare_cli", "keep");
  for (const char* side : {"a", "b", "c"}) {
    fs::create_directories(dir / side);
    std::ofstream(dir / side / "x.csv")
        << "model,error\nm," << (side[0] == 'c' ? "2" : "1") << "\n";
  }
  const auto q = [&](const std::string& s) { return shell_quote((dir / s).string()); };
  // a and b hold the same table: exit 0.
  ASSERT_EQ(run_cli("compare " + q("a") + " " + q("b") + " --out " + q("out")).code, 0);
  const std::string first = slurp(dir / "out" / "compare.csv");
  const auto o = run_cli("compare " + q("a") + " " + q("c") + " --out " + q("out"));
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--force"), std::string::npos) << o.err;
  EXPECT_EQ(slurp(dir / "out" / "compare.csv"), first);
  // With --force: replaced; c's error 2 against a's 1 is a change (exit 1).
  EXPECT_EQ(run_cli("compare " + q("a") + " " + q("c") + " --out " + q("out") + " --force").code,
            1);
  EXPECT_NE(slurp(dir / "out" / "compare.csv").find("error 1 -> 2"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace stiffbench
