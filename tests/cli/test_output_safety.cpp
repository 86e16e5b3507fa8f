// Output safety (README "Existing results: --force and --resume"): a second run of every command
// into a folder holding results of a different spec exits 2 naming the folder and --force and
// leaves every file as it was; the same spec is recomputed and replaced; --force replaces; `run`
// needs --resume or --force for units of its own spec. Runs the real binary like test_cli.cpp;
// the library-level check is in tests/experiments/test_output_safety_library.cpp.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
    EveryCommand, OutputSafety,
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

}  // namespace

namespace {

const std::string kSmallConvergence =
    "convergence --model harmonic_oscillator --integrators rk4,heun --t-end 1 --h 0.1 --levels 3";

bool have_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

// A PNG is complete when it ends with its IEND chunk (PNG specification, Sect. 11.2.5: length 0,
// type IEND, CRC ae 42 60 82).
bool complete_png(const fs::path& p) {
  const std::string b = slurp(p);
  static const std::string iend("\x00\x00\x00\x00IEND\xae\x42\x60\x82", 12);
  return b.size() > iend.size() && b.compare(b.size() - iend.size(), iend.size(), iend) == 0;
}

}  // namespace

// Symlinks planted under the names the testbed writes (the write probe's old fixed name, a
// temporary's, the outputs') never have their target changed: probes and temporaries are created
// exclusively under random names, outputs are renamed over the link (which replaces the link).
TEST(OutputSafety, SymlinksInTheOutputFolderNeverChangeTheirTarget) {
  const fs::path base = stiffbench::testing_support::fresh_dir("safety", "symlinks");
  fs::create_directories(base / "R");
  const fs::path victim = base / "victim.txt";
  std::ofstream(victim) << "precious\n";
  for (const char* name : {".stiffbench_write_test", ".convergence.csv.tmp.0", "convergence.png",
                           "convergence.md", "convergence.csv", "convergence.json"})
    fs::create_symlink(victim, base / "R" / name);
  // Links under the result names are results that cannot be identified: refused, then replaced
  // with --force.
  const Outcome refused = run(kSmallConvergence + " --out " + (base / "R").string());
  EXPECT_EQ(refused.code, 2) << refused.err;
  EXPECT_EQ(slurp(victim), "precious\n");
  const Outcome forced = run(kSmallConvergence + " --out " + (base / "R").string() + " --force");
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_EQ(slurp(victim), "precious\n");
  EXPECT_FALSE(fs::is_symlink(base / "R" / "convergence.csv"));
  EXPECT_NE(slurp(base / "R" / "convergence.csv").find("rk4"), std::string::npos);
  EXPECT_TRUE(fs::is_symlink(base / "R" / ".stiffbench_write_test"));  // left alone
  fs::remove_all(base);
}

// Shell characters in --out reach gnuplot as given (no shell between): the plot lands in that
// folder, and no folder named by what a shell would have made of the path is written.
TEST(OutputSafety, ShellCharactersInOutReachThePlots) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot not installed";
  const fs::path base = stiffbench::testing_support::fresh_dir("safety", "shell_chars");
  fs::create_directories(base);
  const fs::path out = base / "R$x\"y'z`w`\\v";
  const Outcome o =
      run(kSmallConvergence + " --out " + stiffbench::testing_support::shell_quote(out.string()));
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(complete_png(out / "convergence.png"));
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(base)) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1u);  // only the folder given
  fs::remove_all(base);
}

// A full disk: on a 32 KiB tmpfs the tables fit and the plot does not; the command exits
// non-zero naming ENOSPC, and no file under a final name is incomplete (the PNG, when present, is
// whole). Needs root for the mount; skipped elsewhere.
TEST(OutputSafety, AFullDiskLeavesNoIncompleteFileAndSaysSo) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot not installed";
  const fs::path mnt = stiffbench::testing_support::fresh_dir("safety", "tmpfs");
  fs::create_directories(mnt);
  if (::geteuid() != 0 ||
      std::system(("mount -t tmpfs -o size=32k tmpfs " + mnt.string() + " 2>/dev/null").c_str()) !=
          0) {
    fs::remove_all(mnt);
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root)";
  }
  const Outcome o =
      run("convergence --model harmonic_oscillator --integrators rk4,heun,euler,midpoint "
          "--t-end 1 --h 0.1 --levels 6 --out " +
          (mnt / "R").string());
  EXPECT_NE(o.code, 0) << o.err;
  EXPECT_NE(o.err.find("No space left on device"), std::string::npos) << o.err;
  if (fs::exists(mnt / "R" / "convergence.png")) {
    EXPECT_TRUE(complete_png(mnt / "R" / "convergence.png"));
  }
  for (const auto& e : fs::directory_iterator(mnt / "R"))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  std::system(("umount " + mnt.string()).c_str());
  fs::remove_all(mnt);
}

// Two commands on one --out a second apart: the first claims the folder
// (DIR/.stiffbench.lock) before it checks it, so the second, of another spec, is refused with exit
// 2 naming the folder and the first run while the first is still computing, and the first's
// files are its own when it ends. A lock left by a process that is gone is taken over.
TEST(OutputSafety, ConcurrentRunsOnOneFolderExactlyOneWrites) {
  const fs::path base = stiffbench::testing_support::fresh_dir("safety", "concurrent");
  const fs::path out = base / "R";
  fs::create_directories(base);
  const pid_t first = ::fork();
  ASSERT_GE(first, 0);
  if (first == 0) {
    const std::string o = out.string();
    // About a second or more in a Release build: 1,500 masses, 20,000 rk4 steps at the finest
    // level.
    const char* argv[] = {
        STIFFBENCH_BIN,  "convergence", "--model", "spring_chain", "--param", "n=1500",
        "--integrators", "rk4",         "--t-end", "10",           "--h",     "0.002",
        "--levels",      "3",           "--out",   o.c_str(),      nullptr};
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execv(STIFFBENCH_BIN, const_cast<char* const*>(argv));
    ::_exit(127);
  }
  bool claimed = false;
  for (int i = 0; i < 2000 && !claimed; ++i) {
    claimed = fs::exists(out / ".stiffbench.lock");
    if (!claimed) ::usleep(5000);
  }
  ASSERT_TRUE(claimed) << "the first run never claimed " << out;
  const Outcome second = run(kSmallConvergence + " --out " + out.string());
  int status = 0;
  ::waitpid(first, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(second.code, 2) << second.err;
  // Either refusal is right: the claim while the first computes, or the record of another spec
  // when the first was already done (a loaded machine); never a second writer.
  EXPECT_TRUE(second.err.find("is being written by another run (pid " + std::to_string(first)) !=
                  std::string::npos ||
              second.err.find("holds results of a different spec") != std::string::npos)
      << second.err;
  EXPECT_NE(slurp(out / "convergence.json").find("spring_chain"), std::string::npos);
  EXPECT_FALSE(fs::exists(out / ".stiffbench.lock"));

  // A lock of a process that is gone (a killed run): taken over, with a note.
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ::waitpid(gone, &status, 0);
  std::ofstream(out / ".stiffbench.lock") << "pid " << gone << "\nstarted earlier\ncommand x\n";
  const Outcome over = run(kSmallConvergence + " --out " + out.string() + " --force");
  EXPECT_EQ(over.code, 0) << over.err;
  EXPECT_NE(over.err.find("was left by a run that is gone"), std::string::npos) << over.err;
  EXPECT_FALSE(fs::exists(out / ".stiffbench.lock"));
  fs::remove_all(base);
}
