// Integrator variants on the command line (experiments/catalog.hpp): METHOD{key=value,...}
// wherever an integrator is named — a method file with its own Newton setting beside radau5 and
// radau5 with another linear solver in one table, the same in `run` spec files and `profile`
// suites — and the refusals that name the variant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/build_info.hpp"
#include "experiments/output/csv.hpp"
#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;
using testing_support::fresh_dir;
using testing_support::run_cli;
using testing_support::shell_quote;
using testing_support::slurp;

const fs::path kSource = STIFFBENCH_SOURCE_DIR;

// methods/esdirk43.toml under the name my_esdirk (an embedded ESDIRK pair: adaptive, Newton).
fs::path write_my_esdirk(const fs::path& dir) {
  fs::create_directories(dir);
  std::string text = slurp(kSource / "methods" / "esdirk43.toml");
  const std::string key = "name = \"esdirk43\"";
  const auto at = text.find(key);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) text.replace(at, key.size(), "name = \"my_esdirk\"");
  const fs::path p = dir / "my_esdirk.toml";
  std::ofstream(p) << text;
  return p;
}

// Rows of a CSV as maps column -> cell (the library's CSV line reader, quoted labels included).
std::vector<std::map<std::string, std::string>> rows_of(const fs::path& csv) {
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  const auto header = parse_csv_line(line);
  std::vector<std::map<std::string, std::string>> out;
  while (std::getline(in, line)) {
    const auto cells = parse_csv_line(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    out.push_back(row);
  }
  return out;
}

const char* kVariants = "{newton=full}";

TEST(VariantsCli, WorkPrecisionLabelsAMethodFileVariantAndTwoRadau5Settings) {
  const fs::path dir = fresh_dir("variants", "work_precision");
  const fs::path file = write_my_esdirk(dir / "methods");
  const std::string list = file.string() + kVariants + ",radau5,radau5{linear_solver=dense_lu}";
  const auto r = run_cli("work-precision --model van_der_pol --integrators " + shell_quote(list) +
                         " --tol-levels 3 --rtol-max 1e-4 --repeats 1 --out " +
                         shell_quote((dir / "out").string()));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = rows_of(dir / "out" / "work_precision.csv");
  std::map<std::string, std::vector<std::map<std::string, std::string>>> by;
  for (const auto& row : rows) by[row.at("integrator")].push_back(row);
  ASSERT_EQ(by.size(), 3u) << slurp(dir / "out" / "work_precision.csv");
  ASSERT_TRUE(by.count("my_esdirk{newton=full}"));
  ASSERT_TRUE(by.count("radau5"));
  ASSERT_TRUE(by.count("radau5{linear_solver=dense_lu}"));
  // Full Newton evaluates the Jacobian at every iterate; an adaptive run makes at least one
  // iterate per stage per step, so more Jacobians than steps (modified Newton: one per step).
  for (const auto& row : by["my_esdirk{newton=full}"])
    EXPECT_GT(std::stod(row.at("jac_evals")), std::stod(row.at("steps"))) << row.at("setting");
  // radau5 with a dense LU is the same method: only round-off differs between the two linear
  // solvers, so at each tolerance the errors agree far below the tolerance itself.
  ASSERT_EQ(by["radau5"].size(), by["radau5{linear_solver=dense_lu}"].size());
  for (std::size_t i = 0; i < by["radau5"].size(); ++i) {
    const double a = std::stod(by["radau5"][i].at("error"));
    const double b = std::stod(by["radau5{linear_solver=dense_lu}"][i].at("error"));
    EXPECT_LE(std::abs(a - b), 1e-3 * std::max(a, b)) << by["radau5"][i].at("setting");
  }
  // The JSON records what each label stands for.
  const std::string json = slurp(dir / "out" / "work_precision.json");
  EXPECT_NE(json.find("\"variants\""), std::string::npos);
  EXPECT_NE(json.find("\"linear_solver\": \"dense_lu\""), std::string::npos) << json;
  EXPECT_NE(json.find("my_esdirk.toml"), std::string::npos) << json;
}

TEST(VariantsCli, GlobalParamForOneMethodNamesTheVariantSyntax) {
  const fs::path dir = fresh_dir("variants", "global_param");
  const auto r = run_cli(
      "work-precision --model van_der_pol --integrators esdirk43,radau5 "
      "--param newton=full --tol-levels 2 --repeats 1 --out " +
      shell_quote((dir / "out").string()));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("radau5{key=value}"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "work_precision.csv"));
}

TEST(VariantsCli, BadVariantsAreRefusedNamingThem) {
  const fs::path dir = fresh_dir("variants", "bad");
  const std::string out = " --tol-levels 2 --repeats 1 --out " + shell_quote((dir / "o").string());
  const auto unknown = run_cli(
      "work-precision --model van_der_pol --integrators "
      "'radau5{newtn=frozen}'" +
      out);
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.err.find("integrator variant 'radau5{newtn=frozen}'"), std::string::npos)
      << unknown.err;
  EXPECT_NE(unknown.err.find("newton"), std::string::npos) << unknown.err;  // did you mean
  const auto value = run_cli(
      "work-precision --model van_der_pol --integrators "
      "'radau5{newton=full}'" +
      out);
  EXPECT_EQ(value.code, 2);
  EXPECT_NE(value.err.find("'full'"), std::string::npos) << value.err;
  const auto empty = run_cli("work-precision --model van_der_pol --integrators 'radau5{}'" + out);
  EXPECT_EQ(empty.code, 2) << empty.err;
  const auto clash = run_cli(
      "work-precision --model van_der_pol --integrators "
      "'radau5{newton=frozen,label=rk4}'" +
      out);
  EXPECT_EQ(clash.code, 2);
  EXPECT_NE(clash.err.find("label 'rk4'"), std::string::npos) << clash.err;
}

// The same list in a spec file of `run`, and in a folder of spec files given to `profile`.
TEST(VariantsCli, RunAndProfileTakeVariantsInSpecFiles) {
  const fs::path dir = fresh_dir("variants", "spec_files");
  write_my_esdirk(dir / "suite" / "methods");
  const std::string spec =
      "kind = \"work-precision\"\n"
      "model = \"van_der_pol\"\n"
      "integrators = [\"methods/my_esdirk.toml{newton=full}\", \"radau5\", "
      "\"radau5{linear_solver=dense_lu,label=radau5_dense}\"]\n"
      "rtol_max = 1e-4\ntol_levels = 2\nrepeats = 1\n";
  std::ofstream(dir / "suite" / "01_vdp.toml") << spec;
  const auto run = run_cli("run " + shell_quote((dir / "suite" / "01_vdp.toml").string()) +
                           " --out " + shell_quote((dir / "run").string()));
  ASSERT_EQ(run.code, 0) << run.err;
  std::set<std::string> labels;
  for (const auto& row : rows_of(dir / "run" / "work_precision.csv"))
    labels.insert(row.at("integrator"));
  EXPECT_EQ(labels, (std::set<std::string>{"my_esdirk{newton=full}", "radau5", "radau5_dense"}));
  const auto profile = run_cli("profile " + shell_quote((dir / "suite").string()) + " --out " +
                               shell_quote((dir / "profile").string()));
  ASSERT_EQ(profile.code, 0) << profile.err;
  const std::string md = slurp(dir / "profile" / "profile.md");
  for (const char* label : {"my_esdirk{newton=full}", "radau5_dense"})
    EXPECT_NE(md.find(label), std::string::npos) << label << "\n" << md;
}

}  // namespace
}  // namespace stiffbench
