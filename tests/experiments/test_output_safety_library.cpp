// Output safety at the library level (experiments/output/output.hpp): the spec difference named in
// a refusal, check_existing_results, the study functions' and the report's checks of the output
// folder, and write_file_atomic's temporaries (the command line: tests/cli/test_output_safety.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include "core/types.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/output/output.hpp"
#include "experiments/studies/convergence.hpp"
#include "tests/cli_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace stiffbench;

using stiffbench::testing_support::slurp;

// Every file under `dir` with its bytes: "byte-identical, nothing added" is one comparison.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    s[fs::relative(e.path(), dir).string()] = e.is_regular_file() ? slurp(e.path()) : "<dir>";
  return s;
}

fs::path fresh_dir(const std::string& name) {
  return stiffbench::testing_support::fresh_dir("safety_library", name);
}

TEST(OutputSafetyLibrary, SpecDifferenceNamesTheFirstKey) {
  const nlohmann::json a = {{"model", "hires"}, {"params", {{"n", "8"}}}, {"h", 0.1}};
  nlohmann::json b = a;
  EXPECT_EQ(spec_difference(a, b), "");
  b["params"]["n"] = "16";
  EXPECT_EQ(spec_difference(a, b), "params.n = \"8\" there, \"16\" here");
  b = a;
  b.erase("h");
  EXPECT_EQ(spec_difference(a, b), "h = 0.1 there, (absent) here");
  // NaN (a flag not given) is recorded as null: the same spec.
  nlohmann::json nan = a, null = a;
  nan["h"] = std::numeric_limits<double>::quiet_NaN();
  null["h"] = nullptr;
  EXPECT_EQ(spec_difference(null, nan), "");
}

TEST(OutputSafetyLibrary, CheckExistingResults) {
  const fs::path dir = fresh_dir("lib");
  fs::create_directories(dir);
  const nlohmann::json spec = {{"model", "kepler"}};
  std::ostringstream note;
  // Nothing there, or only other experiments' files.
  std::ofstream(dir / "other.csv") << "x\n";
  EXPECT_FALSE(check_existing_results(dir, "a.json", {"a.csv"}, spec, false, &note));
  // A result without its record cannot be identified.
  std::ofstream(dir / "a.csv") << "x\n";
  EXPECT_THROW(check_existing_results(dir, "a.json", {"a.csv"}, spec, false, &note), BadInput);
  EXPECT_TRUE(check_existing_results(dir, "a.json", {"a.csv"}, spec, true, &note));
  // A record that is not JSON, or has no spec.
  std::ofstream(dir / "a.json") << "{not json";
  try {
    check_existing_results(dir, "a.json", {"a.csv"}, spec, false, &note);
    ADD_FAILURE() << "not refused";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "a.json", std::ios::trunc) << "{\"date\": \"today\"}";
  EXPECT_THROW(check_existing_results(dir, "a.json", {}, spec, false, &note), BadInput);
  // The same spec (whatever else the record holds) is replaced, with a note.
  std::ofstream(dir / "a.json", std::ios::trunc)
      << nlohmann::json{{"spec", spec}, {"date", "today"}, {"threads", 2}}.dump();
  note.str("");
  EXPECT_TRUE(check_existing_results(dir, "a.json", {"a.csv"}, spec, false, &note));
  EXPECT_NE(note.str().find("same spec"), std::string::npos) << note.str();
  // A different one is refused, naming the folder, the file and the key.
  try {
    check_existing_results(dir, "a.json", {"a.csv"}, {{"model", "hires"}}, false, &note);
    ADD_FAILURE() << "not refused";
  } catch (const BadInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("--out " + dir.string()), std::string::npos) << m;
    EXPECT_NE(m.find((dir / "a.json").string()), std::string::npos) << m;
    EXPECT_NE(m.find("model = \"kepler\" there, \"hires\" here"), std::string::npos) << m;
  }
  fs::remove_all(dir);
}

// The library's study functions make the same check, with force_output() as --force.
TEST(OutputSafetyLibrary, StudyFunctionsCheckTheFolder) {
  const fs::path dir = fresh_dir("study");
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  std::ostringstream err;
  convergence_study(spec, dir.string(), false, nullptr, err);
  const auto before = snapshot(dir);
  ConvergenceSpec other = spec;
  other.integrators = {"heun"};
  EXPECT_THROW(convergence_study(other, dir.string(), false, nullptr, err), BadInput);
  EXPECT_EQ(snapshot(dir), before);
  set_force_output(true);
  EXPECT_NO_THROW(convergence_study(other, dir.string(), false, nullptr, err));
  set_force_output(false);
  EXPECT_NE(err.str().find("(--force)"), std::string::npos) << err.str();
  fs::remove_all(dir);
}

// report records {"suite": quick|full} in DIR/report.json and refuses the other suite before
// anything runs (a full report would take minutes); the same suite passes the check.
TEST(OutputSafetyLibrary, ReportRefusesTheOtherSuite) {
  const fs::path dir = fresh_dir("report");
  fs::create_directories(dir);
  ReportOptions full;
  full.out_dir = dir.string();
  ReportOptions quick = full;
  quick.quick = true;
  std::ofstream(dir / "report.json") << run_metadata("report", report_spec(quick)).dump(2);
  std::ofstream(dir / "REPORT.md") << "# stiffbench report\n";
  const auto before = snapshot(dir);
  std::ostringstream out, err;
  try {
    cmd_report(full, out, err);
    ADD_FAILURE() << "not refused";
  } catch (const BadInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("suite = \"quick\" there, \"full\" here"), std::string::npos) << m;
    EXPECT_NE(m.find("--force"), std::string::npos) << m;
  }
  EXPECT_EQ(snapshot(dir), before);
  EXPECT_TRUE(check_existing_results(dir, "report.json", {"REPORT.md"}, report_spec(quick), false,
                                     nullptr));
  fs::remove_all(dir);
}

