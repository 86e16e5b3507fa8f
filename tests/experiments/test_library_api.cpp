// The library face: typed parameters, a model registered from outside the library
// and run through the CLI entry point cli_main() and the study functions, `describe` of
// experiments and variable-order methods, and what the run metadata records. gtest_discover_tests
// runs every test in its own process, so the process-wide registries and command line start
// fresh in each.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "stiffbench/stiffbench.hpp"

namespace stiffbench {
namespace {

// y' = -k y (k a parameter), y(0) = 1, exact y = exp(-k t): a user's own system.
class Decay final : public OdeSystem {
 public:
  explicit Decay(double k) : k_(k) {}
  std::string name() const override { return "user_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-k_ * t); }
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -k_ * y[0]; }

 private:
  double k_;
};

ModelRegistry::Entry decay_entry() {
  // Member by member: g++ 12 warns falsely (maybe-uninitialized) on the nested braced form.
  ModelRegistry::Entry e;
  e.info.name = "user_decay";
  e.info.description = "y' = -k y, registered by the test";
  e.info.exact = true;
  e.info.source = "test";
  e.params = {{"k", ParamType::real, "2", "decay rate"}};
  e.make = [](const Params& p) { return std::make_unique<Decay>(p.real("k")); };
  return e;
}

// Once per process (ctest runs each test alone; a direct run of the binary runs them all).
void register_decay() {
  if (!model_registry().find("user_decay")) register_model(decay_entry());
}

// Runs cli_main with `args`, capturing what it prints on stdout.
int run_cli(std::vector<std::string> args, std::string* out) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream captured;
  auto* old = std::cout.rdbuf(captured.rdbuf());
  const int code = cli_main(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old);
  if (out) *out = captured.str();
  return code;
}

std::filesystem::path fresh_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("stiffbench_api_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d;
}

TEST(LibraryApi, TypedParamsReachTheConsumerBitForBit) {
  const double x = 0.1 + 0.2;  // 0.30000000000000004: needs all 17 digits
  const Params user{{"x", x}, {"n", 32}, {"flag", true}, {"name", "klu"}};
  const std::vector<ParamSpec> specs = {{"x", ParamType::real, "1", ""},
                                        {"n", ParamType::integer, "1", ""},
                                        {"flag", ParamType::boolean, "false", ""},
                                        {"name", ParamType::text, "dense", ""}};
  const Params p = resolve_params(specs, user, nullptr, "test");
  EXPECT_EQ(p.real("x"), x);  // exact equality: the text form round-trips
  EXPECT_EQ(p.integer("n"), 32);
  EXPECT_TRUE(p.boolean("flag"));
  EXPECT_EQ(p.text("name"), "klu");
}

TEST(LibraryApi, RegisteredModelGetsDescribeSolveAndConvergence) {
  register_decay();
  std::string out;
  ASSERT_EQ(run_cli({"describe", "user_decay"}, &out), 0);
  EXPECT_NE(out.find("y' = -k y, registered by the test"), std::string::npos) << out;
  EXPECT_NE(out.find("decay rate"), std::string::npos) << out;

  ASSERT_EQ(run_cli({"solve", "--model", "user_decay", "--integrator", "rk4", "--h", "0.01",
                     "--t-end", "1", "--param", "k=3"},
                    &out),
            0);
  EXPECT_NE(out.find("user_decay"), std::string::npos) << out;

  const auto dir = fresh_dir("conv");
  ASSERT_EQ(run_cli({"convergence", "--model", "user_decay", "--integrators", "euler,rk4",
                     "--t-end", "1", "--h", "0.1", "--levels", "4", "--out", dir.string()},
                    &out),
            0);
  ASSERT_TRUE(std::filesystem::exists(dir / "convergence.csv"));
  // Theory: the global error of a method of order p falls like h^p (1 for euler, 4 for rk4).
  ConvergenceSpec spec;
  spec.model = "user_decay";
  spec.integrators = {"euler", "rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 4;
  const auto res = run_convergence(spec, nullptr);
  EXPECT_NEAR(*last_observed_order(res.rows, "euler"), 1.0, 0.1);
  EXPECT_NEAR(*last_observed_order(res.rows, "rk4"), 4.0, 0.1);
  std::filesystem::remove_all(dir);
}

TEST(LibraryApi, StudyFunctionsWriteTablesLikeTheCli) {
  register_decay();
  const auto dir = fresh_dir("study");
  ConvergenceSpec spec;
  spec.model = "user_decay";
  spec.integrators = {"heun"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 3;
  std::ostringstream err;
  const auto res = convergence_study(spec, (dir / "c").string(), false, nullptr, err);
  EXPECT_NEAR(*last_observed_order(res.rows, "heun"), 2.0, 0.1);  // Heun is order 2
  std::ifstream csv(dir / "c" / "convergence.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_NE(header.find("observed_order"), std::string::npos) << header;
  // The metadata of a library call: no command line, the caller and the registered model.
  std::ifstream js(dir / "c" / "convergence.json");
  const auto j = nlohmann::json::parse(js);
  EXPECT_EQ(j["caller"], "library");
  EXPECT_TRUE(j["command_line"].is_null());
  EXPECT_EQ(j["model"]["name"], "user_decay");
  EXPECT_EQ(j["model"]["built_in"], false);
  std::filesystem::remove_all(dir);
}

TEST(LibraryApi, CliRunsRecordTheirCommandLine) {
  const auto dir = fresh_dir("meta");
  ASSERT_EQ(run_cli({"convergence", "--model", "dahlquist", "--integrators", "rk4", "--t-end", "1",
                     "--h", "0.1", "--levels", "2", "--out", dir.string()},
                    nullptr),
            0);
  std::ifstream js(dir / "convergence.json");
  const auto j = nlohmann::json::parse(js);
  EXPECT_EQ(j["caller"], "cli");
  EXPECT_NE(j["command_line"].get<std::string>().find("--model dahlquist"), std::string::npos);
  EXPECT_EQ(j["model"]["built_in"], true);
  // A library call after cli_main() has returned records no command line again.
  ConvergenceSpec spec;
  spec.model = "dahlquist";
  spec.integrators = {"rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  std::ostringstream err;
  convergence_study(spec, (dir / "lib").string(), false, nullptr, err);
  std::ifstream lib_js(dir / "lib" / "convergence.json");
  const auto lib = nlohmann::json::parse(lib_js);
  EXPECT_EQ(lib["caller"], "library");
  EXPECT_TRUE(lib["command_line"].is_null());
  std::filesystem::remove_all(dir);
}

TEST(LibraryApi, DescribeKnowsExperimentsAndVariableOrders) {
  std::string out;
  ASSERT_EQ(run_cli({"describe", "convergence"}, &out), 0);
  EXPECT_NE(out.find("study convergence"), std::string::npos) << out;
  EXPECT_NE(out.find("| reference_rtol | --reference-rtol | real |"), std::string::npos) << out;
  ASSERT_EQ(run_cli({"describe", "cvode_bdf"}, &out), 0);
  EXPECT_NE(out.find("order: variable"), std::string::npos) << out;
  EXPECT_NE(out.find("evaluations per step: variable"), std::string::npos) << out;
  EXPECT_EQ(run_cli({"describe", "no_such_thing"}, &out), 2);
}

TEST(LibraryApi, StudiesOnASystemObjectMatchTheNamedModel) {
  // The same system given as an object (a factory of the built-in kepler model with e = 0.5)
  // and by name: every row's error must agree bit for bit.
  const Params model_params{{"e", 0.5}};
  const SystemFactory kepler = [&] { return model_registry().create("kepler", model_params); };
  ConvergenceSpec by_name;
  by_name.model = "kepler";
  by_name.params = model_params;
  by_name.integrators = {"rk4", "velocity_verlet"};
  by_name.t_end = 2;
  by_name.h = 0.05;
  by_name.levels = 3;
  ConvergenceSpec by_object = by_name;
  by_object.model = "my_kepler";
  by_object.params = Params{};
  const auto a = run_convergence(by_name, nullptr);
  const auto b =
      run_convergence(inputs_of(by_object, StudyObjects{kepler, {}}), by_object, nullptr);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    EXPECT_EQ(a.rows[k].error, b.rows[k].error) << k;
    EXPECT_EQ(b.rows[k].model, "my_kepler");
  }
  WorkPrecisionSpec wp;
  wp.model = "kepler";
  wp.params = model_params;
  wp.integrators = {"rk4", "cvode_adams"};
  wp.t_end = 2;
  wp.h = 0.05;
  wp.levels = 2;
  wp.tol_levels = 2;
  wp.repeats = 1;
  wp.reference = "exact";
  WorkPrecisionSpec wp_object = wp;
  wp_object.model = "my_kepler";
  wp_object.params = Params{};
  const auto c = run_work_precision(wp, nullptr);
  const auto d =
      run_work_precision(inputs_of(wp_object, StudyObjects{kepler, {}}), wp_object, nullptr);
  ASSERT_EQ(c.rows.size(), d.rows.size());
  for (std::size_t k = 0; k < c.rows.size(); ++k) EXPECT_EQ(c.rows[k].error, d.rows[k].error) << k;
  // A built-in model's name cannot be taken by a system object.
  StudyTarget taken;
  taken.model = "kepler";
  taken.objects.system = kepler;
  EXPECT_THROW(resolve_inputs(taken), BadInput);
}

TEST(LibraryApi, RegisteringANameTwiceIsAnError) {
  register_decay();
  EXPECT_THROW(register_model(decay_entry()), std::logic_error);
}

}  // namespace
}  // namespace stiffbench
