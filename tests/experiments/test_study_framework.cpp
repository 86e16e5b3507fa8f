// The study framework (experiments/framework/study.hpp): options declared once, a user's own study
// registered with one call and run from the command line and from a spec file, studies on a
// user's objects without registering them by name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "cli/cli_main.hpp"
#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/commands/run.hpp"
#include "experiments/framework/option_table.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/studies/convergence.hpp"
#include "experiments/studies/energy.hpp"
#include "experiments/studies/stability.hpp"
#include "experiments/studies/work_precision.hpp"
#include "tests/test_support.hpp"

namespace fs = std::filesystem;
using namespace stiffbench;

namespace {

std::string slurp_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Whether a C++ file names option `key`: as the whole of a string literal (a declaration, a
// lookup, a JSON key), as its flag at the start of a literal ("--norm-growth must be ..."), as a
// field of a study spec (`spec.norm_growth`, `spec_.norm_growth`) or in a typed declaration
// (`double norm_growth = 10;`). Comments and prose do not count, nor do unrelated things of the
// same spelling (a driver's FixedStepOptions::max_steps, MethodInfo::reference).
bool names_key(const std::string& text, const std::string& key) {
  std::string code;
  const std::string flag = option_flag(key);
  bool named = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 2, "//") == 0) {
      while (i < text.size() && text[i] != '\n') ++i;
      code += '\n';
    } else if (text.compare(i, 2, "/*") == 0) {
      const auto end = text.find("*/", i + 2);
      i = end == std::string::npos ? text.size() : end + 1;
    } else if (text[i] == '"') {
      std::string literal;
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') ++i;
        literal += text[i];
      }
      const bool flag_first = literal.rfind(flag, 0) == 0 &&
                              (literal.size() == flag.size() ||
                               !(std::isalnum(static_cast<unsigned char>(literal[flag.size()])) ||
                                 literal[flag.size()] == '-'));
      named = named || literal == key || flag_first;
      code += "\"\"";
    } else if (text[i] == '\'' && i + 2 < text.size()) {
      // A character literal ('a', '\n'): skipped so its quote does not open a string.
      const auto end = text.find('\'', i + (text[i + 1] == '\\' ? 3 : 2));
      code += "' '";
      i = end == std::string::npos ? i : end;
    } else {
      code += text[i];
    }
  }
  // Whole-word occurrences of the key in the code (no std::regex: GCC 12 warns inside <regex>
  // under the sanitizer build's flags).
  auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (std::size_t at = code.find(key); at != std::string::npos; at = code.find(key, at + 1)) {
    const std::size_t end = at + key.size();
    if ((at > 0 && word(code[at - 1])) || (end < code.size() && word(code[end]))) continue;
    // A field of a study spec: `spec.key`, `spec_.key`, `my_spec.key`.
    if (at > 0 && code[at - 1] == '.') {
      std::size_t b = at - 1;
      while (b > 0 && word(code[b - 1])) --b;
      if (code.substr(b, at - 1 - b).find("spec") != std::string::npos) return true;
      continue;
    }
    // A typed declaration: `double key = ...;`, `long key;`, `std::optional<double> key{}`.
    std::size_t after = end;
    while (after < code.size() && code[after] == ' ') ++after;
    if (after >= code.size() || std::string("=;{").find(code[after]) == std::string::npos ||
        (code[after] == '=' && after + 1 < code.size() && code[after + 1] == '='))
      continue;
    std::size_t b = at;
    while (b > 0 && code[b - 1] == ' ') --b;
    if (b == at) continue;
    for (const std::string type :
         {"int", "long", "double", "bool", "std::string", "Index", "unsigned long", ">"}) {
      if (b >= type.size() && code.compare(b - type.size(), type.size(), type) == 0 &&
          (type == ">" || b == type.size() || !word(code[b - type.size() - 1])))
        return true;
    }
  }
  return named;
}

// The unit a file under experiments/ counts as: a .cpp with its header (X.cpp and X.hpp are
// X), and a study's files (studies/X.* and its parts studies/X_PART.*, X the shortest
// underscore-cut prefix of the stem with a header studies/X.hpp) are one unit, studies/X.
std::string unit_of(const fs::path& relative, const std::set<std::string>& studies) {
  if (relative.parent_path() != "studies")
    return (relative.parent_path() / relative.stem()).string();
  const std::string stem = relative.stem().string();
  for (std::size_t cut = stem.find('_'); cut != std::string::npos; cut = stem.find('_', cut + 1))
    if (studies.count(stem.substr(0, cut))) return "studies/" + stem.substr(0, cut);
  return "studies/" + stem;
}

}  // namespace

