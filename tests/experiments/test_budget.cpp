// `stiffbench budget`: the grid of configurations, the strain measure against an
// independent computation, the equal-total families of XPBD (Macklin et al. 2019), the best
// configuration at the frame budget, the output files and bad input. Small cloths, few frames;
// no assertion depends on how long anything took.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "core/ode_system.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/studies/budget.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;

constexpr double kFrame = 1.0 / 60.0;

BudgetSpec small_cloth(std::vector<std::string> integrators) {
  BudgetSpec s;
  s.model = "cloth";
  s.params = Params{{"n", 8}, {"perturbation", 0.0}};
  s.integrators = std::move(integrators);
  s.frame = kFrame;
  s.frame_count = 3;
  s.substeps_list = {1, 2, 4};
  s.iterations_list = {1, 3};
  s.timing_repeats = 1;
  return s;
}

// The grid: every method at every substeps value, the methods with an `iterations` parameter
// (xpbd) also at every iterations value; h = frame/substeps, total = substeps × iterations.
TEST(Budget, OneRowPerConfigurationWithItsStepAndTotal) {
  const BudgetResult r = run_budget(small_cloth({"xpbd", "backward_euler"}), nullptr);
  ASSERT_EQ(r.rows.size(), 3u * 2u + 3u);
  std::size_t xpbd = 0, be = 0;
  for (const auto& row : r.rows) {
    EXPECT_NEAR(row.h, kFrame / static_cast<double>(row.substeps), 1e-15) << row.integrator;
    EXPECT_EQ(row.stats.status, Status::ok) << row.stats.message;
    // The driver took substeps steps per frame.
    EXPECT_EQ(row.stats.steps, row.substeps * 3);
    if (row.integrator == "xpbd") {
      ++xpbd;
      ASSERT_TRUE(row.iterations.has_value());
      EXPECT_EQ(*row.total_iterations(), row.substeps * *row.iterations);
    } else {
      ++be;
      EXPECT_FALSE(row.iterations.has_value());
      EXPECT_FALSE(row.total_iterations().has_value());
    }
  }
  EXPECT_EQ(xpbd, 6u);
  EXPECT_EQ(be, 3u);
  const Table t = budget_table(r);
  EXPECT_EQ(t.rows.size(), r.rows.size());
  const auto col = static_cast<std::size_t>(
      std::find(t.columns.begin(), t.columns.end(), "total_iterations") - t.columns.begin());
  ASSERT_LT(col, t.columns.size());
  EXPECT_EQ(t.rows.front()[col], std::to_string(*r.rows.front().total_iterations()));
  EXPECT_EQ(t.rows.back()[col], "");  // backward_euler has no iterations
}

// The cloth without perturbation starts at its rest lengths (prestretch 1): every spring's
// |l - L|/L is round-off. The default perturbation (0.003 per coordinate, spacing 0.1) moves
// points off the grid, so that cloth does not start at rest.
TEST(Budget, RestStateHasZeroStrain) {
  const auto at_rest = model_registry().create("cloth", Params{{"n", 8}, {"perturbation", 0.0}});
  const StrainStats s = spring_strain(*at_rest->spring_network(), at_rest->initial_state());
  EXPECT_GT(s.springs, 0);
  EXPECT_LT(s.max, 1e-14);
  EXPECT_LT(s.rms, 1e-14);
  const auto perturbed = model_registry().create("cloth", Params{{"n", 8}});
  EXPECT_GT(spring_strain(*perturbed->spring_network(), perturbed->initial_state()).max, 1e-3);
}

// The strain reported equals an independent computation: the same configuration run directly
// through the driver (xpbd with substeps = 1 and 3 iterations, h = frame/2 over 3 frames), and
// |l - L|/L evaluated with Eigen's norm over the network's springs.
TEST(Budget, StrainMatchesIndependentComputation) {
  BudgetSpec spec = small_cloth({"xpbd"});
  spec.substeps_list = {2};
  spec.iterations_list = {3};
  const BudgetResult r = run_budget(spec, nullptr);
  ASSERT_EQ(r.rows.size(), 1u);
  EXPECT_EQ(r.initial_strain_max,
            spring_strain(*model_registry().create("cloth", spec.params)->spring_network(),
                          model_registry().create("cloth", spec.params)->initial_state())
                .max);

  const auto sys = model_registry().create("cloth", spec.params);
  auto integ = integrator_registry().create("xpbd", Params{{"substeps", 1}, {"iterations", 3}});
  FixedStepOptions opt;
  opt.t_end = 3 * kFrame;
  opt.h = kFrame / 2;
  const RunResult run = run_fixed_step(*sys, *integ, opt);
  ASSERT_EQ(run.stats.status, Status::ok);
  const SpringNetworkView& net = *sys->spring_network();
  double max = 0, sum2 = 0;
  long n = 0;
  for (const auto& e : net.springs) {
    if (e.k <= 0 || e.rest <= 0) continue;
    const Eigen::Vector3d xi = run.y.segment<3>(3 * e.i), xj = run.y.segment<3>(3 * e.j);
    const double strain = std::abs((xj - xi).norm() - e.rest) / e.rest;
    max = std::max(max, strain);
    sum2 += strain * strain;
    ++n;
  }
  ASSERT_GT(n, 0);
  EXPECT_GT(max, 1e-6);  // the cloth has moved under gravity
  EXPECT_NEAR(r.rows[0].strain_max, max, 1e-12 * max);
  EXPECT_NEAR(r.rows[0].strain_rms, std::sqrt(sum2 / static_cast<double>(n)), 1e-12 * max);
  EXPECT_GE(r.rows[0].strain_peak, r.rows[0].strain_max);
}

