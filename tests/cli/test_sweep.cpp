// `stiffbench run SPEC.toml`, --shard + merge, --resume after SIGKILL, --slurm, spec errors
// (experiments/commands/run.hpp). Runs the real binary like test_cli.cpp.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "tests/cli_support.hpp"

namespace {

namespace fs = std::filesystem;

// Absolute: with a compiler launcher that rewrites paths (ccache base_dir) __FILE__ is relative
// to the build folder, while the runner writes absolute spec paths into its job scripts. This
// file is tests/cli/test_sweep.cpp: three levels below the repository root.
const fs::path kSource = fs::absolute(fs::path(__FILE__)).parent_path().parent_path().parent_path();
const std::string kSweep = (kSource / "suites/sweep_spring_chain.toml").string();

using Outcome = stiffbench::testing_support::CliOutcome;
using stiffbench::testing_support::slurp;
Outcome run(const std::string& args, const fs::path& cwd = {}) {
  return stiffbench::testing_support::run_cli(args, cwd);
}

// The CSV with the wall_s column removed (the only column that differs between runs).
std::string without_wall_time(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, out;
  long wall = -1;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    std::string item;
    while (std::getline(ls, item, ',')) f.push_back(item);
    if (wall < 0) wall = std::find(f.begin(), f.end(), "wall_s") - f.begin();
    for (std::size_t i = 0; i < f.size(); ++i)
      if (static_cast<long>(i) != wall) out += f[i] + ",";
    out += "\n";
  }
  return out;
}

long count_lines(const std::string& s) { return std::count(s.begin(), s.end(), '\n'); }

fs::path fresh_dir(const std::string& name) {
  return stiffbench::testing_support::fresh_dir("sweep", name);
}

// 4 chain lengths x 3 integrators = 12 units of 4 step levels each.
TEST(Sweep, ShardsMergedReproduceTheUnshardedRun) {
  const fs::path base = fresh_dir("shards");
  const Outcome full = run("run " + kSweep + " --out " + (base / "full").string());
  ASSERT_EQ(full.code, 0) << full.err;
  const std::string csv = slurp(base / "full/convergence.csv");
  // Header + 12 units x 4 levels (the spec's n list and integrators, levels = 4).
  EXPECT_EQ(count_lines(csv), 1 + 12 * 4);
  for (int i = 0; i < 2; ++i) {
    const Outcome s = run("run " + kSweep + " --shard " + std::to_string(i) + "/2 --out " +
                          (base / ("shard-" + std::to_string(i))).string());
    ASSERT_EQ(s.code, 0) << s.err;
    // Every other unit: 6 units x 4 rows.
    EXPECT_EQ(count_lines(slurp(base / ("shard-" + std::to_string(i)) / "convergence.csv")),
              1 + 6 * 4);
  }
  const Outcome m = run("merge --out " + (base / "merged").string() + " " +
                        (base / "shard-0").string() + " " + (base / "shard-1").string());
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_EQ(without_wall_time(slurp(base / "merged/convergence.csv")), without_wall_time(csv));
  EXPECT_NE(without_wall_time(csv), without_wall_time(slurp(base / "shard-0/convergence.csv")));
  // The Markdown table: only for a complete set of units, one line per row plus 2 header lines.
  EXPECT_EQ(count_lines(slurp(base / "full/convergence.md")), 2 + 12 * 4);
  EXPECT_EQ(count_lines(slurp(base / "merged/convergence.md")), 2 + 12 * 4);
  EXPECT_FALSE(fs::exists(base / "shard-0/convergence.md"));

  // One shard alone: the 6 units of the other one are reported missing (exit 3).
  const Outcome partial =
      run("merge --out " + (base / "partial").string() + " " + (base / "shard-0").string());
  EXPECT_EQ(partial.code, 3);
  EXPECT_FALSE(fs::exists(base / "partial/convergence.md"));
  EXPECT_NE(partial.err.find("missing units: 1, 3, 5, 7, 9, 11"), std::string::npos) << partial.err;

  // A shard of another spec (t_end changed) is refused.
  const Outcome other =
      run("run " + kSweep + " --set t_end=2 --shard 1/2 --out " + (base / "other").string());
  ASSERT_EQ(other.code, 0) << other.err;
  const Outcome refused = run("merge --out " + (base / "bad").string() + " " +
                              (base / "shard-0").string() + " " + (base / "other").string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("different spec"), std::string::npos) << refused.err;
}

