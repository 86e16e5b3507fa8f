// Work-precision's timing with spread: the bootstrap interval of the median, the
// shuffled run order, the counter and timing columns, and the check that repeats reproduce the
// first run. No assertion here depends on how long anything took.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/driver.hpp"
#include "experiments/build_info.hpp"
#include "experiments/studies/work_precision.hpp"
#include "tests/experiments/method_file_copy.hpp"

namespace stiffbench {
namespace {

std::string heun_file(const std::string& name) {
  return testing_support::renamed_method_file("heun", name);
}

std::size_t column(const Table& t, const std::string& name) {
  const auto it = std::find(t.columns.begin(), t.columns.end(), name);
  EXPECT_NE(it, t.columns.end()) << name;
  return static_cast<std::size_t>(it - t.columns.begin());
}

TEST(TimingSpread, MedianOfOddAndEvenSamples) {
  EXPECT_EQ(median_of({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(median_of({4.0, 1.0, 3.0, 2.0}), 2.5);  // mean of the two middle values
  EXPECT_EQ(median_of({7.0}), 7.0);
  EXPECT_TRUE(std::isnan(median_of({})));
}

// Every resample of a constant sample is that constant, so the interval collapses to it.
TEST(TimingSpread, EqualValuesCollapseTheInterval) {
  for (const std::vector<double>& s : {std::vector<double>{0.25}, std::vector<double>(5, 0.25)}) {
    const TimingSpread t = timing_spread(s, 7, 0);
    EXPECT_EQ(t.repeats, static_cast<int>(s.size()));
    EXPECT_EQ(t.median, 0.25);
    EXPECT_EQ(t.min, 0.25);
    EXPECT_EQ(t.ci_low, 0.25);
    EXPECT_EQ(t.ci_high, 0.25);
  }
}

// Five distinct values x_(1) < ... < x_(5). A resample's median is x_(k) with
// P(median <= x_(k)) = P(Binomial(5, k/5) >= 3) (at least three of five draws at or below x_(k)):
// 0.0579, 0.3174, 0.6826, 0.9421, 1 for k = 1..5 (computed independently from the binomial
// sums). The 2.5% quantile is therefore x_(1) (0.0579 > 0.025) and the 97.5% quantile x_(5)
// (0.9421 < 0.975); with 2000 resamples both margins are over 7 standard deviations of the
// sampled fractions, so the interval is [min, max] whatever the seed.
TEST(TimingSpread, FiveDistinctValuesGiveTheMinMaxInterval) {
  const std::vector<double> s = {0.5, 0.1, 0.4, 0.2, 0.3};
  for (std::uint64_t seed : {1u, 2u, 12345u}) {
    const TimingSpread t = timing_spread(s, seed, 3);
    EXPECT_EQ(t.median, 0.3);
    EXPECT_EQ(t.min, 0.1);
    EXPECT_EQ(t.ci_low, 0.1) << seed;
    EXPECT_EQ(t.ci_high, 0.5) << seed;
  }
}

// The resampling against the exact bootstrap distribution of the median of three values:
// P(median = x_(1)) = P(Binomial(3, 1/3) >= 2) = 7/27, P(median = x_(3)) = 7/27,
// P(median = x_(2)) = 13/27 (binomial sums, by hand). 20000 resample medians drawn with the
// building blocks of timing_spread (uniform_index on an mt19937_64, median_of) must match within
// 5 standard deviations; the interval's ends are then x_(1) and x_(3) (each 0.26 > 0.025).
TEST(TimingSpread, ResampledMediansFollowTheExactBootstrapDistribution) {
  std::mt19937_64 rng(99);
  std::map<int, int> count;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    std::vector<double> d(3);
    for (auto& x : d) x = static_cast<double>(uniform_index(rng, 3));
    ++count[static_cast<int>(median_of(d))];
  }
  const std::vector<double> p = {7.0 / 27, 13.0 / 27, 7.0 / 27};
  for (int k = 0; k < 3; ++k) {
    const double sd = std::sqrt(p[k] * (1 - p[k]) / n);
    EXPECT_NEAR(count[k] / static_cast<double>(n), p[k], 5 * sd) << k;
  }
  const TimingSpread t = timing_spread({0.3, 0.1, 0.2}, 5, 0);
  EXPECT_EQ(t.ci_low, 0.1);
  EXPECT_EQ(t.ci_high, 0.3);
  // The same seed and stream give the same interval; the sample order does not matter.
  const TimingSpread u = timing_spread({0.2, 0.4, 0.1, 0.3}, 5, 2);
  const TimingSpread v = timing_spread({0.2, 0.4, 0.1, 0.3}, 5, 2);
  EXPECT_EQ(u.ci_low, v.ci_low);
  EXPECT_EQ(u.ci_high, v.ci_high);
  EXPECT_EQ(u.median, 0.25);
  EXPECT_LE(u.ci_low, u.median);
  EXPECT_GE(u.ci_high, u.median);
}

TEST(RunOrder, EachRoundIsAPermutationReproducibleFromTheSeed) {
  const std::size_t n = 37;
  std::set<std::vector<std::size_t>> rounds;
  for (std::uint64_t round = 1; round <= 5; ++round) {
    const auto order = run_order(n, 42, round);
    std::vector<std::size_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::size_t> iota(n);
    std::iota(iota.begin(), iota.end(), 0);
    EXPECT_EQ(sorted, iota) << "round " << round;
    EXPECT_EQ(order, run_order(n, 42, round));  // reproducible
    rounds.insert(order);
  }
  EXPECT_EQ(rounds.size(), 5u);                         // rounds are shuffled afresh
  EXPECT_NE(run_order(n, 42, 1), run_order(n, 43, 1));  // the seed matters
  EXPECT_EQ(run_order(1, 42, 1), std::vector<std::size_t>{0});
  EXPECT_TRUE(run_order(0, 42, 1).empty());
}

// Fisher-Yates with an exact uniform index makes the 6 orders of 3 points equally likely
// (1/6 each): 12000 rounds, each order within 5 standard deviations of 2000.
TEST(RunOrder, OrdersOfThreePointsAreEquallyLikely) {
  std::map<std::vector<std::size_t>, int> count;
  const int n = 12000;
  for (int r = 0; r < n; ++r) ++count[run_order(3, 7, static_cast<std::uint64_t>(r))];
  ASSERT_EQ(count.size(), 6u);
  const double sd = std::sqrt(n * (1.0 / 6) * (5.0 / 6));
  for (const auto& [order, c] : count) EXPECT_NEAR(c, n / 6.0, 5 * sd);
}

// A work-precision run on the harmonic oscillator (exact solution): the timing columns follow
// the counters, wall_s is the median, the interval brackets it, every row ran at least once and
// at most --repeats times, and the repeats reproduced the first run (status ok).
TEST(WorkPrecisionTiming, ColumnsAndRepeats) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4", "backward_euler", "cvode_bdf"};
  spec.t_end = 1;
  spec.h = 0.05;
  spec.levels = 2;
  spec.tol_levels = 2;
  spec.repeats = 3;
  spec.seed = 11;
  const WorkPrecisionResult res = run_work_precision(spec, nullptr);
  const Table t = work_precision_table(res);
  const std::vector<std::string> tail = {
      "newton_iters",  "newton_conv_failures", "error_test_failures",
      "linear_setups", "linear_iters",         "fe_evals",
      "fi_evals",      "wall_s_median",        "wall_s_min",
      "wall_s_ci_low", "wall_s_ci_high",       "repeats",
      "flag",          "reference_error"};
  ASSERT_EQ(t.columns.size(), 11u + tail.size());
  EXPECT_EQ(std::vector<std::string>(t.columns.begin() + 11, t.columns.end()), tail);
  ASSERT_EQ(t.rows.size(), 6u);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    const auto& r = res.rows[i];
    EXPECT_EQ(row[column(t, "status")], "ok") << r.stats.message;
    const int reps = std::stoi(row[column(t, "repeats")]);
    EXPECT_GE(reps, 1);
    EXPECT_LE(reps, 3);
    EXPECT_EQ(row[column(t, "wall_s")], row[column(t, "wall_s_median")]);
    EXPECT_LE(r.wall.min, r.wall.median);
    EXPECT_LE(r.wall.min, r.wall.ci_low);
    EXPECT_LE(r.wall.ci_low, r.wall.median);
    EXPECT_LE(r.wall.median, r.wall.ci_high);
    EXPECT_EQ(row[column(t, "newton_iters")], std::to_string(r.stats.newton_iters));
    // The exact solution is the reference: its error is 0 and no row is at its floor.
    EXPECT_EQ(row[column(t, "reference_error")], "0");
    EXPECT_EQ(row[column(t, "flag")], "");
  }
  EXPECT_EQ(res.reference.kind, "exact");
  // rk4 is explicit: no Newton iterations, no set-ups; backward Euler and CVODE's BDF solve a
  // nonlinear system per step.
  EXPECT_EQ(res.rows[0].stats.newton_iters, 0);
  EXPECT_EQ(res.rows[0].stats.linear_setups, 0);
  for (std::size_t i = 2; i < 6; ++i) {
    EXPECT_GE(res.rows[i].stats.newton_iters, res.rows[i].stats.steps) << res.rows[i].integrator;
    EXPECT_GE(res.rows[i].stats.linear_setups, 1) << res.rows[i].integrator;
  }
  // The same seed gives the same rows apart from the times.
  const WorkPrecisionResult again = run_work_precision(spec, nullptr);
  for (std::size_t i = 0; i < res.rows.size(); ++i) {
    EXPECT_EQ(again.rows[i].error, res.rows[i].error);
    EXPECT_EQ(again.rows[i].stats.f_evals, res.rows[i].stats.f_evals);
    EXPECT_EQ(again.rows[i].stats.counter_values(), res.rows[i].stats.counter_values());
  }
}

// A method whose work changes from run to run (its k-th run makes k extra f evaluations in its
// first step): its repeats do not reproduce the first run, and the row says so.
class Fickle : public Integrator {
 public:
  Fickle() : Integrator(info()) {}
  void reset(const OdeSystem& sys, double, CVecRef) override {
    k_.resize(sys.dimension());
    extra_ = ++resets_;
  }
  Status step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) override {
    for (; extra_ > 0; --extra_) sys.rhs(t, y, k_);
    sys.rhs(t, y, k_);
    y += h * k_;
    return Status::ok;
  }