// Small steps (Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke, Müller, SCA 2019): at a fixed
// total T = S·I of Gauss-Seidel sweeps per frame, a stiff cloth (α̃ = 1/(k h_s²) ≪ 1/m) is in
// the under-converged regime, where each substep's prediction stretches the springs by about
// g h_s² and each sweep removes a fraction 1 - ρ of the error: the error left is about
// g h_s² ρ^I/(1 - ρ^I) ≈ g h²/(S² · I(1 - ρ)) = g h²/(S T (1 - ρ)), falling as 1/S. With k_struct
// = 1e4, m = 0.01, h = 1/60: k h² = 2.8 ≫ m. So the family 1×4, 2×2, 4×1 has strictly falling
// strain (measured 2.60e-2, 1.54e-2, 1.05e-2). The regime ends once the sweeps converge: on this
// 8-row cloth a total of 8 (2×4: 7.05e-3, 4×2: 9.88e-3) no longer falls, so that family is not
// asserted.
// (The error of the families is the strain error against the rk4 reference, as below; the strain
// itself falls too, asserted on strain_max.)
TEST(Budget, XpbdEqualTotalFamilyFallsWithSubsteps) {
  BudgetSpec spec = small_cloth({"xpbd"});
  spec.params = Params{{"n", 8}, {"perturbation", 0.0}, {"k_struct", 1e4}, {"gravity", 9.81}};
  spec.frame_count = 10;
  spec.substeps_list = {1, 2, 4};
  spec.iterations_list = {1, 2, 4};
  const BudgetResult r = run_budget(spec, nullptr);
  ASSERT_EQ(r.rows.size(), 9u);
  const auto families = equal_total_families(r);
  const auto four = std::find_if(families.begin(), families.end(),
                                 [](const BudgetFamily& f) { return f.total == 4; });
  ASSERT_NE(four, families.end());
  ASSERT_EQ(four->rows.size(), 3u);
  EXPECT_EQ(four->rows[0]->substeps, 1);
  EXPECT_EQ(four->rows[2]->substeps, 4);
  EXPECT_TRUE(four->all_ok);
  EXPECT_TRUE(four->falls) << four->rows[0]->strain_max << " " << four->rows[1]->strain_max << " "
                           << four->rows[2]->strain_max;
  EXPECT_LT(four->rows[2]->strain_max, four->rows[0]->strain_max);
  EXPECT_LT(four->rows[1]->strain_max, four->rows[0]->strain_max);

  // The best configuration at the budget is the smallest strain among the rows that fit, and a
  // row fits when it is ok and its median time is within the frame.
  const BudgetRow* best = best_at_budget(r, "xpbd");
  const BudgetRow* expect = nullptr;
  for (const auto& row : r.rows) {
    EXPECT_EQ(row.fits, row.stats.status == Status::ok && row.ms.median <= 1e3 * kFrame);
    if (row.fits && (!expect || row.error() < expect->error())) expect = &row;
  }
  EXPECT_EQ(best, expect);
  if (best) {
    EXPECT_TRUE(best->fits);
  }

  const fs::path dir =
      fs::temp_directory_path() / ("stiffbench_budget_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  write_budget_outputs(dir, spec, r);
  std::ifstream in(dir / "budget.md");
  std::stringstream md;
  md << in.rdbuf();
  EXPECT_NE(md.str().find("xpbd, total 4: 1×4"), std::string::npos) << md.str();
  EXPECT_NE(md.str().find("falls monotonically with substeps"), std::string::npos);
  std::ifstream csv(dir / "budget.csv");
  std::string line;
  long lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 1 + 9);
  fs::remove_all(dir);
}

