// Stopping the command from outside (core/run_control.hpp), on the real binary: SIGINT/SIGTERM
// stop it with exit 130/143 leaving complete files only (a sweep resumes with --resume), and
// --max-wall writes the row over the limit with status timeout and exits 3.
//
// No assertion here is on speed: the limits are far from the work the runs need, so a loaded
// machine changes only how long the test takes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/cli_support.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace {

// --- the command line -------------------------------------------------------------------------

struct Child {
  pid_t pid = -1;
  fs::path out, err;
};

// Starts the real binary with stdout and stderr sent to files (no shell in between, so signals
// reach stiffbench itself).
Child spawn(const std::vector<std::string>& args, const fs::path& dir) {
  Child c;
  c.out = dir / "stdout.txt";
  c.err = dir / "stderr.txt";
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> all = {STIFFBENCH_BIN};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  if (posix_spawn(&c.pid, STIFFBENCH_BIN, &fa, nullptr, argv.data(), environ) != 0) c.pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return c;
}

int wait_exit(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
}

using stiffbench::testing_support::slurp;

// Waits (up to two minutes) until `file` holds `needle` `times` times.
bool wait_for(const fs::path& file, const std::string& needle, long times = 1) {
  for (int i = 0; i < 12000; ++i) {
    const std::string text = slurp(file);
    long n = 0;
    for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    if (n >= times) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::vector<fs::path> temporaries(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().string().find(".tmp") != std::string::npos) out.push_back(e.path());
  return out;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = stiffbench::testing_support::fresh_dir("run_control", name);
  fs::create_directories(d);
  return d;
}

// A sweep of 24 units of about 0.05 s each in a Release build (rk4 on the oscillator, 3·10⁵
// steps: h = 10⁻⁵ and its half; about ten times as long under the sanitizers): SIGINT while it
// runs leaves the units completed so far as whole CSV lines, exit code 130, no temporaries; a
// --resume run then finishes the others.
TEST(RunControlCli, SigintDuringASweepKeepsCompleteUnitsAndResumeFinishes) {
  const fs::path d = fresh_dir("sweep");
  std::ofstream(d / "spec.toml") << "kind = \"convergence\"\n"
                                    "model = \"harmonic_oscillator\"\n"
                                    "integrators = [\"rk4\"]\n"
                                    "t_end = 1.0\nh = 1e-5\nlevels = 2\nrefine = 2\n"
                                    "reference = \"exact\"\n"
                                    "[params]\n"
                                    "k = [1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8, 1.9, 2.0, "
                                    "2.1, 2.2, 2.3, 2.4, 2.5, 2.6, 2.7, 2.8, 2.9, 3.0, 3.1, 3.2, "
                                    "3.3]\n";
  const fs::path out = d / "out";
  Child c = spawn({"run", (d / "spec.toml").string(), "--out", out.string()}, d);
  ASSERT_GT(c.pid, 0);
  // Two units (two rows each) are in the CSV, whose lines are flushed as units finish.
  ASSERT_TRUE(wait_for(out / "convergence.csv", "\n", 5)) << slurp(c.err);
  ::kill(c.pid, SIGINT);
  EXPECT_EQ(wait_exit(c.pid), 130) << slurp(c.err);
  const std::string err = slurp(c.err);
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;
  EXPECT_NE(err.find("--resume"), std::string::npos) << err;
  EXPECT_TRUE(temporaries(d).empty());

  // Every line of the CSV is complete: it ends with a newline and has the header's field count
  // (no field of these rows holds a comma); the header and at least two units (of 2 rows each).
  const std::string csv = slurp(out / "convergence.csv");
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.back(), '\n');
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  const auto fields = std::count(line.begin(), line.end(), ',');
  int rows = 0;
  while (std::getline(lines, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), fields) << line;
    ++rows;
  }
  EXPECT_GE(rows, 4);
  EXPECT_LT(rows, 48);  // interrupted before the end

  Child resume = spawn({"run", (d / "spec.toml").string(), "--out", out.string(), "--resume"}, d);
  ASSERT_GT(resume.pid, 0);
  EXPECT_EQ(wait_exit(resume.pid), 0) << slurp(resume.err);
  const std::string full = slurp(out / "convergence.csv");
  EXPECT_EQ(std::count(full.begin(), full.end(), '\n'), 1 + 48);
  EXPECT_EQ(full.rfind(csv.substr(0, csv.find('\n')), 0), 0u);  // same header
  fs::remove_all(d);
}