 private:
  static MethodInfo info() {
    MethodInfo i;
    i.name = "fickle_euler";
    i.description = "explicit Euler with a varying extra f evaluation";
    i.family = Family::explicit_rk;
    i.order = 1;
    i.stages = 1;
    return i;
  }
  Vec k_;
  int resets_ = 0, extra_ = 0;
};

TEST(WorkPrecisionTiming, RepeatThatDiffersIsAnError) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"euler"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  spec.repeats = 2;
  const WorkPrecisionResult res = run_work_precision(
      inputs_of(spec, StudyObjects{nullptr, {[] { return std::make_unique<Fickle>(); }}}), spec,
      nullptr);
  ASSERT_EQ(res.rows.size(), 4u);
  for (std::size_t i = 0; i < 2; ++i) {  // euler: deterministic
    EXPECT_EQ(res.rows[i].stats.status, Status::ok) << res.rows[i].stats.message;
  }
  // fickle_euler: every run of the object makes a different number of f evaluations.
  for (std::size_t i = 2; i < 4; ++i) {
    const auto& r = res.rows[i];
    EXPECT_EQ(r.integrator, "fickle_euler");
    EXPECT_EQ(r.stats.status, Status::error);
    EXPECT_NE(r.stats.message.find("not deterministic"), std::string::npos) << r.stats.message;
    EXPECT_NE(r.stats.message.find("f_evals"), std::string::npos) << r.stats.message;
  }
}