// A run of `spec` killed after three units and resumed gives the uninterrupted run's CSV.
void killed_run_resumes_to_the_same_csv(const std::string& spec, const fs::path& base) {
  // Larger than the spec's default so that the kill lands mid-sweep (about 2.5 s a run in a Release
  // build, the 9 units after the third well over the 5 ms the loop below polls at). The same
  // settings for the shell command lines and the killed child's argument vector.
  const std::vector<std::string> larger = {"t_end=10", "levels=6", "params.n=[16,32,64,128]"};
  std::string sets;
  for (const std::string& s : larger) sets += " --set '" + s + "'";
  sets += " --out ";
  const Outcome full = run("run " + spec + sets + (base / "full").string());
  ASSERT_EQ(full.code, 0) << full.err;
  const std::string csv = slurp(base / "full/convergence.csv");
  ASSERT_EQ(count_lines(csv), 1 + 12 * 6);

  const fs::path part = base / "killed";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string out = part.string();
    // push_back one at a time: GCC 12 reports a false -Wstringop-overflow (-Werror) for
    // initializer-list inserts into this vector once the spec path is not a constant.
    std::vector<const char*> argv = {STIFFBENCH_BIN, "run", spec.c_str()};
    for (const std::string& s : larger) {
      argv.push_back("--set");
      argv.push_back(s.c_str());
    }
    argv.push_back("--out");
    argv.push_back(out.c_str());
    argv.push_back(nullptr);
    ::execv(STIFFBENCH_BIN, const_cast<char* const*>(argv.data()));
    ::_exit(127);
  }
  // Wait for 3 complete units (18 rows), then SIGKILL.
  long rows = 0;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(20)) {
    rows = count_lines(slurp(part / "convergence.csv"));
    if (rows >= 1 + 18) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run finished before it was killed";
  const long at_kill = count_lines(slurp(part / "convergence.csv"));
  EXPECT_LT(at_kill, 1 + 12 * 6);
  // A torn write: a row of unit 11 without its newline, as a kill in the middle of a write
  // leaves it; --resume drops it.
  { std::ofstream(part / "convergence.csv", std::ios::app) << "11,6,128,spring_chain,sdi"; }

  const Outcome resumed = run("run " + spec + sets + part.string() + " --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("already done"), std::string::npos) << resumed.out;
  EXPECT_EQ(without_wall_time(slurp(part / "convergence.csv")), without_wall_time(csv));

  // --resume of a different spec into the same folder is refused.
  const Outcome wrong = run("run " + spec + " --out " + part.string() + " --resume");
  EXPECT_EQ(wrong.code, 2);
}

TEST(Sweep, KilledRunResumesToTheSameCsv) {
  killed_run_resumes_to_the_same_csv(kSweep, fresh_dir("resume"));
}

// The sweep spec with two of its integrators given as method files by relative paths (copies of
// rk4 and sdirk2 under other names, in a folder beside the spec): the spec's identity is taken
// after the files are read, from their content, so resume, shards and merge work as for named
// methods, from any working folder; an edited file is another spec, named in the refusal.
fs::path spec_with_method_files(const fs::path& dir) {
  fs::create_directories(dir / "methods");
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"rk4", "my_rk4"},
                                 std::pair<std::string, std::string>{"sdirk2", "my_sdirk2"}}) {
    std::string text = slurp(kSource / "methods" / (from + ".toml"));
    const std::string key = "name = \"" + from + "\"";
    const auto at = text.find(key);
    if (at == std::string::npos)
      ADD_FAILURE() << "no " << key << " in methods/" << from << ".toml";
    else
      text.replace(at, key.size(), "name = \"" + to + "\"");
    std::ofstream(dir / "methods" / (to + ".toml")) << text;
  }
  std::string spec = slurp(kSweep);
  const std::string list = "integrators = [\"rk4\", \"velocity_verlet\", \"sdirk2\"]";
  const auto at = spec.find(list);
  if (at == std::string::npos)
    ADD_FAILURE() << "no integrator list in " << kSweep;
  else
    spec.replace(at, list.size(),
                 "integrators = [\"methods/my_rk4.toml\", \"velocity_verlet\", "
                 "\"methods/my_sdirk2.toml\"]");
  std::ofstream(dir / "sweep.toml") << spec;
  return dir / "sweep.toml";
}