// The measure of "declared once": every option key of six or more characters of a
// built-in study is named (as an identifier or as the whole of a string literal; comments and
// prose in messages do not count) in at most two units under experiments/ (a .cpp with its
// header, or the files of one study): its declaration and at most one use. Before the framework,
// norm_growth was in five files.
TEST(StudyFramework, OptionKeysAreNamedInAtMostTwoFiles) {
  const fs::path dir = fs::path(STIFFBENCH_SOURCE_DIR) / "experiments";
  std::set<std::string> studies;
  for (const auto& e : fs::directory_iterator(dir / "studies"))
    if (e.path().extension() == ".hpp") studies.insert(e.path().stem().string());
  std::map<std::string, std::string> files;  // unit -> its files' text
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".cpp" || e.path().extension() == ".hpp")
      files[unit_of(fs::relative(e.path(), dir), studies)] += slurp_file(e.path()) + "\n";
  ASSERT_GT(files.size(), 10u);
  std::set<std::string> keys;
  for (const auto& kind : study_kinds())
    for (const auto& o : kind.options)
      if (o.key.size() >= 6) keys.insert(o.key);
  ASSERT_TRUE(keys.count("norm_growth"));
  ASSERT_TRUE(keys.count("reference_rtol"));
  for (const auto& key : keys) {
    std::vector<std::string> where;
    for (const auto& [name, text] : files)
      if (names_key(text, key)) where.push_back(name);
    EXPECT_LE(where.size(), 2u) << key << " is named in " << join(where);
    EXPECT_GE(where.size(), 1u) << key;
  }
}

TEST(StudyFramework, DescribeStudyPrintsEveryOption) {
  for (const auto& kind : study_kinds()) {
    std::ostringstream os;
    describe_study(kind, os);
    for (const auto& o : kind.options) {
      EXPECT_NE(os.str().find("| " + o.key + " |"), std::string::npos) << kind.name << " " << o.key;
      EXPECT_NE(os.str().find(option_flag(o.key)), std::string::npos) << kind.name << " " << o.key;
    }
  }
}

namespace {

// A small user study: one fixed-step run of each integrator over `steps` steps of size `h`;
// its table has the f evaluations taken. One registration line below adds it everywhere.
class FevalJob : public StudyJob {
 public:
  FevalJob(StudyInputs t, long steps, double h) : t_(std::move(t)), steps_(steps), h_(h) {}
  nlohmann::json spec_json() const override {
    return {{"model", t_.model}, {"integrators", t_.integrators}, {"steps", steps_}, {"h", h_}};
  }
  void run(std::ostream*) override {
    Setup setup = make_setup(t_);
    table_ = Table{{"integrator", "steps", "f_evals"}, {}};
    for (auto& integ : setup.integrators) {
      FixedStepOptions opt;
      opt.h = h_;
      opt.t_end = setup.model->initial_time() + static_cast<double>(steps_) * h_;
      const RunResult r = run_fixed_step(*setup.model, *integ, opt);
      table_.rows.push_back(
          {integ->info().name, std::to_string(r.stats.steps), std::to_string(r.stats.f_evals)});
    }
  }
  Table unit_table() const override { return table_; }
  bool write(const fs::path& dir, const std::string&, const PlotOptions&,
             std::ostream&) const override {
    write_file_atomic(dir / "feval_count.csv", table_.to_csv());
    write_file_atomic(dir / "feval_count.md", table_.to_markdown());
    write_file_atomic(dir / "feval_count.json", run_metadata("feval-count", spec_json()).dump());
    return false;
  }
  void print_summary(std::ostream& out) const override { out << table_.to_markdown(); }
  std::string report_markdown(const std::string& note) const override {
    return note + "\n\n" + table_.to_markdown();
  }
  std::string default_title() const override { return "f evaluations"; }

 private:
  StudyInputs t_;
  long steps_;
  double h_;
  Table table_;
};

void register_feval_study() {
  if (find_study("feval-count")) return;
  StudyKind k;
  k.name = "feval-count";
  k.stem = "feval_count";
  k.summary = "f evaluations of a fixed-step run";
  k.options = {{"steps", ParamType::integer, "10", "steps", Bounds::at_least(1)},
               {"h", ParamType::real, "0.01", "step", Bounds::positive()}};
  k.unit_columns = {"integrator", "steps", "f_evals"};
  k.make = [](const StudyInputs& t, const Params& o, const StudyContext&) {
    return std::make_unique<FevalJob>(t, o.integer("steps"), o.real("h"));
  };
  register_study(std::move(k));
}

int cli(std::vector<std::string> args) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return cli_main(static_cast<int>(argv.size()), argv.data());
}

