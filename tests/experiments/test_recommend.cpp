// `stiffbench recommend`: the answer is the cheapest row of its own table that meets
// the tolerance, the Pareto flags agree with an independent recomputation from the table, bad
// input is refused before anything runs, and a user's own system gets a recommendation. Small
// problems and small budgets; no assertion depends on how long anything took (the recomputation
// reads the same measured times the command used).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_main.hpp"
#include "experiments/build_info.hpp"
#include "experiments/framework/catalog.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/output/csv.hpp"
#include "experiments/studies/recommend.hpp"
#include "tests/experiments/method_file_copy.hpp"

namespace stiffbench {
namespace {

std::string heun_file(const std::string& name) {
  return testing_support::renamed_method_file("heun", name);
}

namespace fs = std::filesystem;

RecommendSpec small_spec() {
  RecommendSpec s;
  s.model = "harmonic_oscillator";
  s.rtol = 1e-6;
  s.t_end = 1.0;
  s.budget_s = 20;
  s.timing_repeats = 1;
  return s;
}

const RecommendResult& harmonic_result() {
  static const RecommendResult r = run_recommend(small_spec(), nullptr);
  return r;
}

double col(const Table& t, std::size_t row, const std::string& name) {
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c] == name) return t.rows[row][c].empty() ? NAN : std::stod(t.rows[row][c]);
  ADD_FAILURE() << "no column " << name;
  return NAN;
}

std::string text(const Table& t, std::size_t row, const std::string& name) {
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c] == name) return t.rows[row][c];
  return "";
}

// The answer, recomputed from the written table alone: among the rows with meets_rtol = 1 (and
// checked again: error_rel <= R), the minimum of wall_s and of f_evals.
TEST(Recommend, AnswerIsTheCheapestRowThatMeetsTheTolerance) {
  const RecommendResult& r = harmonic_result();
  const Table t = recommend_table(r);
  ASSERT_EQ(t.rows.size(), r.rows.size());
  ASSERT_TRUE(r.best_wall && r.best_f) << recommend_markdown(r);
  double min_wall = INFINITY, min_f = INFINITY;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const bool meets = text(t, i, "meets_rtol") == "1";
    EXPECT_EQ(meets, text(t, i, "status") == "ok" && col(t, i, "error_rel") <= r.rtol) << i;
    if (!meets) continue;
    min_wall = std::min(min_wall, col(t, i, "wall_s"));
    min_f = std::min(min_f, col(t, i, "f_evals"));
  }
  EXPECT_LE(col(t, *r.best_wall, "error_rel"), r.rtol);
  EXPECT_LE(col(t, *r.best_f, "error_rel"), r.rtol);
  EXPECT_EQ(col(t, *r.best_wall, "wall_s"), min_wall);
  EXPECT_EQ(col(t, *r.best_f, "f_evals"), min_f);
  // error_rel is the max-norm error over max(1, ||y_ref||_inf); the oscillator's exact solution
  // at t = 1 is (cos 1, -sin 1) (unit frequency, y0 = (1, 0)), so ||y_ref||_inf = sin 1 < 1.
  EXPECT_NEAR(r.ref_norm, std::sin(1.0), 1e-12);
  for (const auto& row : r.rows)
    if (row.run.stats.status == Status::ok) {
      EXPECT_EQ(row.error_rel, row.run.error);
    }
}

// Pareto flags recomputed by brute force from the table: an ok row is on a front iff no other
// ok row is at most as large in both error_rel and cost and smaller in one.
TEST(Recommend, ParetoFlagsMatchABruteForceRecomputation) {
  const RecommendResult& r = harmonic_result();
  const Table t = recommend_table(r);
  int on_wall = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const bool ok = text(t, i, "status") == "ok";
    for (const std::string cost : {"wall_s", "f_evals"}) {
      bool dominated = false;
      for (std::size_t j = 0; ok && j < t.rows.size(); ++j) {
        if (j == i || text(t, j, "status") != "ok") continue;
        const double ei = col(t, i, "error_rel"), ej = col(t, j, "error_rel");
        const double ci = col(t, i, cost), cj = col(t, j, cost);
        dominated = dominated || (ej <= ei && cj <= ci && (ej < ei || cj < ci));
      }
      const std::string flag = text(t, i, cost == "wall_s" ? "on_pareto_wall" : "on_pareto_f");
      EXPECT_EQ(flag == "1", ok && !dominated) << "row " << i << " " << cost;
      if (cost == "wall_s" && flag == "1") ++on_wall;
    }
  }
  EXPECT_GE(on_wall, 1);
}

// mark_pareto on three hand-made rows: (error 1e-3, 1 s, 10 f), (1e-4, 2 s, 5 f) and
// (1e-3, 3 s, 20 f): the third is dominated by the first in both costs; by f evaluations the
// second dominates the first (smaller error, fewer evaluations).
TEST(Recommend, MarkParetoOnAHandMadeTable) {
  std::vector<RecommendRow> rows(3);
  const double e[] = {1e-3, 1e-4, 1e-3}, w[] = {1, 2, 3};
  const long f[] = {10, 5, 20};
  for (int i = 0; i < 3; ++i) {
    rows[i].error_rel = e[i];
    rows[i].run.wall.median = w[i];
    rows[i].run.stats.f_evals = f[i];
  }
  mark_pareto(rows);
  EXPECT_TRUE(rows[0].pareto_wall);
  EXPECT_TRUE(rows[1].pareto_wall);
  EXPECT_FALSE(rows[2].pareto_wall);
  EXPECT_FALSE(rows[0].pareto_f);
  EXPECT_TRUE(rows[1].pareto_f);
  EXPECT_FALSE(rows[2].pareto_f);
}