// The files record how the times were taken: the JSON's timing block (seed, the repeat rule,
// the resamples) and the Markdown's "median [interval]" columns.
TEST(WorkPrecisionTiming, OutputsRecordTheTimingRule) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.levels = 2;
  spec.repeats = 2;
  spec.seed = 5;
  const WorkPrecisionResult res = run_work_precision(spec, nullptr);
  const auto dir =
      std::filesystem::temp_directory_path() / ("sb_wp_timing_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  write_work_precision_outputs(dir.string(), spec, res);
  std::ifstream js(dir / "work_precision.json");
  const auto meta = nlohmann::json::parse(js);
  EXPECT_EQ(meta.at("spec").at("seed"), 5);
  EXPECT_EQ(meta.at("timing").at("seed"), 5);
  EXPECT_EQ(meta.at("timing").at("max_repeats"), 2);
  EXPECT_EQ(meta.at("timing").at("bootstrap_resamples"), kBootstrapResamples);
  EXPECT_EQ(meta.at("timing").at("repeat_long_run_s").get<double>(), kRepeatLongRun);
  EXPECT_EQ(meta.at("timing").at("repeat_budget_s").get<double>(), kRepeatBudget);
  std::ifstream md(dir / "work_precision.md");
  const std::string text((std::istreambuf_iterator<char>(md)), {});
  EXPECT_NE(text.find("| wall s (median) | 95% interval | repeats |"), std::string::npos) << text;
  EXPECT_NE(text.find("seed 5"), std::string::npos) << text;
  // rk4 solves nothing: no solver-counter column in the Markdown.
  EXPECT_EQ(text.find("newton_iters"), std::string::npos) << text;
  std::filesystem::remove_all(dir);
}