fs::path fresh(const std::string& name) {
  // Per process: helpers or parallel test runs on one machine must not share the folder.
  const fs::path d =
      fs::temp_directory_path() / ("stiffbench_study_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

}  // namespace

// rk4 evaluates f four times a step and heun twice (their tableaux have 4 and 2 stages, no
// first-same-as-last), so 7 steps take 28 and 14 evaluations.
TEST(StudyFramework, UserStudyRunsFromTheCommandLineAndFromASpecFile) {
  register_feval_study();
  const fs::path out = fresh("cli");
  ASSERT_EQ(cli({"feval-count", "--model", "harmonic_oscillator", "--integrators", "rk4,heun",
                 "--steps", "7", "--out", out.string()}),
            0);
  EXPECT_EQ(slurp_file(out / "feval_count.csv"), "integrator,steps,f_evals\nrk4,7,28\nheun,7,14\n");
  EXPECT_EQ(cli({"feval-count", "--model", "harmonic_oscillator", "--integrators", "rk4", "--steps",
                 "0", "--out", fresh("bad").string()}),
            2);  // the declared range (>= 1), checked before anything runs

  const fs::path dir = fresh("spec");
  fs::create_directories(dir);
  std::ofstream(dir / "feval.toml") << "kind = \"feval-count\"\nmodel = \"harmonic_oscillator\"\n"
                                       "integrators = [\"rk4\", \"heun\"]\nsteps = [3, 7]\n";
  ASSERT_EQ(cli({"run", (dir / "feval.toml").string(), "--out", (dir / "out").string()}), 0);
  const std::string csv = slurp_file(dir / "out" / "feval_count.csv");
  EXPECT_NE(csv.find(",3,rk4,3,12,ok,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",7,heun,7,14,ok,"), std::string::npos) << csv;
}

// `list experiments` comes from the two declarations, not from a list of its own: one row per
// command of command_entries() and per study of the registry, a study registered by a program
// included, solve first and the studies before the other commands.
TEST(StudyFramework, ListExperimentsIsTheCommandTableAndTheStudyRegistry) {
  register_feval_study();
  std::ostringstream out;
  cmd_list("experiments", out);
  const std::string text = out.str();
  std::vector<std::string> names;
  for (const auto& c : command_entries()) names.push_back(c.name);
  for (const auto& k : study_kinds()) names.push_back(k.name);
  for (const auto& n : names)
    EXPECT_NE(text.find("| " + n + " |"), std::string::npos) << n << "\n" << text;
  EXPECT_NE(text.find("| feval-count |"), std::string::npos);
  EXPECT_LT(text.find("| solve |"), text.find("| convergence |"));
  EXPECT_LT(text.find("| feval-count |"), text.find("| report |"));
  // Each command's --help says what its row says (the same declaration).
  for (const auto& c : command_entries())
    EXPECT_NE(text.find(c.summary), std::string::npos) << c.name;
}

namespace {

// A user's own integrator, not registered by name: explicit Euler written out (one f evaluation
// a step, order 1).
class MyEuler : public Integrator {
 public:
  MyEuler() : Integrator(my_info()) {}
  void reset(const OdeSystem& sys, double, CVecRef) override { k_.resize(sys.dimension()); }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) override {
    sys.rhs(t, y, k_);
    y += h * k_;
    return Status::ok;
  }

 private:
  static MethodInfo my_info() {
    MethodInfo i;
    i.name = "my_euler";
    i.description = "explicit Euler, written by a user";
    i.family = Family::explicit_rk;
    i.order = 1;
    i.stages = 1;
    return i;
  }
  Vec k_;
};

}  // namespace

// Euler on y'' = -y from (1, 0): the global error at t = 1 is first order, so halving h halves
// it (observed order -> 1 from above; 0.95..1.1 over these steps by the error expansion), and
// the user's object gives bit for bit the numbers of the built-in euler.
TEST(StudyFramework, UserIntegratorObjectRunsWithoutRegistration) {
  ConvergenceSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"euler"};
  spec.t_end = 1;
  spec.h = 0.01;
  spec.levels = 3;
  const ConvergenceResult r = run_convergence(
      inputs_of(spec, StudyObjects{nullptr, {[] { return std::make_unique<MyEuler>(); }}}), spec,
      nullptr);
  ASSERT_EQ(r.rows.size(), 6u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(r.rows[k].integrator, "euler");
    EXPECT_EQ(r.rows[3 + k].integrator, "my_euler");
    EXPECT_EQ(r.rows[k].error, r.rows[3 + k].error);
  }
  ASSERT_TRUE(r.rows[5].observed_order);
  EXPECT_NEAR(*r.rows[5].observed_order, 1.0, 0.1);
  EXPECT_EQ(integrator_registry().find("my_euler"), nullptr);  // nothing registered
}

namespace {

// A user's adaptive method object: its factory takes no parameters, so it has no rtol/atol.
class MyAdaptiveEuler : public MyEuler {
 public:
  bool supports_adaptive() const override { return true; }
};

}  // namespace

// Work-precision runs adaptive methods over a tolerance ladder: an object that cannot take the
// ladder's rtol would give rows at one tolerance labelled with many, so it is refused up front.
TEST(StudyFramework, AdaptiveObjectWithoutTolerancesIsRefusedByWorkPrecision) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  spec.tol_levels = 2;
  spec.repeats = 1;
  try {
    run_work_precision(
        inputs_of(spec,
                  StudyObjects{nullptr, {[] { return std::make_unique<MyAdaptiveEuler>(); }}}),
        spec, nullptr);
    ADD_FAILURE() << "not refused";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("takes no rtol/atol"), std::string::npos) << e.what();
  }
}