// write_file_atomic: the temporary is hidden and per process (a user's NAME.tmp is not touched)
// and removed when the write fails (here: the rename onto a folder that is not empty).
// A Markdown cell holding '|' (a stability note quoting |E0|) or a line break keeps the table's
// shape: each row has as many unescaped '|' as the header (columns + 1).
TEST(OutputSafetyLibrary, MarkdownCellsKeepTheTableShape) {
  const Table t{{"a", "b|c"}, {{"energy exceeded 2 x |E0| at t = 1", "two\nlines"}, {"", "x"}}};
  const std::string md = t.to_markdown();
  std::istringstream lines(md);
  std::string line;
  std::vector<std::string> all;
  while (std::getline(lines, line)) all.push_back(line);
  ASSERT_EQ(all.size(), 4u);  // header, rule, two rows
  for (const std::string& l : all) {
    int bars = 0;
    for (std::size_t i = 0; i < l.size(); ++i)
      if (l[i] == '|' && (i == 0 || l[i - 1] != '\\')) ++bars;
    EXPECT_EQ(bars, 3) << l;
  }
  EXPECT_EQ(all[2], "| energy exceeded 2 x \\|E0\\| at t = 1 | two lines |");
}

TEST(OutputSafetyLibrary, WriteFileAtomicLeavesNoTemporary) {
  const fs::path dir = fresh_dir("atomic");
  fs::create_directories(dir / "busy");
  std::ofstream(dir / "busy" / "x") << "x";
  std::ofstream(dir / "table.csv.tmp") << "the user's";
  write_file_atomic(dir / "table.csv", "a,b\n");
  EXPECT_EQ(slurp(dir / "table.csv"), "a,b\n");
  EXPECT_EQ(slurp(dir / "table.csv.tmp"), "the user's");
  EXPECT_THROW(write_file_atomic(dir / "busy", "text"), std::exception);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"busy", "table.csv", "table.csv.tmp"}));
  fs::remove_all(dir);
}

}  // namespace

namespace {

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// AtomicFileStream (solve's trajectory, written as the run goes): PATH keeps its old content until
// commit(); a stream destroyed without commit() leaves PATH as it was and removes its temporary.
TEST(OutputSafetyLibrary, AtomicFileStreamPublishesOnlyOnCommit) {
  const fs::path dir = fresh_dir("atomic_stream");
  fs::create_directories(dir);
  std::ofstream(dir / "traj.csv") << "old\n";
  {
    AtomicFileStream f(dir / "traj.csv");
    f.stream() << "new\n";
    f.stream().flush();
    EXPECT_EQ(names_in(dir).size(), 2u);  // the temporary exists beside the file
    EXPECT_EQ(slurp(dir / "traj.csv"), "old\n");
  }
  EXPECT_EQ(slurp(dir / "traj.csv"), "old\n");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"traj.csv"});
  {
    AtomicFileStream f(dir / "traj.csv");
    f.stream() << "t,y0\n0,1\n";
    f.commit();
  }
  EXPECT_EQ(slurp(dir / "traj.csv"), "t,y0\n0,1\n");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"traj.csv"});
  fs::remove_all(dir);
}

// trajectory_bytes_bound against a real file: solve's trajectory of a small cloth is not larger
// than the bound, and the bound is exactly the size of a table of the same shape in which every
// number is the longest the shortest round-trip form writes (-2.2250738585072014e-308, 24
// characters), built here independently of the formula: the bound is tight.
TEST(OutputSafetyLibrary, TrajectoryBoundHoldsAndIsTheWorstCase) {
  const fs::path dir = fresh_dir("trajectory_bound");
  fs::create_directories(dir);
  SolveOptions opt;
  opt.model = "cloth";
  opt.params = Params::from_assignments({"n=4"});
  opt.integrator = "rk4";
  opt.h = 1e-3;
  opt.t_end = 0.01;
  opt.outputs = 5;
  opt.out_csv = (dir / "traj.csv").string();
  std::ostringstream out, err;
  cmd_solve(opt, out, err);
  const std::string text = slurp(dir / "traj.csv");
  const auto columns = std::count(text.begin(), text.begin() + text.find('\n'), ',') + 1;
  const long rows = std::count(text.begin(), text.end(), '\n') - 1;
  ASSERT_EQ(rows, 6);  // outputs at 5 equal intervals and t0
  const Index dim = columns - 1;
  std::string worst = "t";
  for (Index i = 0; i < dim; ++i) worst += ",y" + std::to_string(i);
  worst += "\n";
  const std::string longest = "-2.2250738585072014e-308";
  ASSERT_EQ(longest.size(), 24u);
  for (long r = 0; r < rows; ++r)
    for (Index c = 0; c < columns; ++c) worst += longest + (c + 1 < columns ? "," : "\n");
  EXPECT_EQ(trajectory_bytes_bound(rows, dim), static_cast<double>(worst.size()));
  EXPECT_LE(static_cast<double>(text.size()), trajectory_bytes_bound(rows, dim));
  EXPECT_EQ(err.str().find("up to"), std::string::npos) << err.str();  // small: no note
  fs::remove_all(dir);
}

}  // namespace