TEST(Sweep, MethodFilesResumeShardAndMergeLikeNamedMethods) {
  const fs::path base = fresh_dir("method_files");
  const fs::path spec = spec_with_method_files(base / "spec");
  killed_run_resumes_to_the_same_csv(spec.string(), base / "killed");

  const Outcome full = run("run " + spec.string() + " --out " + (base / "full").string());
  ASSERT_EQ(full.code, 0) << full.err;
  const std::string csv = slurp(base / "full/convergence.csv");
  EXPECT_EQ(count_lines(csv), 1 + 12 * 4);
  // Four shards, two of them started from the spec's own folder with a relative spec path (the
  // method files are then reached by other paths: the same spec).
  std::string shards;
  for (int i = 0; i < 4; ++i) {
    const fs::path out = base / ("shard-" + std::to_string(i));
    const Outcome s =
        i % 2 ? run("run sweep.toml --shard " + std::to_string(i) + "/4 --out " + out.string(),
                    base / "spec")
              : run("run " + spec.string() + " --shard " + std::to_string(i) + "/4 --out " +
                    out.string());
    ASSERT_EQ(s.code, 0) << s.err;
    shards += " " + out.string();
  }
  const Outcome m = run("merge --out " + (base / "merged").string() + shards);
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_EQ(without_wall_time(slurp(base / "merged/convergence.csv")), without_wall_time(csv));

  // Resuming the complete run: every unit already done.
  const Outcome again =
      run("run " + spec.string() + " --out " + (base / "full").string() + " --resume");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("12 of 12 unit(s) already done"), std::string::npos) << again.out;

  // An edited method file (a comment is enough: the identity is the file's content) is another
  // spec: refused, naming the file, and the rows are left as they were; --force runs it again.
  { std::ofstream(base / "spec/methods/my_rk4.toml", std::ios::app) << "# edited\n"; }
  const Outcome edited =
      run("run " + spec.string() + " --out " + (base / "full").string() + " --resume");
  EXPECT_EQ(edited.code, 2);
  EXPECT_NE(edited.err.find("my_rk4.toml (method 'my_rk4') changed"), std::string::npos)
      << edited.err;
  EXPECT_EQ(edited.err.find("--quick"), std::string::npos) << edited.err;
  EXPECT_EQ(slurp(base / "full/convergence.csv"), csv);
  const Outcome plain = run("run " + spec.string() + " --out " + (base / "full").string());
  EXPECT_EQ(plain.code, 2);
  EXPECT_NE(plain.err.find("my_rk4.toml (method 'my_rk4') changed"), std::string::npos)
      << plain.err;
  const Outcome forced =
      run("run " + spec.string() + " --out " + (base / "full").string() + " --force");
  ASSERT_EQ(forced.code, 0) << forced.err;
  EXPECT_EQ(without_wall_time(slurp(base / "full/convergence.csv")), without_wall_time(csv));
  // A shard of the edited spec does not merge with the others.
  const Outcome edited_shard =
      run("run " + spec.string() + " --shard 1/4 --out " + (base / "edited-1").string());
  ASSERT_EQ(edited_shard.code, 0) << edited_shard.err;
  const Outcome refused = run("merge --out " + (base / "bad").string() + " " +
                              (base / "shard-0").string() + " " + (base / "edited-1").string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("my_rk4.toml (method 'my_rk4') changed"), std::string::npos)
      << refused.err;
}

// A resumed run keeps only units that hold exactly their distinct rows under unit indices this
// spec and shard have: unit 0 with one row replaced by a copy of another (a duplicate standing in
// for a missing row) is run again, and the four rows of a unit 99 the spec does not have are
// dropped; the result equals the uninterrupted run.
TEST(Sweep, ResumeRecomputesUnitsWithDuplicatedOrForeignRows) {
  const fs::path base = fresh_dir("resume_dup");
  const Outcome full = run("run " + kSweep + " --out " + (base / "full").string());
  ASSERT_EQ(full.code, 0) << full.err;
  const std::string csv = slurp(base / "full/convergence.csv");
  std::vector<std::string> lines;
  std::istringstream in(csv);
  for (std::string l; std::getline(in, l);) lines.push_back(l + "\n");
  ASSERT_EQ(lines.size(), 1u + 12 * 4);
  ASSERT_EQ(lines[1].rfind("0,4,", 0), 0u);
  ASSERT_EQ(lines[5].rfind("1,4,", 0), 0u);
  std::string edited;
  for (std::size_t i = 0; i < lines.size(); ++i) edited += i == 2 ? lines[1] : lines[i];
  for (std::size_t i = 5; i < 9; ++i) edited += "99" + lines[i].substr(1);  // a complete unit
  fs::create_directories(base / "part");
  fs::copy_file(base / "full/run.json", base / "part/run.json");
  std::ofstream(base / "part/convergence.csv") << edited;
  const Outcome resumed = run("run " + kSweep + " --out " + (base / "part").string() + " --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resume: 11 of 12 unit(s) already done"), std::string::npos)
      << resumed.out;
  EXPECT_NE(resumed.err.find("dropped unit 99"), std::string::npos) << resumed.err;
  EXPECT_EQ(without_wall_time(slurp(base / "part/convergence.csv")), without_wall_time(csv));
}