namespace {

// A spec with one option of each kind an OptionTable binds.
struct TableSpec {
  double h = std::numeric_limits<double>::quiet_NaN();  // no default
  double tol = 1e-3;
  long samples = 1000;
  bool quick = false;
  std::string norm = "rms";
};

const OptionTable<TableSpec>& table_options() {
  static const OptionTable<TableSpec> t =
      OptionTable<TableSpec>()
          .add("h", &TableSpec::h, "step", Bounds::positive())
          .add("tol", &TableSpec::tol, "tolerance", Bounds::in_open_closed(0, 1))
          .add("samples", &TableSpec::samples, "rows", Bounds::at_least(1))
          .add("quick", &TableSpec::quick, "fewer runs")
          .add("norm", &TableSpec::norm, "error norm", std::vector<std::string>{"rms", "max"});
  return t;
}

}  // namespace

// The table's declarations carry the fields' initialisers as defaults (the shortest text that
// reads back as the same double), read resolved options into the fields, check a hand-filled
// spec against the same ranges, and write the values under their keys.
TEST(StudyFramework, OptionTableBindsKeysToFieldsWithTheirInitialisersAsDefaults) {
  const auto& d = table_options().declarations();
  ASSERT_EQ(d.size(), 5u);
  EXPECT_EQ(d[0].default_value, "");  // NaN: an option without default
  EXPECT_EQ(d[1].default_value, "0.001");
  EXPECT_EQ(d[2].default_value, "1000");
  EXPECT_EQ(d[3].default_value, "false");
  EXPECT_EQ(d[4].default_value, "rms");
  EXPECT_EQ(d[2].type, ParamType::integer);
  EXPECT_EQ(d[4].choices, (std::vector<std::string>{"rms", "max"}));
  // 1/3 needs all 17 significant digits to read back; 0.1 needs one.
  EXPECT_EQ(std::stod(option_default_text(1.0 / 3.0)), 1.0 / 3.0);
  EXPECT_EQ(option_default_text(0.1), "0.1");
  EXPECT_EQ(option_default_text(100.0), "100");  // %g alone gives 1e+02
  EXPECT_EQ(option_default_text(1e-7), "1e-7");  // %g alone gives 1e-07
  EXPECT_EQ(option_default_text(1e20), "1e20");

  StudyKind kind;
  kind.name = "table";
  kind.options = d;
  const Params o =
      resolve_study_options(kind, Params{{"samples", 7}, {"norm", "max"}}, option_flag);
  TableSpec s;
  table_options().read(o, s);
  EXPECT_TRUE(std::isnan(s.h));  // not given, no default: the field keeps its NaN
  EXPECT_EQ(s.tol, 1e-3);
  EXPECT_EQ(s.samples, 7);
  EXPECT_EQ(s.norm, "max");

  nlohmann::json j;
  table_options().to_json(s, j);
  EXPECT_EQ(j["samples"], 7);
  EXPECT_EQ(j["norm"], "max");
  EXPECT_TRUE(j["h"].is_null() || std::isnan(j["h"].get<double>()));

  table_options().check(s);  // in range
  s.samples = 0;
  try {
    table_options().check(s);
    FAIL() << "samples = 0 passed";
  } catch (const BadInput& e) {
    EXPECT_EQ(std::string(e.what()), "--samples must be >= 1 (got 0)");
  }
  s.samples = 7;
  s.norm = "l1";
  EXPECT_THROW(table_options().check(s), BadInput);
}