TEST(WorkPrecisionTiming, SeedIsRecordedAndRepeatsValidated) {
  WorkPrecisionSpec spec;
  spec.seed = 77;
  EXPECT_EQ(spec.to_json().at("seed"), 77);
  EXPECT_EQ(spec.to_json().at("repeats"), 5);  // the default
  spec.model = "harmonic_oscillator";
  spec.integrators = {"rk4"};
  spec.t_end = 1;
  spec.h = 0.1;
  spec.repeats = 0;
  EXPECT_THROW(run_work_precision(spec, nullptr), BadInput);
}

// tolerance_response_notes on hand-made rows (the slopes by hand: log10 error against log10 rtol).
// "flat": errors 5e-3, 6e-3, 2e-3 at rtol 1e-4, 1e-6, 1e-8 (ark324l2sa with the filtered estimate
// on stiff Prothero-Robinson): log10 e = -2.301, -2.222, -2.699 against log10 rtol = -4, -6, -8
// gives the slope (2 * 0.106 + 2 * 0.292) / 8 = 0.0995, and 2e-3 > 100 * 1e-8, so it is named.
// "good": errors 10 rtol (slope 1): not named. "floor": 1e-9, 1e-12, 3e-13, slope
// (2 * 2.174 + 2 * 1.349) / 8 = 0.881: not named. "short": two settings only: no fit. "fixed":
// h settings: not adaptive.
TEST(WorkPrecisionTolerance, AMethodWhoseErrorIgnoresTheToleranceIsNamed) {
  WorkPrecisionResult res;
  auto add = [&](const std::string& name, const std::string& setting, double error) {
    WorkPrecisionRow r;
    r.integrator = name;
    r.setting = setting;
    r.error = error;
    r.stats.status = Status::ok;
    res.rows.push_back(r);
  };
  const std::vector<std::string> rtols = {"rtol=1e-04", "rtol=1e-06", "rtol=1e-08"};
  const std::vector<double> flat = {5e-3, 6e-3, 2e-3}, good = {1e-3, 1e-5, 1e-7},
                            floor = {1e-9, 1e-12, 3e-13}, fixed = {1e-2, 1e-2, 1e-2};
  for (std::size_t k = 0; k < 3; ++k) {
    add("flat", rtols[k], flat[k]);
    add("good", rtols[k], good[k]);
    add("floor", rtols[k], floor[k]);
    add("fixed", "h=" + std::to_string(k + 1), fixed[k]);
  }
  add("short", "rtol=1e-04", 1e-2);
  add("short", "rtol=1e-06", 1e-2);
  const std::vector<std::string> notes = tolerance_response_notes(res);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0].rfind("**flat**: the error does not follow the tolerance (slope 0.10", 0), 0u)
      << notes[0];
  // A failed run is no evidence either way: with the 2e-3 row failed, two settings remain.
  res.rows[8].stats.status = Status::newton_failed;  // flat at rtol=1e-08
  EXPECT_TRUE(tolerance_response_notes(res).empty());
}

// --- The reference and its check ---------------------------------------------------------

// The IVP test set's HIRES solution at t = 321.8122 (Mazzia & Magherini 2008, problem hires),
// typed from the literature (not read from the model).
const std::vector<double> kHiresPublished = {
    0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4, 0.1175651343283149e-2,
    0.2386356198831331e-2, 0.6238968252742796e-2, 0.2849998395185769e-2, 0.2850001604814231e-2};
constexpr double kHiresEnd = 321.8122;