TEST(Sweep, ExpansionOrderAndRowTags) {
  // Dimensions: top-level keys by name (h), then parameters by name (params.n), the last one
  // fastest; units: point x integrator, integrators in spec order. h also names a study column
  // (the step actually used), so its tag column is spec.h.
  const fs::path base = fresh_dir("order");
  const Outcome o =
      run("run " + kSweep + " --set 'h=[0.02,0.01]' --set 'params.n=[8,4]' " +
          "--set 'integrators=[\"rk4\",\"sdirk2\"]' --set levels=2 --out " + base.string());
  ASSERT_EQ(o.code, 0) << o.err;
  std::istringstream csv(slurp(base / "convergence.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("unit,unit_rows,spec.h,params.n,model,integrator,order,h,", 0), 0u) << line;
  std::vector<std::string> prefixes;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    std::string item;
    while (std::getline(ls, item, ',')) f.push_back(item);
    ASSERT_GE(f.size(), 6u);
    prefixes.push_back(f[0] + "," + f[1] + "," + f[2] + "," + f[3] + "," + f[5]);
  }
  // 4 points x 2 integrators = 8 units of 2 rows (levels = 2).
  const std::vector<std::string> expected = {
      "0,2,0.02,8,rk4", "0,2,0.02,8,rk4", "1,2,0.02,8,sdirk2", "1,2,0.02,8,sdirk2",
      "2,2,0.02,4,rk4", "2,2,0.02,4,rk4", "3,2,0.02,4,sdirk2", "3,2,0.02,4,sdirk2",
      "4,2,0.01,8,rk4", "4,2,0.01,8,rk4", "5,2,0.01,8,sdirk2", "5,2,0.01,8,sdirk2",
      "6,2,0.01,4,rk4", "6,2,0.01,4,rk4", "7,2,0.01,4,sdirk2", "7,2,0.01,4,sdirk2"};
  EXPECT_EQ(prefixes, expected);
}

TEST(Sweep, FailingUnitIsRecordedAndExitCodeIsThree) {
  // Forward Euler on Prothero-Robinson with lambda = -1e6 at h = 0.1: h·lambda = -1e5 lies far
  // outside its stability interval [-2, 0], so it blows up; backward Euler is A-stable.
  const fs::path base = fresh_dir("fail");
  fs::create_directories(base);
  const fs::path spec = base / "fail.toml";
  std::ofstream(spec) << "kind = \"convergence\"\nmodel = \"prothero_robinson\"\n"
                         "integrators = [\"euler\", \"backward_euler\"]\nt_end = 10\nh = 0.1\n"
                         "levels = 2\n[params]\nlambda = -1e6\n";
  const Outcome o = run("run " + spec.string() + " --out " + (base / "out").string());
  EXPECT_EQ(o.code, 3) << o.err;
  const std::string csv = slurp(base / "out/convergence.csv");
  EXPECT_EQ(count_lines(csv), 1 + 2 * 2);
  // The unstable row has no error, and its steps are those taken before the blow-up was
  // detected: fewer than the planned N = 100 (the growth factor per step is |1 + hλ| ≈ 1e5, so
  // the 1e10 bound is passed within a few steps).
  const auto at = csv.find(",euler,1,0.1,");
  ASSERT_NE(at, std::string::npos) << csv;
  const long steps = std::stol(csv.substr(at + std::string(",euler,1,0.1,").size()));
  EXPECT_GE(steps, 1);
  EXPECT_LT(steps, 100);
  EXPECT_NE(csv.find("euler,1,0.1," + std::to_string(steps) + ",,,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",failed,a row has status"), std::string::npos) << csv;
  EXPECT_NE(csv.find("backward_euler"), std::string::npos);
}

TEST(Sweep, FidelitySpecWithoutAModelRuns) {
  // fidelity's model is optional (the oscillator curves need none); a spec without one used to
  // crash the validation of `run`. 2 points x 2 integrators; each unit holds the analytic and the
  // measured curve: 2 sources x curve_points rows.
  const fs::path base = fresh_dir("fidelity");
  fs::create_directories(base);
  const fs::path spec = base / "fid.toml";
  std::ofstream(spec) << "kind = \"fidelity\"\nintegrators = [\"rk4\", \"backward_euler\"]\n"
                         "curve_points = [3, 5]\nsteps = 100\n";
  const Outcome o = run("run " + spec.string() + " --out " + (base / "out").string());
  ASSERT_EQ(o.code, 0) << o.err;
  const std::string csv = slurp(base / "out/fidelity.csv");
  EXPECT_EQ(count_lines(csv), 1 + 2 * (2 * 3) + 2 * (2 * 5)) << csv;
}

struct SpecError {
  std::string text, set, expected;
};

TEST(Sweep, SpecErrorsNameFileLineAndKey) {
  const fs::path base = fresh_dir("errors");
  fs::create_directories(base);
  const std::string head =
      "kind = \"convergence\"\nmodel = \"spring_chain\"\nintegrators = [\"rk4\"]\nt_end = 1\n";
  const std::vector<SpecError> cases = {
      {head + "levelz = 3\n", "", "bad.toml:5:10: key 'levelz': unknown key"},
      {head + "levels = 2.5\n", "", "bad.toml:5:10: key 'levels': expected an integer"},
      {head + "[params]\nn = []\n", "", "bad.toml:6:5: key 'params.n': empty list"},
      {head + "[params]\nnn = [4, 8]\n", "", "bad.toml:6:6: key 'params.nn': unknown parameter"},
      {"kind = \"convergence\"\nmodel = [\"spring_chain\", \"nope\"]\nintegrators = [\"rk4\"]\n"
       "t_end = 1\n",
       "", "bad.toml:2:9: key 'model': unknown model 'nope'"},
      {head, "--set levels=1", "levels"},
      {head, "--set t_end=abc", "--set t_end=abc: key 't_end': expected a number"},
      {head + "[params]\nn = [4, 8]\n", "--set params.k=x", "--set params.k=x: key 'params.k'"},
  };
  for (const auto& c : cases) {
    const fs::path spec = base / "bad.toml";
    std::ofstream(spec) << c.text;
    const Outcome o =
        run("run " + spec.string() + " " + c.set + " --out " + (base / "out").string());
    EXPECT_EQ(o.code, 2) << c.expected;
    EXPECT_NE(o.err.find(c.expected), std::string::npos) << o.err;
    EXPECT_EQ(count_lines(o.err), 1) << o.err;
    // Reported before any row ran.
    EXPECT_FALSE(fs::exists(base / "out/convergence.csv"));
  }
}

TEST(Sweep, EverySpecInTheRepositoryValidates) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kSource / "suites")) {
    if (e.path().extension() != ".toml") continue;
    ++n;
    const Outcome o = run("run " + e.path().string() + " --check");
    EXPECT_EQ(o.code, 0) << e.path() << ": " << o.err;
  }
  EXPECT_GE(n, 1);
}

