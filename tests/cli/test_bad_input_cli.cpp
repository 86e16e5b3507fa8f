// The bad-input catalogue on the command line (the real binary): what a new user can get wrong,
// each case refused with exit code 2, one message naming the bad value, and no file left behind:
// unknown names (with the closest names suggested), absurd sizes, unwritable output paths,
// unknown flags, empty lists, t_end <= t0, malformed spec files. The parameters of every
// registered model and integrator: tests/experiments/test_bad_input_catalogue.cpp.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "tests/cli_support.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = stiffbench::testing_support::CliOutcome;
// Runs the binary in `cwd` (relative output paths land there).
Outcome run_in(const fs::path& cwd, const std::string& args) {
  return stiffbench::testing_support::run_cli(args, cwd);
}

// Every path under `dir`, for the "nothing left behind" check.
std::set<std::string> tree(const fs::path& dir) {
  std::set<std::string> s;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    s.insert(fs::relative(e.path(), dir).string());
  return s;
}

struct CliCase {
  const char* label;
  std::string args;
  std::vector<std::string> must_name;  // the message contains each
};

void PrintTo(const CliCase& c, std::ostream* os) { *os << c.args; }

class CliCatalogue : public ::testing::TestWithParam<CliCase> {};

// Spec files written into the case's folder before it runs (malformed on purpose).
void write_specs(const fs::path& dir) {
  auto put = [&](const char* name, const char* text) { std::ofstream(dir / name) << text; };
  put("syntax.toml", "kind = \"convergence\"\nmodel = \"kepler\nt_end = 1\n");
  put("unknown_key.toml",
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = [\"rk4\"]\nt_end = 1.0\n"
      "h = 0.1\nbogus_key = 3\n");
  put("empty_list.toml",
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = []\nt_end = 1.0\nh = 0.1\n");
  put("wrong_type.toml",
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = [\"rk4\"]\nt_end = \"long\"\n"
      "h = 0.1\n");
  put("bad_kind.toml", "kind = \"convergense\"\nmodel = \"kepler\"\n");
  put("unknown_model.toml",
      "kind = \"convergence\"\nmodel = \"keplr\"\nintegrators = [\"rk4\"]\nt_end = 1.0\n"
      "h = 0.1\n");
  put("t_end_zero.toml",
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = [\"rk4\"]\nt_end = 0.0\n"
      "h = 0.1\n");
  put("empty.toml", "");
  std::ofstream(dir / "a_file") << "x";
  // Output folders holding results of another spec (every experiment's record in one folder:
  // each command looks at its own files only) or a record that is not JSON.
  put("ok.toml",
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = [\"rk4\"]\nt_end = 1.0\n"
      "h = 0.1\n");
  fs::create_directories(dir / "held");
  const std::string other = R"({"experiment": "other", "spec": {"model": "van_der_pol"}})";
  for (const char* record :
       {"convergence.json", "local_error.json", "work_precision.json", "stability.json",
        "energy.json", "region.json", "solve.json", "run.json", "report.json"})
    std::ofstream(dir / "held" / record) << other;
  std::ofstream(dir / "held" / "traj.csv") << "t,y0\n0,1\n";
  // Input files that must be refused before they are read or used: a coefficient nested 20,000
  // parentheses deep (40 kB), coefficients finite only in long double (1e400) in each kind of
  // method, a control character in a description, a FIFO, and sweeps of 2^64 and 32^6 (about
  // 1e9) points.
  std::string deep = "\"" + std::string(20000, '(') + "1" + std::string(20000, ')') + "\"";
  std::ofstream(dir / "deep.toml") << "name = \"deep\"\nkind = \"explicit_rk\"\norder = 1\n"
                                      "description = \"d\"\nA = [[0]]\nb = ["
                                   << deep << "]\n";
  put("huge_rk.toml",
      "name = \"huge_rk\"\nkind = \"explicit_rk\"\norder = 1\n"
      "description = \"d\"\nA = [[0]]\n"
      "b = [\"1e400\"]\n");
  put("huge_kick.toml",
      "name = \"huge_kick\"\nkind = \"kick_drift\"\norder = 1\n"
      "description = \"d\"\n"
      "velocity_independent = false\nkick = [\"1e400\"]\ndrift = [1]\n");
  put("huge_gamma.toml",
      "name = \"huge_gamma\"\nkind = \"rosenbrock\"\norder = 1\n"
      "description = \"d\"\n"
      "gamma = \"1e400\"\nalpha = [[0]]\ngamma_offdiag = [[0]]\nb = [1]\n");
  put("huge_imex.toml",
      "name = \"huge_imex\"\nkind = \"imex_ark\"\norder = 1\n"
      "description = \"d\"\nc = [0, 1]\n"
      "[explicit]\nA = [[0, 0], [\"1e400\", 0]]\nb = [1, 0]\n"
      "[implicit]\nA = [[0, 0], [0, 1]]\nb = [0, 1]\n");
  put("control.toml",
      "name = \"control\"\nkind = \"explicit_rk\"\norder = 1\n"
      "description = \"clears \\u001b[2J the screen\"\nA = [[0]]\nb = [1]\n");
  if (::mkfifo((dir / "fifo.toml").c_str(), 0600) != 0) ADD_FAILURE() << "mkfifo failed";
  std::string wide =
      "kind = \"convergence\"\nmodel = \"kepler\"\nintegrators = [\"rk4\"]\n"
      "t_end = 1.0\nh = 0.1\n[params]\n";
  std::string wide64 = wide;
  for (int k = 0; k < 64; ++k) wide64 += "p" + std::to_string(k) + " = [1, 2]\n";
  std::ofstream(dir / "sweep_2_64.toml") << wide64;
  std::string list32 = "[";
  for (int v = 0; v < 32; ++v) list32 += (v ? ", " : "") + std::to_string(v + 1);
  list32 += "]\n";
  for (const char* k : {"a", "b", "c", "d", "e", "f"}) wide += std::string(k) + " = " + list32;
  std::ofstream(dir / "sweep_1e9.toml") << wide;
  fs::create_directories(dir / "garbled");
  std::ofstream(dir / "garbled" / "convergence.json") << "{\"spec\": ";
  std::ofstream(dir / "garbled" / "convergence.csv") << "model\n";
}

TEST_P(CliCatalogue, ExitsTwoNamesTheValueLeavesNothing) {
  const CliCase& c = GetParam();
  const fs::path dir = fs::temp_directory_path() /
                       ("stiffbench_catalogue_" + std::to_string(::getpid()) + "_" + c.label);
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_specs(dir);
  const std::set<std::string> before = tree(dir);
  const Outcome o = run_in(dir, c.args);
  EXPECT_EQ(o.code, 2) << o.err;
  for (const auto& s : c.must_name) EXPECT_NE(o.err.find(s), std::string::npos) << o.err;
  // One message, one line (CLI11's own errors included).
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_EQ(tree(dir), before) << "files left behind by: " << c.args;
  fs::remove_all(dir);
}

const std::string kSolve = "solve --model harmonic_oscillator --integrator rk4 --h 0.1 --t-end 1";
const std::string kConv =
    "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 --out out";

INSTANTIATE_TEST_SUITE_P(
    BadInput, CliCatalogue,
    ::testing::Values(
        // Unknown names, with the closest known names suggested.
        CliCase{"unknown_command", "solv", {"'solv'", "did you mean 'solve'"}},
        CliCase{"unknown_model",
                "solve --model clth --integrator rk4 --h 0.1 --t-end 1 --out x.csv",
                {"'clth'", "did you mean 'cloth'"}},
        CliCase{"unknown_integrator",
                "solve --model kepler --integrator rk5 --h 0.1 --t-end 1 --out x.csv",
                {"'rk5'", "did you mean", "rk4"}},
        CliCase{"unknown_integrator_in_list",
                "convergence --model kepler --integrators rk4,velocity_verlt --t-end 1 --h 0.1 "
                "--out out",
                {"velocity_verlt", "did you mean 'velocity_verlet'"}},
        CliCase{"unknown_param",
                kSolve + " --param gama=0.1 --out x.csv",
                {"'gama'", "did you mean 'gamma'"}},
        CliCase{"unknown_describe", "describe keplr", {"'keplr'", "did you mean 'kepler'"}},
        CliCase{"unknown_model_in_conv",
                "convergence --model van_der_poll --integrators rk4 --t-end 1 --h 0.1 --out out",
                {"van_der_poll", "did you mean 'van_der_pol'"}},
        // Non-finite, negative and zero flag values.
        CliCase{"param_nan", kSolve + " --param k=nan --out x.csv", {"'k'", "nan"}},
        CliCase{"param_inf", kSolve + " --param m=inf --out x.csv", {"'m'", "inf"}},
        CliCase{"h_nan", "solve --model kepler --integrator rk4 --h nan --t-end 1", {"h"}},
        CliCase{"h_negative", "solve --model kepler --integrator rk4 --h -0.1 --t-end 1", {"h"}},
        CliCase{"levels_zero", kConv + " --levels 0", {"levels"}},
        CliCase{"refine_one", kConv + " --refine 1", {"refine"}},
        CliCase{"floor_word", kConv + " --floor low", {"--floor", "'low'"}},
        CliCase{"floor_zero", kConv + " --floor 0", {"--floor", "'0'"}},
        CliCase{"outputs_zero", kSolve + " --outputs 0", {"outputs"}},
        CliCase{"t_end_nan",
                "solve --model kepler --integrator rk4 --h 0.1 --t-end nan",
                {"--t-end", "'nan'", "not a finite number"}},
        // Input files refused before they are read or used.
        CliCase{"deep_expression", "analyze deep.toml", {"deep.toml", "nested deeper than 200"}},
        CliCase{"huge_rk", "analyze huge_rk.toml", {"huge_rk.toml", "1e400"}},
        CliCase{"huge_kick", "analyze huge_kick.toml", {"huge_kick.toml", "range of double"}},
        CliCase{"huge_gamma", "analyze huge_gamma.toml", {"huge_gamma.toml", "range of double"}},
        CliCase{"huge_imex", "analyze huge_imex.toml", {"huge_imex.toml", "range of double"}},
        CliCase{"control_characters",
                "analyze control.toml",
                {"control.toml", "'description'", "control character (code 27"}},
        CliCase{"fifo_method_file", "analyze fifo.toml", {"fifo.toml", "not a regular file"}},
        CliCase{"fifo_spec_file", "run fifo.toml --out out", {"fifo.toml", "not a regular file"}},
        CliCase{
            "dev_zero_spec_file", "run /dev/zero --out out", {"/dev/zero", "not a regular file"}},
        CliCase{"folder_spec_file", "run held --out out", {"held", "a folder, not a spec file"}},
        CliCase{"sweep_2_64",
                "run sweep_2_64.toml --out out",
                {"sweep_2_64.toml", "more than 100000 units"}},
        CliCase{"sweep_1e9",
                "run sweep_1e9.toml --out out",
                {"params.a (32) x params.b (32)", "more than 100000 units"}},
        CliCase{"slurm_partition_newline",
                "run ok.toml --slurm 2 --partition \"$(printf 'debug\\necho pwned')\" --out out",
                {"--partition", "debug\\necho pwned", "Slurm partition name"}},
        CliCase{"out_not_utf8",
                kConv.substr(0, kConv.find(" --out")) + " --out \"$(printf 'R\\377')\"",
                {"not valid UTF-8", "R\\xff"}},
        CliCase{"slurm_time_space",
                "run ok.toml --slurm 2 --time '1:00 ; x' --out out",
                {"--time", "Slurm time limit"}},
        // Absurd sizes: refused before anything is allocated.
        CliCase{"cloth_1e9",
                "solve --model cloth --param n=1000000000 --integrator rk4 --h 0.001 --t-end 0.01 "
                "--out x.csv",
                {"n=1000000000", "unknowns", "largest supported"}},
        CliCase{"cloth_memory",
                "solve --model cloth --param n=5000 --integrator rk4 --h 0.001 --t-end 0.01 "
                "--out x.csv",
                {"n=5000", "would need about", "GiB", "limit"}},
        CliCase{"max_memory",
                "solve --model cloth --param n=64 --integrator rk4 --h 0.001 --t-end 0.01 "
                "--max-memory 1M --out x.csv",
                {"n=64", "would need about", "limit 1 MiB", "--max-memory"}},
        CliCase{"dense_refused",
                "solve --model cloth --param n=300 --integrator radau5 --param "
                "linear_solver=dense_lu --h 0.001 --t-end 0.01 --max-memory 2G --out x.csv",
                {"radau5", "dense", "sparse or matrix-free"}},
        CliCase{"soft_cube_huge",
                "convergence --model soft_cube --param n=5000 --integrators rk4 --t-end 1 --h 0.1 "
                "--out out",
                {"n=5000", "unknowns"}},
        CliCase{"max_memory_bad", kSolve + " --max-memory lots", {"--max-memory", "lots"}},
        CliCase{"max_memory_negative", kSolve + " --max-memory -5G", {"--max-memory", "-5G"}},
        // Output paths that cannot be created or written: refused before the run.
        CliCase{"out_proc", kSolve + " --out /proc/nope/x.csv", {"/proc/nope/x.csv", "cannot"}},
        CliCase{"out_under_file", kSolve + " --out a_file/x.csv", {"a_file", "is a file"}},
        CliCase{"out_is_folder", kSolve + " --out .", {"--out", "folder"}},
        CliCase{"conv_out_proc",
                "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 "
                "--out /proc/nope",
                {"/proc/nope", "cannot"}},
        CliCase{"conv_out_under_file",
                "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 "
                "--out a_file/sub",
                {"a_file", "is a file"}},
        CliCase{"wp_out_proc",
                "work-precision --model harmonic_oscillator --integrators rk4 --t-end 1 "
                "--out /proc/nope",
                {"/proc/nope"}},
        CliCase{"stability_out_proc",
                "stability --model harmonic_oscillator --integrators rk4 --out /proc/nope",
                {"/proc/nope"}},
        CliCase{"report_out_proc", "report --quick --out /proc/nope", {"/proc/nope"}},
        CliCase{"run_out_proc", "run t_end_zero.toml --out /proc/nope", {"t_end"}},
        // Existing output folders holding results of a different spec (or results that
        // cannot be identified): refused before the run unless --force, nothing changed.
        CliCase{
            "out_holds_other_convergence",
            "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 "
            "--out held",
            {"--out held holds results of a different spec", "held/convergence.json", "--force"}},
        CliCase{"out_holds_other_local_error",
                "local-error --model harmonic_oscillator --integrators rk4 --h 0.1 --out held",
                {"held/local_error.json", "different spec", "--force"}},
        CliCase{"out_holds_other_work_precision",
                "work-precision --model harmonic_oscillator --integrators rk4 --t-end 1 "
                "--out held",
                {"held/work_precision.json", "different spec", "--force"}},
        CliCase{"out_holds_other_stability",
                "stability --model harmonic_oscillator --integrators rk4 --out held",
                {"held/stability.json", "different spec", "--force"}},
        CliCase{"out_holds_other_energy",
                "energy --model harmonic_oscillator --integrators rk4 --h 0.1 --t-end 1 "
                "--out held",
                {"held/energy.json", "different spec", "--force"}},
        CliCase{"out_holds_other_region",
                "region --integrators rk4 --out held",
                {"held/region.json", "different spec", "--force"}},
        CliCase{"out_holds_other_frames",
                kSolve + " --frames 2 --out held",
                {"held/solve.json", "different spec", "--force"}},
        CliCase{"out_file_exists", kSolve + " --out held/traj.csv", {"held/traj.csv", "--force"}},
        CliCase{"out_holds_other_run",
                "run ok.toml --out held",
                {"held/run.json", "different spec", "--force"}},
        CliCase{"out_holds_other_report",
                "report --quick --out held",
                {"held/report.json", "different spec", "--force"}},
        CliCase{"out_holds_unidentified",
                "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 "
                "--out garbled",
                {"garbled/convergence.json", "not valid JSON", "--force"}},
        // A work-precision reference that is one of the methods studied (their errors would
        // be correlated with its own), or a published solution the model does not have.
        CliCase{"wp_reference_is_studied",
                "work-precision --model hires --integrators radau5,rodas4 --reference radau5 "
                "--out out",
                {"--reference radau5", "also one of --integrators"}},
        CliCase{"wp_reference_published_missing",
                "work-precision --model van_der_pol --integrators radau5 --reference published "
                "--out out",
                {"--reference published", "van_der_pol", "no published solution"}},
        CliCase{"wp_reference_published_elsewhere",
                "work-precision --model hires --integrators radau5 --t-end 10 --reference "
                "published --out out",
                {"--reference published", "t = 321.8122"}},
        // A bad input discovered after the output folder was prepared leaves no folder.
        CliCase{"conv_bad_after_out",
                "convergence --model harmonic_oscillator --integrators rk4 --t-end 1 --h 0.1 "
                "--levels 1 --out new/deeper",
                {"levels"}},
        // Unknown flags.
        CliCase{"unknown_flag", kSolve + " --bogus 3", {"--bogus"}},
        CliCase{"unknown_flag_conv", kConv + " --hh 0.1", {"--hh"}},
        // Empty lists.
        CliCase{"empty_integrators",
                "convergence --model kepler --integrators '' --t-end 1 --h 0.1 --out out",
                {"--integrators"}},
        CliCase{"trailing_comma",
                "convergence --model kepler --integrators rk4, --t-end 1 --h 0.1 --out out",
                {"--integrators"}},
        CliCase{"empty_times", kSolve + " --times ''", {"--times"}},
        // t_end <= t0.
        CliCase{"t_end_zero", "solve --model kepler --integrator rk4 --h 0.1 --t-end 0", {"t"}},
        CliCase{
            "t_end_negative", "solve --model kepler --integrator rk4 --h 0.1 --t-end -1", {"t"}},
        CliCase{"conv_t_end_zero",
                "convergence --model kepler --integrators rk4 --t-end 0 --h 0.1 --out out",
                {"t"}},
        // Malformed spec files: the file and the key named.
        CliCase{"spec_syntax", "run syntax.toml --out out", {"syntax.toml"}},
        CliCase{"spec_unknown_key", "run unknown_key.toml --out out", {"bogus_key"}},
        CliCase{"spec_empty_list", "run empty_list.toml --out out", {"integrators"}},
        CliCase{"spec_wrong_type", "run wrong_type.toml --out out", {"t_end"}},
        CliCase{"spec_bad_kind", "run bad_kind.toml --out out", {"convergense"}},
        CliCase{"spec_unknown_model", "run unknown_model.toml --out out", {"keplr"}},
        CliCase{"spec_t_end_zero", "run t_end_zero.toml --out out", {"t_end"}},
        CliCase{"spec_empty", "run empty.toml --out out", {"empty.toml"}},
        CliCase{"spec_missing", "run nosuch.toml --out out", {"nosuch.toml"}}),
    [](const ::testing::TestParamInfo<CliCase>& i) { return std::string(i.param.label); });

}  // namespace