// An independent run of a library code on a fresh copy of `model` to t at rtol and atol.
Vec library_state(const std::string& model, const std::string& method, double t, double rtol,
                  double atol) {
  const auto sys = model_registry().create(model, Params{});
  Params p;
  p.set("rtol", format_full(rtol));
  p.set("atol", format_full(atol));
  const auto integ = integrator_registry().create(method, p);
  const RunResult r = run_adaptive(*sys, *integ, {t, 0});
  EXPECT_EQ(r.stats.status, Status::ok) << r.stats.message;
  return r.y;
}

double max_distance(const Vec& a, const std::vector<double>& b) {
  double d = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    d = std::max(d, std::abs(a[static_cast<Index>(i)] - b[i]));
  return d;
}

std::vector<double> as_vector(const Vec& y) {
  return std::vector<double>(y.data(), y.data() + y.size());
}

nlohmann::json written_json(const WorkPrecisionSpec& spec, const WorkPrecisionResult& res,
                            const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("sb_wp_ref_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  write_work_precision_outputs(dir.string(), spec, res);
  std::ifstream js(dir / "work_precision.json");
  const auto meta = nlohmann::json::parse(js);
  std::filesystem::remove_all(dir);
  return meta;
}

// HIRES with the default reference: the published solution is the reference (its stated
// accuracy, ~1e-18, is far below cvode_bdf's at rtol 1e-14), and the JSON records the
// published-solution check of the numerical reference. Every recorded number is recomputed here:
// cvode_bdf by an independent run, the distance from the literature's values, and the stated
// accuracy by hand: y6 = 0.6238968252742796e-2 is the largest component and its 16th significant
// digit is the 1e-18 place, so half a unit is 0.5e-18, plus its rounding to double 2^-53·|y6|
// (every other component's last digit is at 1e-18 or 1e-19 and its value smaller).
TEST(WorkPrecisionReference, PublishedSolutionIsTheReferenceAndChecksTheNumericalOne) {
  WorkPrecisionSpec spec;
  spec.model = "hires";
  spec.integrators = {"radau5"};
  spec.rtol_max = 1e-6;
  spec.tol_levels = 2;
  spec.repeats = 1;
  const WorkPrecisionResult res = run_work_precision(spec, nullptr);
  const auto rc = written_json(spec, res, "published").at("reference_check");
  EXPECT_EQ(rc.at("kind"), "published");
  const auto& pub = rc.at("published");
  EXPECT_EQ(pub.at("t").get<double>(), kHiresEnd);
  EXPECT_EQ(pub.at("values").get<std::vector<double>>(), kHiresPublished);
  const double stated = 0.5e-18 + 0x1p-53 * 0.6238968252742796e-2;
  EXPECT_DOUBLE_EQ(pub.at("stated_accuracy").get<double>(), stated);
  EXPECT_DOUBLE_EQ(rc.at("estimated_error").get<double>(), stated);

  // The numerical reference: cvode_bdf at rtol 1e-14, atol 1e-16 (deterministic: the same
  // state), its distance from the published values, and its second run at rtol and atol / 10.
  const Vec r = library_state("hires", "cvode_bdf", kHiresEnd, 1e-14, 1e-16);
  const Vec r2 = library_state("hires", "cvode_bdf", kHiresEnd, 1e-15, 1e-16 / 10);
  const auto& num = rc.at("numerical");
  EXPECT_EQ(num.at("values").get<std::vector<double>>(), as_vector(r));
  const double distance = max_distance(r, kHiresPublished);
  EXPECT_DOUBLE_EQ(pub.at("distance_from_numerical").get<double>(), distance);
  EXPECT_DOUBLE_EQ(num.at("check_difference").get<double>(), max_distance(r, as_vector(r2)));
  // The model's notes: CVODE BDF at rtol 1e-13 reproduces the published values to 3e-11
  // relative (components below 1e-2): rtol 1e-14 is within 1e-12 absolute, and not exact.
  EXPECT_GT(distance, 0);
  EXPECT_LT(distance, 1e-12);
  EXPECT_TRUE(num.at("method_studied") == false);

  // The errors are against the published values; radau5 at rtol 1e-6 and 1e-7 is far above
  // 10 × 1.2e-18, so no row is marked.
  EXPECT_EQ(rc.at("rows_at_reference_floor"), 0);
  const Table t = work_precision_table(res);
  for (const auto& row : t.rows) {
    EXPECT_EQ(row[column(t, "flag")], "");
    EXPECT_DOUBLE_EQ(std::stod(row[column(t, "reference_error")]), stated);
  }
}

// A deliberately loose reference (cvode_bdf at rtol 1e-11, atol 1e-14) on HIRES: its estimated
// error is the larger of its second run's difference and its distance from the published
// solution, both recomputed here; the rows within 10 times of it are marked reference_floor. By
// the triangle inequality a row's error against the reference is within radau5's own error
// (against the published values, computed here) of the reference's distance d: radau5 at rtol
// 1e-10 is far more accurate than d, so its error is about d and the row is marked; at rtol
// 1e-5 its own error is more than 10 d + d, so that row is not.
TEST(WorkPrecisionReference, RowsAtALooseReferenceAreMarked) {
  WorkPrecisionSpec spec;
  spec.model = "hires";
  spec.integrators = {"radau5"};
  spec.reference = "cvode_bdf";
  spec.reference_rtol = 1e-11;
  spec.reference_atol = 1e-14;
  spec.tol_levels = 6;  // rtol 1e-5 ... 1e-10
  spec.repeats = 1;
  const WorkPrecisionResult res = run_work_precision(spec, nullptr);
  const Vec r = library_state("hires", "cvode_bdf", kHiresEnd, 1e-11, 1e-14);
  const Vec r2 = library_state("hires", "cvode_bdf", kHiresEnd, 1e-12, 1e-15);
  const double d = max_distance(r, kHiresPublished);
  const double estimate = std::max(d, max_distance(r, as_vector(r2)));
  ASSERT_TRUE(res.reference.error_estimate.has_value());
  EXPECT_EQ(res.reference.kind, "numerical");
  EXPECT_DOUBLE_EQ(*res.reference.error_estimate, estimate);

  const double own_tight =
      max_distance(library_state("hires", "radau5", kHiresEnd, 1e-10, 1e-13), kHiresPublished);
  const double own_loose =
      max_distance(library_state("hires", "radau5", kHiresEnd, 1e-5, 1e-8), kHiresPublished);
  ASSERT_LT(own_tight, 0.1 * d);
  ASSERT_GT(own_loose, 11 * estimate);
  const Table t = work_precision_table(res);
  ASSERT_EQ(t.rows.size(), 6u);
  EXPECT_EQ(t.rows.front()[column(t, "setting")], "rtol=1e-05");
  EXPECT_EQ(t.rows.front()[column(t, "flag")], "");
  EXPECT_EQ(t.rows.back()[column(t, "setting")], "rtol=1e-10");
  EXPECT_EQ(t.rows.back()[column(t, "flag")], "reference_floor");
  std::size_t marked = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const bool floor = res.rows[i].error <= 10 * estimate;
    EXPECT_EQ(res.rows[i].at_reference_floor, floor) << res.rows[i].setting;
    EXPECT_EQ(t.rows[i][column(t, "flag")], floor ? "reference_floor" : "");
    EXPECT_DOUBLE_EQ(std::stod(t.rows[i][column(t, "reference_error")]), estimate);
    marked += floor ? 1 : 0;
  }
  const auto meta = written_json(spec, res, "loose");
  EXPECT_EQ(meta.at("reference_check").at("rows_at_reference_floor"), marked);
}