// The oscillator is not stiff (rho = 1, rho·T = 1 < kStiffRatio) and mechanical: explicit and
// symplectic methods are considered; every candidate carries a reason.
TEST(Recommend, CandidatesFollowTheModelsCapabilities) {
  const RecommendResult& r = harmonic_result();
  EXPECT_FALSE(r.stiff);
  bool explicit_in = false, symplectic_in = false;
  for (const auto& c : r.candidates) {
    EXPECT_FALSE(c.reason.empty()) << c.integrator;
    if (c.family == to_string(Family::explicit_rk) && c.included) explicit_in = true;
    if (c.family == to_string(Family::symplectic) && c.included) symplectic_in = true;
  }
  EXPECT_TRUE(explicit_in);
  EXPECT_TRUE(symplectic_in);
}

int run_cli(std::vector<std::string> args, std::string* err) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream out_s, err_s;
  auto* old_out = std::cout.rdbuf(out_s.rdbuf());
  auto* old_err = std::cerr.rdbuf(err_s.rdbuf());
  const int code = cli_main(static_cast<int>(argv.size()), argv.data());
  std::cout.rdbuf(old_out);
  std::cerr.rdbuf(old_err);
  *err = err_s.str();
  return code;
}

TEST(Recommend, BadInputExitsTwoBeforeAnythingRuns) {
  const fs::path dir = fs::temp_directory_path() / ("recommend_bad_" + std::to_string(getpid()));
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--model", "hires", "--rtol", "0"}, "--rtol"},
      {{"--model", "hires", "--rtol", "-1e-6"}, "--rtol"},
      {{"--model", "no_such_model", "--rtol", "1e-6"}, "no_such_model"},
      {{"--model", "hires", "--rtol", "1e-6", "--budget", "0"}, "--budget"},
      {{"--model", "hires", "--rtol", "1e-6", "--budget", "-5"}, "--budget"}};
  for (const auto& [args, named] : cases) {
    std::vector<std::string> a = {"recommend"};
    a.insert(a.end(), args.begin(), args.end());
    a.insert(a.end(), {"--out", dir.string()});
    std::string err;
    EXPECT_EQ(run_cli(a, &err), 2) << err;
    EXPECT_NE(err.find(named), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir / "recommend.csv"));
  }
  RecommendSpec s = small_spec();
  s.rtol = 0;
  EXPECT_THROW(run_recommend(s, nullptr), BadInput);
  s = small_spec();
  s.budget_s = 0;
  EXPECT_THROW(run_recommend(s, nullptr), BadInput);
  fs::remove_all(dir);
}

// y' = -y, y(0) = 1 on [0, 1], exact exp(-t): a user's own system, not registered.
class UserDecay final : public OdeSystem {
 public:
  std::string name() const override { return "recommend_user_decay"; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }
  void eval_rhs(double, CVecRef y, VecRef f) const override { f[0] = -y[0]; }
};

TEST(Recommend, UsersOwnSystemGetsARecommendation) {
  const fs::path dir = fs::temp_directory_path() / ("recommend_user_" + std::to_string(getpid()));
  RecommendSpec s;
  s.rtol = 1e-5;
  s.t_end = 1.0;
  s.budget_s = 20;
  s.timing_repeats = 1;
  std::ostringstream out, err;
  StudyContext ctx;
  ctx.out = &out;
  ctx.err = &err;
  const RecommendResult r = recommend_study(
      inputs_of(s, StudyObjects{[] { return std::make_unique<UserDecay>(); }, {}}), s, dir, ctx);
  ASSERT_TRUE(r.best_wall) << recommend_markdown(r);
  EXPECT_LE(r.rows[*r.best_wall].error_rel, 1e-5);
  // ||y_ref||_inf = e^-1 < 1: error_rel is the absolute error |y - e^-1|.
  EXPECT_NEAR(r.ref_norm, std::exp(-1.0), 1e-15);
  EXPECT_TRUE(fs::exists(dir / "recommend.csv"));
  EXPECT_TRUE(fs::exists(dir / "recommend.md"));
  EXPECT_EQ(model_registry().find("recommend_user_decay"), nullptr);
  fs::remove_all(dir);
}

// The sweep runs on resolved inputs: a method file and a variant given as integrators are
// candidates under their labels (kept whatever their family) and run or are reported by label.
TEST(RecommendInputs, MethodFileAndVariantAreCandidatesUnderTheirLabels) {
  RecommendSpec s = small_spec();
  s.rtol = 1e-3;
  s.budget_s = 10;
  StudyTarget t;
  t.model = s.model;
  t.integrators = {heun_file("rec_heun"), "radau5{linear_solver=dense_lu,label=radau5_dense_rec}"};
  const StudyInputs in = resolve_inputs(t);
  const RecommendResult r = run_recommend(in, s, nullptr);
  for (const std::string label : {"rec_heun", "radau5_dense_rec"}) {
    bool candidate = false, reported = false;
    for (const auto& c : r.candidates)
      if (c.integrator == label) candidate = c.included;
    for (const auto& row : r.rows) reported = reported || row.run.integrator == label;
    for (const auto& [name, why] : r.dropped) reported = reported || name == label;
    EXPECT_TRUE(candidate) << label;
    EXPECT_TRUE(reported) << label;
  }
}

}  // namespace
}  // namespace stiffbench