// SIGTERM during a one-off study: exit 143, and the study's files are not written half-way (its
// table holds all rows or does not exist); the output folder it created is removed when empty.
TEST(RunControlCli, SigtermDuringAStudyExits143WithoutPartialFiles) {
  const fs::path d = fresh_dir("study");
  const fs::path out = d / "out";
  // Level 1 (10⁵ steps) finishes at once; level 3 (9·10⁷ steps) takes seconds.
  Child c =
      spawn({"convergence", "--model", "harmonic_oscillator", "--integrators", "rk4", "--t-end",
             "100", "--h", "1e-3", "--levels", "3", "--refine", "30", "--out", out.string()},
            d);
  ASSERT_GT(c.pid, 0);
  ASSERT_TRUE(wait_for(c.err, "[1/3]")) << slurp(c.err);
  ::kill(c.pid, SIGTERM);
  const int code = wait_exit(c.pid);
  if (code == 0) GTEST_SKIP() << "the study finished before the signal arrived";
  EXPECT_EQ(code, 143) << slurp(c.err);
  EXPECT_NE(slurp(c.err).find("interrupted by SIGTERM"), std::string::npos) << slurp(c.err);
  EXPECT_FALSE(fs::exists(out / "convergence.csv"));
  EXPECT_FALSE(fs::exists(out));  // created by this run, left empty, removed
  EXPECT_TRUE(temporaries(d).empty());
  fs::remove_all(d);
}

// --max-wall on the command line: the row over the limit is written with status timeout, the
// rows before it are real results, and the exit code is 3 (a row failed).
TEST(RunControlCli, MaxWallWritesATimeoutRowAndExitsThree) {
  const fs::path d = fresh_dir("maxwall");
  const fs::path out = d / "out";
  // h = 0.1 and 0.1/3000 take 100 and 3·10⁵ steps (milliseconds, far inside 2 s even under
  // the sanitizers); 0.1/3000² takes 9·10⁸ (tens of seconds).
  Child c = spawn(
      {"convergence", "--model", "harmonic_oscillator", "--integrators", "rk4", "--t-end", "10",
       "--h", "0.1", "--levels", "3", "--refine", "3000", "--max-wall", "2", "--out", out.string()},
      d);
  ASSERT_GT(c.pid, 0);
  EXPECT_EQ(wait_exit(c.pid), 3) << slurp(c.err);
  EXPECT_NE(slurp(c.err).find("timeout"), std::string::npos) << slurp(c.err);
  std::istringstream csv(slurp(out / "convergence.csv"));
  std::string header, line;
  std::getline(csv, header);
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_NE(rows[0].find(",ok"), std::string::npos) << rows[0];
  // 3·10⁵ rk4 steps reach the round-off floor: a real result with status floor.
  EXPECT_TRUE(rows[1].find(",ok") != std::string::npos ||
              rows[1].find(",floor") != std::string::npos)
      << rows[1];
  EXPECT_NE(rows[2].find(",timeout"), std::string::npos) << rows[2];
  fs::remove_all(d);
}

// --max-wall on a study without runs: region's rows are methods. radau5's region on a
// 4000×4000 grid is about 1.6·10⁷ evaluations of R = P/Q (a tenth of a second or more, ten
// times that under the sanitizers) against a limit of 5 ms: the method is marked stopped (no
// boundary, no limits), the tables are written, exit 3.
TEST(RunControlCli, MaxWallStopsOneMethodsRegionAndExitsThree) {
  const fs::path d = fresh_dir("maxwall_region");
  const fs::path out = d / "out";
  Child c = spawn({"region", "--integrators", "radau5", "--resolution", "4000", "--box",
                   "-8,8,-8,8", "--max-wall", "0.005", "--out", out.string()},
                  d);
  ASSERT_GT(c.pid, 0);
  EXPECT_EQ(wait_exit(c.pid), 3) << slurp(c.err);
  EXPECT_NE(slurp(c.err).find("region of radau5 stopped"), std::string::npos) << slurp(c.err);
  const std::string limits = slurp(out / "region_limits.csv");
  std::istringstream csv(limits);
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 1u) << limits;
  EXPECT_EQ(rows[0].rfind("radau5,", 0), 0u) << rows[0];
  EXPECT_NE(rows[0].find(",stopped"), std::string::npos) << rows[0];
  EXPECT_NE(slurp(out / "region.md").find("radau5 stopped"), std::string::npos);
  fs::remove_all(d);
}

}  // namespace