// The default reference on a model with neither an exact nor a published solution (van der
// Pol): cvode_bdf at rtol 1e-14, its error estimated by the second run at rtol 1e-15 (recomputed
// here); radau5 studied down to rtol 1e-9 has its rows within 10 times of it marked.
TEST(WorkPrecisionReference, DefaultNumericalReferenceIsEstimatedBySecondRun) {
  WorkPrecisionSpec spec;
  spec.model = "van_der_pol";
  spec.integrators = {"radau5", "cvode_bdf"};
  spec.rtol_max = 1e-8;
  spec.tol_levels = 2;
  spec.repeats = 1;
  const WorkPrecisionResult res = run_work_precision(spec, nullptr);
  const double t_end = res.t_end;
  const Vec r = library_state("van_der_pol", "cvode_bdf", t_end, 1e-14, 1e-16);
  const Vec r2 = library_state("van_der_pol", "cvode_bdf", t_end, 1e-15, 1e-16 / 10);
  const double estimate = max_distance(r, as_vector(r2));
  EXPECT_EQ(res.reference.kind, "numerical");
  EXPECT_FALSE(res.reference.has_published);
  EXPECT_TRUE(res.reference.method_studied);  // cvode_bdf is also studied (allowed with auto)
  ASSERT_TRUE(res.reference.error_estimate.has_value());
  EXPECT_DOUBLE_EQ(*res.reference.error_estimate, estimate);
  for (const auto& row : res.rows)
    EXPECT_EQ(row.at_reference_floor, row.error <= 10 * estimate) << row.integrator << row.setting;
}