TEST(Sweep, SlurmWritesAnArrayAndADependentMergeJob) {
  const fs::path base = fresh_dir("slurm");
  const Outcome o =
      run("run " + kSweep + " --slurm 4 --partition debug --time 00:10:00 --out " + base.string());
  ASSERT_EQ(o.code, 0) << o.err;
  const std::string array = slurp(base / "slurm/array.sbatch");
  EXPECT_EQ(array.rfind("#!/bin/bash\n", 0), 0u);
  EXPECT_NE(array.find("#SBATCH --array=0-3\n"), std::string::npos) << array;
  EXPECT_NE(array.find("#SBATCH --partition=debug\n"), std::string::npos);
  EXPECT_NE(array.find("#SBATCH --time=00:10:00\n"), std::string::npos);
  EXPECT_NE(array.find("--shard ${task}/4"), std::string::npos) << array;
  EXPECT_NE(array.find("task=${SLURM_ARRAY_TASK_ID}"), std::string::npos);
  EXPECT_NE(array.find("'" + kSweep + "'"), std::string::npos) << array;
  const std::string merge = slurp(base / "slurm/merge.sbatch");
  EXPECT_NE(merge.find(" merge --out '" + base.string() + "'"), std::string::npos) << merge;
  EXPECT_NE(merge.find("/shard-3'"), std::string::npos);
  const std::string submit = slurp(base / "slurm/submit.sh");
  EXPECT_NE(submit.find("--dependency=afterok:${array_id}"), std::string::npos) << submit;
  for (const char* f : {"array.sbatch", "merge.sbatch", "submit.sh"})
    EXPECT_EQ(std::system(("bash -n " + (base / "slurm" / f).string()).c_str()), 0) << f;
}

}  // namespace