// A network without springs of k > 0 (the constrained pendulum chain: its links are distance
// constraints) is measured by its constraint residual. The driver projects onto the
// constraints after every step (M-SHAKE Newton, models/mass_spring/network.hpp), so the residual
// at every frame is at round-off; the strain columns are empty.
TEST(Budget, ConstrainedChainIsMeasuredByItsResidual) {
  BudgetSpec spec = small_cloth({"symplectic_euler"});
  spec.model = "pendulum_chain";
  spec.params = Params{{"constrained", true}};
  spec.substeps_list = {1, 4};
  const BudgetResult r = run_budget(spec, nullptr);
  EXPECT_EQ(r.error_measure, "constraint_residual");
  ASSERT_EQ(r.rows.size(), 2u);
  for (const auto& row : r.rows) {
    ASSERT_EQ(row.stats.status, Status::ok) << row.stats.message;
    EXPECT_TRUE(std::isnan(row.strain_max));
    EXPECT_GE(row.constraint, 0.0);
    EXPECT_LT(row.constraint_peak, 1e-9);
    EXPECT_LE(row.constraint, row.constraint_peak);
    EXPECT_EQ(row.error(), row.constraint);
  }
}

// Through the study pipeline (run_study, as the command runs it): the files, the recorded spec
// and one CSV row per configuration.
TEST(Budget, PipelineWritesTheTablesAndTheSpec) {
  const fs::path dir =
      fs::temp_directory_path() / ("stiffbench_budget_pipeline_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  StudyTarget target;
  target.model = "cloth";
  target.params = Params{{"n", 4}};
  target.integrators = {"xpbd", "symplectic_euler"};
  std::ostringstream out, err;
  StudyContext ctx;
  ctx.out = &out;
  ctx.err = &err;
  const auto job = run_study(
      "budget", target,
      Params{{"frame_count", 2}, {"substeps", "1,3"}, {"iterations", "2"}, {"repeats", 1}}, dir,
      ctx);
  for (const char* f : {"budget.csv", "budget.md", "budget.json"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_EQ(budget_result(*job).rows.size(), 4u);  // (1, 3 substeps) × (xpbd 2 iterations, euler)
  std::ifstream csv(dir / "budget.csv");
  std::string line;
  long lines = 0;
  while (std::getline(csv, line)) ++lines;
  EXPECT_EQ(lines, 1 + 4);
  std::ifstream json(dir / "budget.json");
  std::stringstream meta;
  meta << json.rdbuf();
  EXPECT_NE(meta.str().find("\"frame_count\": 2"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Budget, BadInputNamesWhatIsWrong) {
  const auto message = [](BudgetSpec s) {
    try {
      run_budget(s, nullptr);
    } catch (const BadInput& e) {
      return std::string(e.what());
    }
    return std::string("no BadInput");
  };
  EXPECT_NE(message(small_cloth({"no_such_method"})).find("no_such_method"), std::string::npos);
  BudgetSpec s = small_cloth({"xpbd"});
  s.frame = 0;
  EXPECT_NE(message(s).find("--frame"), std::string::npos);
  s = small_cloth({"backward_euler"});
  s.model = "robertson";
  s.params = Params{};
  EXPECT_NE(message(s).find("mechanical"), std::string::npos);
  s = small_cloth({"xpbd"});
  s.params.set("iterations", "3");
  EXPECT_NE(message(s).find("--iterations"), std::string::npos);

  // The lists of the command line.
  const StudyTarget target{"cloth", Params{{"n", 8}}, {"xpbd"}, {}};
  const auto how = [](const std::string& key) { return option_flag(key); };
  for (const char* bad : {"1,x", "0", "2,2", ""}) {
    std::string what = "no BadInput";
    try {
      make_study(study_kind("budget"), target, Params{{"substeps", bad}}, StudyContext{}, how);
    } catch (const BadInput& e) {
      what = e.what();
    }
    EXPECT_NE(what.find("--substeps"), std::string::npos) << bad << ": " << what;
  }
}

// The strain error against the reference. (1) A configuration that is the reference's own
// computation (rk4 at the reference's 200 steps per frame, deterministic) has strain error 0
// exactly, and a coarser rk4 run (20 steps per frame, hω ≈ 0.1 on this soft cloth: fourth-order
// accurate) a small one, below its strain by orders of magnitude; (2) without a reference
// (ref_substeps 0) the error measure is the strain itself; (3) the perturbed start's strain,
// which the true motion keeps, is not counted as error: backward Euler's error falls with its
// step (first order), while its strain does not have to.
TEST(Budget, StrainErrorIsMeasuredAgainstTheReference) {
  BudgetSpec spec = small_cloth({"rk4", "backward_euler"});
  spec.params = Params{{"n", 8}};  // the default perturbation: starts stretched
  spec.substeps_list = {20, 40, 200};
  spec.iterations_list = {1};
  const BudgetResult r = run_budget(spec, nullptr);
  EXPECT_EQ(r.error_measure, "strain_error_max");
  EXPECT_GT(r.initial_strain_max, 1e-3);
  EXPECT_LT(r.ref_check, 1e-9);
  ASSERT_EQ(r.rows.size(), 6u);
  std::map<std::pair<std::string, long>, const BudgetRow*> at;
  for (const auto& row : r.rows) {
    ASSERT_EQ(row.stats.status, Status::ok) << row.integrator << " " << row.stats.message;
    at[{row.integrator, row.substeps}] = &row;
  }
  EXPECT_EQ(at.at({"rk4", 200})->strain_error_max, 0.0);
  EXPECT_EQ(at.at({"rk4", 200})->error(), 0.0);
  EXPECT_LT(at.at({"rk4", 20})->strain_error_max, 1e-3 * at.at({"rk4", 20})->strain_max);
  // Backward Euler is first order: the error at 200 substeps is about a tenth of the one at 20
  // (allow 0.05 to 0.2).
  const double be20 = at.at({"backward_euler", 20})->strain_error_max;
  const double be200 = at.at({"backward_euler", 200})->strain_error_max;
  EXPECT_GT(be200, 0.05 * be20);
  EXPECT_LT(be200, 0.2 * be20);
  EXPECT_LT(at.at({"backward_euler", 40})->strain_error_max, be20);
  EXPECT_LE(at.at({"backward_euler", 20})->strain_error_rms, be20);

  spec.ref_substeps = 0;
  const BudgetResult none = run_budget(spec, nullptr);
  EXPECT_EQ(none.error_measure, "strain_max");
  for (const auto& row : none.rows) {
    EXPECT_TRUE(std::isnan(row.strain_error_max));
    EXPECT_EQ(row.error(), row.strain_max);
  }
}

// spring_strains lists what spring_strain summarises.
TEST(Budget, SpringStrainsAgreeWithTheirSummary) {
  auto sys = make_setup("cloth", {}, Params{{"n", 6}}).model;
  const SpringNetworkView& net = *sys->spring_network();
  const Vec y = sys->initial_state();
  const std::vector<double> s = spring_strains(net, y);
  const StrainStats st = spring_strain(net, y);
  ASSERT_EQ(static_cast<long>(s.size()), st.springs);
  double max = 0, sum2 = 0;
  for (double v : s) {
    max = std::max(max, v);
    sum2 += v * v;
  }
  EXPECT_EQ(st.max, max);
  EXPECT_NEAR(st.rms, std::sqrt(sum2 / static_cast<double>(s.size())), 1e-15);
}

// The study on inputs resolved once: a method file given by its path (Ralston's method under
// another name) and a variant of a built-in method run under their labels.
TEST(Budget, RunsFromResolvedInputsWithAMethodFileAndAVariant) {
  const auto dir =
      fs::temp_directory_path() / ("stiffbench_budget_inputs_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto file = dir / "budget_ralston.toml";
  std::ofstream(file) << "name = \"budget_ralston\"\nkind = \"explicit_rk\"\n"
                      << "class = \"explicit RK\"\norder = 2\nstage_order = 1\n"
                      << "description = \"Ralston's method under another name\"\n"
                      << "A = [[0, 0], [\"2/3\", 0]]\nb = [\"1/4\", \"3/4\"]\n";
  StudyTarget t;
  t.model = "cloth";
  t.params = Params{{"n", 4}, {"perturbation", 0.0}};
  t.integrators = {file.string(), "backward_euler{newton_max_iter=30}"};
  const StudyInputs in = resolve_inputs(t);
  BudgetSpec spec;
  spec.frame_count = 2;
  spec.substeps_list = {1, 2};
  spec.timing_repeats = 1;
  spec.ref_substeps = 0;
  const BudgetResult r = run_budget(in, spec, nullptr);
  std::vector<std::string> labels;
  for (const auto& row : r.rows) labels.push_back(row.integrator);
  EXPECT_EQ(labels, (std::vector<std::string>{"budget_ralston", "budget_ralston",
                                              "backward_euler{newton_max_iter=30}",
                                              "backward_euler{newton_max_iter=30}"}));
  EXPECT_EQ(r.model, "cloth");
  for (const auto& row : r.rows) EXPECT_EQ(row.stats.status, Status::ok) << row.integrator;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace stiffbench