// The stated accuracy of a published solution, by hand: ROBER's largest component
// 0.9999999791665050 has its 16th significant digit at 1e-16, so 0.5e-16 plus its rounding to
// double 2^-53·|y3| (y1 = 2.08e-8 and y2 = 8.3e-14 are good to 5e-24 and 5e-30); OREGO's
// y2 = 1228.178521549917 has its 16th digit at 1e-12: 0.5e-12 + 2^-53·|y2| (y1 ≈ 1.0008 and
// y3 ≈ 132.06 are good to ~1e-15 and ~5e-14).
TEST(WorkPrecisionReference, StatedAccuracyOfPublishedSolutions) {
  const auto rober = model_registry().create("robertson", Params{})->published_solution();
  ASSERT_TRUE(rober.has_value());
  EXPECT_DOUBLE_EQ(published_accuracy(*rober), 0.5e-16 + 0x1p-53 * 0.9999999791665050);
  const auto orego = model_registry().create("orego", Params{})->published_solution();
  ASSERT_TRUE(orego.has_value());
  EXPECT_DOUBLE_EQ(published_accuracy(*orego), 0.5e-12 + 0x1p-53 * 1228.178521549917);
  // Robertson with other rate constants has no published solution.
  EXPECT_FALSE(model_registry()
                   .create("robertson", Params::from_assignments({"k1=0.05"}))
                   ->published_solution()
                   .has_value());
}

// A --reference that is one of the integrators is refused before anything runs.
TEST(WorkPrecisionReference, AMethodIsNotItsOwnReference) {
  WorkPrecisionSpec spec;
  spec.model = "hires";
  spec.integrators = {"radau5", "rodas4"};
  spec.reference = "radau5";
  try {
    spec.validate();
    ADD_FAILURE() << "radau5 as its own reference was accepted";
  } catch (const BadInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("--reference radau5 is also one of --integrators"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("cvode_bdf"), std::string::npos) << msg;  // a method to use instead
  }
  EXPECT_THROW(run_work_precision(spec, nullptr), BadInput);
  spec.reference = "cvode_bdf";
  EXPECT_NO_THROW(spec.validate());
  spec.reference = "published";
  EXPECT_NO_THROW(spec.validate());
}

// The study runs on resolved inputs: a method file (fixed-step, over the h ladder) and a variant
// (adaptive, over the tolerance ladder with its fixed key kept) appear under their labels.
TEST(WorkPrecisionInputs, MethodFileAndVariantRunUnderTheirLabels) {
  WorkPrecisionSpec spec;
  spec.model = "harmonic_oscillator";
  spec.t_end = 1;
  spec.h = 0.05;
  spec.levels = 2;
  spec.tol_levels = 2;
  spec.repeats = 1;
  spec.reference = "exact";
  StudyTarget t;
  t.model = spec.model;
  t.integrators = {heun_file("wp_heun"), "radau5{linear_solver=dense_lu,label=radau5_dense_wp}"};
  const StudyInputs in = resolve_inputs(t);
  const WorkPrecisionResult r = run_work_precision(in, spec, nullptr);
  ASSERT_EQ(r.rows.size(), 4u);
  const std::vector<std::string> labels = {"wp_heun", "wp_heun", "radau5_dense_wp",
                                           "radau5_dense_wp"};
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    EXPECT_EQ(r.rows[k].integrator, labels[k]) << k;
    EXPECT_EQ(r.rows[k].stats.status, Status::ok) << r.rows[k].stats.message;
  }
  EXPECT_EQ(r.rows[0].setting.rfind("h=", 0), 0u) << r.rows[0].setting;
  EXPECT_EQ(r.rows[2].setting.rfind("rtol=", 0), 0u) << r.rows[2].setting;
}

}  // namespace
}  // namespace stiffbench
