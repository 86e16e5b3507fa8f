// Output safety (issue 14, README "Existing results: --force and --resume"): a second run of
// every command into a folder holding results of a different spec exits 2 naming the folder and
// --force and leaves every file as it was; the same spec is recomputed and replaced; --force
// replaces; `run` needs --resume or --force for units of its own spec. Runs the real binary
// like test_cli.cpp, plus the library-level check (experiments/output.hpp) and
// write_file_atomic's temporaries.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include "core/types.hpp"
#include "experiments/commands.hpp"
#include "experiments/convergence.hpp"
#include "experiments/output.hpp"
#include "tests/cli_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace stiffbench;

using Outcome = stiffbench::testing_support::CliOutcome;
using stiffbench::testing_support::slurp;
Outcome run(const std::string& args) { return stiffbench::testing_support::run_cli(args); }

// Every file under `dir` with its bytes: "byte-identical, nothing added" is one comparison.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    s[fs::relative(e.path(), dir).string()] = e.is_regular_file() ? slurp(e.path()) : "<dir>";
  return s;
}

fs::path fresh_dir(const std::string& name) {
  return stiffbench::testing_support::fresh_dir("safety", name);
}

long lines(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

struct SafetyCase {
  const char* label;
  std::string first, other;  // two specs of one command (without --out)
  std::string differs;       // the spec key the refusal names
};

void PrintTo(const SafetyCase& c, std::ostream* os) { *os << c.first; }

class OutputSafety : public ::testing::TestWithParam<SafetyCase> {};

TEST_P(OutputSafety, DifferentSpecRefusedSameSpecReplacedForceReplaces) {
  const SafetyCase& c = GetParam();
  const fs::path dir = fresh_dir(c.label);
  const std::string out = " --out " + dir.string();
  const Outcome first = run(c.first + out);
  ASSERT_EQ(first.code, 0) << first.err;
  const auto before = snapshot(dir);

  const Outcome other = run(c.other + out);
  EXPECT_EQ(other.code, 2) << other.err;
  EXPECT_NE(other.err.find("--out " + dir.string() + " holds results of a different spec"),
            std::string::npos)
      << other.err;
  EXPECT_NE(other.err.find(c.differs + " = "), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("--force"), std::string::npos) << other.err;
  EXPECT_EQ(lines(other.err), 1) << other.err;
  EXPECT_EQ(snapshot(dir), before) << "files changed by a refused run: " << c.other;

  const Outcome same = run(c.first + out);
  EXPECT_EQ(same.code, 0) << same.err;
  EXPECT_NE(same.err.find("same spec"), std::string::npos) << same.err;

  const Outcome forced = run(c.other + out + " --force");
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_NE(forced.err.find("(--force)"), std::string::npos) << forced.err;
  // The folder now holds the other spec: the first one is the different one.
  const Outcome back = run(c.first + out);
  EXPECT_EQ(back.code, 2) << back.err;
  fs::remove_all(dir);
}

const std::string kHo = "--model harmonic_oscillator ";

INSTANTIATE_TEST_SUITE_P(
    Issue14, OutputSafety,
    ::testing::Values(
        SafetyCase{"convergence",
                   "convergence " + kHo + "--integrators rk4 --t-end 1 --h 0.1 --levels 2",
                   "convergence " + kHo + "--integrators euler --t-end 1 --h 0.1 --levels 2",
                   "integrators"},
        SafetyCase{"local_error", "local-error " + kHo + "--integrators rk4 --h 0.1 --levels 2",
                   "local-error " + kHo + "--integrators rk4 --h 0.2 --levels 2", "h"},
        SafetyCase{"work_precision",
                   "work-precision " + kHo +
                       "--integrators rk4 --t-end 1 --h 0.1 --levels 2 --tol-levels 2 "
                       "--repeats 1",
                   "work-precision " + kHo +
                       "--integrators rk4 --t-end 1 --h 0.1 --levels 3 --tol-levels 2 "
                       "--repeats 1",
                   "levels"},
        SafetyCase{"stability",
                   "stability --model spring_chain --param n=4 --integrators symplectic_euler",
                   "stability --model spring_chain --param n=5 --integrators symplectic_euler",
                   "params.n"},
        SafetyCase{"energy", "energy " + kHo + "--integrators rk4 --h 0.1 --t-end 1",
                   "energy " + kHo + "--integrators rk4 --h 0.1 --t-end 2", "t_end"},
        SafetyCase{"region", "region --integrators rk4 --resolution 20",
                   "region --integrators heun --resolution 20", "integrators"},
        SafetyCase{"solve_frames", "solve " + kHo + "--integrator rk4 --h 0.1 --t-end 1 --frames 2",
                   "solve " + kHo + "--integrator rk4 --h 0.1 --t-end 1 --frames 3", "frames"}),
    [](const ::testing::TestParamInfo<SafetyCase>& i) { return std::string(i.param.label); });

// A study writes only its own files: a convergence run into a folder holding a work-precision
// study of another model is not a conflict, and leaves that study alone.
TEST(OutputSafety, OtherExperimentsFilesDoNotCount) {
  const fs::path dir = fresh_dir("mixed");
  const std::string out = " --out " + dir.string();
  ASSERT_EQ(run("work-precision --model dahlquist --integrators rk4 --t-end 1 --h 0.1 --levels 2 "
                "--tol-levels 2 --repeats 1" +
                out)
                .code,
            0);
  const std::string wp = slurp(dir / "work_precision.json");
  const Outcome conv =
      run("convergence " + kHo + "--integrators rk4 --t-end 1 --h 0.1 --levels 2" + out);
  EXPECT_EQ(conv.code, 0) << conv.err;
  EXPECT_EQ(conv.err.find("note:"), std::string::npos) << conv.err;
  EXPECT_EQ(slurp(dir / "work_precision.json"), wp);
  fs::remove_all(dir);
}

// solve --out FILE.csv records no spec: an existing FILE is refused (whatever it holds) unless
// --force.
TEST(OutputSafety, SolveTrajectoryFileNeedsForce) {
  const fs::path dir = fresh_dir("solve_file");
  const fs::path csv = dir / "traj.csv";
  const std::string solve =
      "solve " + kHo + "--integrator rk4 --h 0.1 --t-end 1 --out " + csv.string();
  ASSERT_EQ(run(solve).code, 0);
  const auto before = snapshot(dir);
  for (const std::string& again : {solve, solve + " --outputs 5"}) {
    const Outcome o = run(again);
    EXPECT_EQ(o.code, 2) << o.err;
    EXPECT_NE(o.err.find("--out " + csv.string() + " exists"), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("--force"), std::string::npos) << o.err;
    EXPECT_EQ(lines(o.err), 1) << o.err;
    EXPECT_TRUE(o.out.empty()) << o.out;
    EXPECT_EQ(snapshot(dir), before);
  }
  const Outcome forced = run(solve + " --outputs 5 --force");
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_EQ(lines(slurp(csv)), 1 + 6);  // header + 6 rows
  fs::remove_all(dir);
}

// A fresh DIR with DIR/tiny.toml: a convergence sweep of 2 units (rk4, euler), 2 levels each.
fs::path tiny_spec(const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path spec = dir / "tiny.toml";
  std::ofstream(spec) << "kind = \"convergence\"\nmodel = \"harmonic_oscillator\"\n"
                         "integrators = [\"rk4\", \"euler\"]\nt_end = 1\nh = 0.1\nlevels = 2\n";
  return spec;
}

// run: a different spec is refused unless --force; units of the same spec need --resume (runs
// the missing ones) or --force (starts over).
TEST(OutputSafety, RunNeedsResumeOrForce) {
  const fs::path dir = fresh_dir("run");
  const fs::path spec = tiny_spec(dir);
  const fs::path out = dir / "out";
  const std::string cmd = "run " + spec.string() + " --out " + out.string();
  ASSERT_EQ(run(cmd).code, 0);
  const std::string full = slurp(out / "convergence.csv");
  auto before = snapshot(out);

  const Outcome same = run(cmd);
  EXPECT_EQ(same.code, 2) << same.err;
  EXPECT_NE(same.err.find("holds 2 of 2 unit(s) of this spec"), std::string::npos) << same.err;
  EXPECT_NE(same.err.find("--resume"), std::string::npos) << same.err;
  EXPECT_NE(same.err.find("--force"), std::string::npos) << same.err;
  EXPECT_EQ(snapshot(out), before);

  const Outcome other = run(cmd + " --set t_end=2");
  EXPECT_EQ(other.code, 2) << other.err;
  EXPECT_NE(other.err.find("holds results of a different spec"), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("t_end = 1 there, 2 here"), std::string::npos) << other.err;
  EXPECT_EQ(snapshot(out), before);
  const Outcome both = run(cmd + " --resume --force");
  EXPECT_EQ(both.code, 2) << both.err;
  EXPECT_EQ(snapshot(out), before);

  // Keep unit 0 only (header + its 2 rows): --resume runs unit 1.
  {
    std::istringstream in(full);
    std::string line, kept;
    for (int i = 0; i < 3 && std::getline(in, line); ++i) kept += line + "\n";
    std::ofstream(out / "convergence.csv", std::ios::binary | std::ios::trunc) << kept;
  }
  const Outcome resumed = run(cmd + " --resume");
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resume: 1 of 2 unit(s) already done"), std::string::npos)
      << resumed.out;
  EXPECT_EQ(lines(slurp(out / "convergence.csv")), lines(full));

  const Outcome forced = run(cmd + " --set t_end=2 --force");
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_NE(slurp(out / "run.json").find("\"t_end\": 2"), std::string::npos);
  fs::remove_all(dir);
}

// merge: an --out folder holding a merged run of a different spec is refused unless --force.
TEST(OutputSafety, MergeRefusesAnotherSpecUnlessForce) {
  const fs::path dir = fresh_dir("merge");
  const fs::path spec = tiny_spec(dir);
  const std::string base = "run " + spec.string();
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(run(base + " --shard " + std::to_string(i) + "/2 --out " +
                  (dir / ("s" + std::to_string(i))).string())
                  .code,
              0);
  ASSERT_EQ(run(base + " --set t_end=2 --out " + (dir / "t2").string()).code, 0);
  const std::string merged = (dir / "merged").string();
  const std::string shards = " " + (dir / "s0").string() + " " + (dir / "s1").string();
  ASSERT_EQ(run("merge --out " + merged + shards).code, 0);
  const auto before = snapshot(merged);
  const Outcome same = run("merge --out " + merged + shards);
  EXPECT_EQ(same.code, 0) << same.err;
  EXPECT_NE(same.err.find("same spec"), std::string::npos) << same.err;
  const Outcome other = run("merge --out " + merged + " " + (dir / "t2").string());
  EXPECT_EQ(other.code, 2) << other.err;
  EXPECT_NE(other.err.find("--out " + merged + " holds results of a different spec"),
            std::string::npos)
      << other.err;
  EXPECT_NE(other.err.find("--force"), std::string::npos) << other.err;
  EXPECT_EQ(snapshot(merged), before);
  const Outcome forced = run("merge --force --out " + merged + " " + (dir / "t2").string());
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_NE(slurp(dir / "merged" / "run.json").find("\"t_end\": 2"), std::string::npos);
  fs::remove_all(dir);
}

// ---- library level --------------------------------------------------------------------------

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
