// compare_runs (experiments/commands/compare.hpp) on small hand-written result folders: row
// matching by key columns, the tolerance on reals against exact counters, the wall-time verdict
// from the bootstrap intervals, run-record differences and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/types.hpp"
#include "experiments/commands/compare.hpp"
#include "tests/cli_support.hpp"

namespace stiffbench {
namespace {

namespace fs = std::filesystem;
using testing_support::fresh_dir;

const char* kHeader =
    "model,integrator,setting,error,f_evals,steps,status,newton_iters,wall_s_median,wall_s_ci_low,"
    "wall_s_ci_high,repeats\n";

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

const RowComparison& row_named(const CompareResult& r, const std::string& key) {
  for (const auto& row : r.rows)
    if (row.key == key) return row;
  throw std::runtime_error("no row " + key);
}

// Two folders of one work-precision-like table; NEW differs as each test says.
struct Pair {
  fs::path old_dir, new_dir;
  explicit Pair(const std::string& name)
      : old_dir(fresh_dir("compare", name) / "old"), new_dir(fresh_dir("compare", name) / "new") {
    fs::remove_all(old_dir.parent_path());
  }
  ~Pair() { fs::remove_all(old_dir.parent_path()); }
};

TEST(Compare, SameWithinToleranceAndExactCounters) {
  Pair p("tolerance");
  write(p.old_dir / "work_precision.csv",
        std::string(kHeader) + "m,rk4,h=0.1,1e-05,400,100,ok,0,0.01,0.009,0.011,5\n" +
            "m,rk4,h=0.05,6.25e-07,800,200,ok,0,0.02,0.019,0.021,5\n");
  // A relative change of 1e-13 in an error (within the default 1e-12); different wall times;
  // the rows in another order.
  write(p.new_dir / "work_precision.csv",
        std::string(kHeader) + "m,rk4,h=0.05,6.25e-07,800,200,ok,0,0.03,0.029,0.031,5\n" +
            "m,rk4,h=0.1,1.0000000000001e-05,400,100,ok,0,0.01,0.009,0.011,5\n");
  const CompareResult r = compare_runs(p.old_dir, p.new_dir);
  EXPECT_TRUE(r.same());
  ASSERT_EQ(r.rows.size(), 2u);
  const auto& coarse = row_named(r, "model=m, integrator=rk4, setting=h=0.1");
  EXPECT_FALSE(coarse.changed);
  EXPECT_TRUE(coarse.counter_changes.empty());
  // (1e-5·(1 + 1e-13))/1e-5 - 1 = 1e-13, up to the rounding of both decimals (~1e-16 relative).
  EXPECT_EQ(compare_ratio(1e-5, 1.0000000000001e-05), "1+1.0e-13");
  // A tighter tolerance makes the same relative change a difference.
  CompareOptions tight;
  tight.rtol = 1e-14;
  const CompareResult t = compare_runs(p.old_dir, p.new_dir, tight);
  EXPECT_FALSE(t.same());
  EXPECT_EQ(t.changed_rows(), 1);
  EXPECT_TRUE(row_named(t, "model=m, integrator=rk4, setting=h=0.1").changed);
}

TEST(Compare, CountersExactAndRowsOnOneSide) {
  Pair p("counters");
  write(p.old_dir / "work_precision.csv",
        std::string(kHeader) + "m,bdf2,rtol=1e-6,1e-06,1000000000000,10,ok,7,0.01,0.009,0.011,5\n" +
            "m,bdf2,rtol=1e-7,1e-07,30,10,ok,7,0.01,0.009,0.011,5\n");
  // f_evals differs by 1 in 1e12 (below any relative tolerance on reals: counters are exact), a
  // Newton count changes, and the second row is replaced by another setting.
  write(p.new_dir / "work_precision.csv",
        std::string(kHeader) + "m,bdf2,rtol=1e-6,1e-06,1000000000001,10,ok,9,0.01,0.009,0.011,5\n" +
            "m,bdf2,rtol=1e-8,1e-08,30,10,ok,7,0.01,0.009,0.011,5\n");
  CompareOptions loose;
  loose.rtol = 1e-6;
  const CompareResult r = compare_runs(p.old_dir, p.new_dir, loose);
  EXPECT_FALSE(r.same());
  EXPECT_EQ(r.changed_rows(), 3);  // the changed row, the row only in OLD, the row only in NEW
  const auto& row = row_named(r, "model=m, integrator=bdf2, setting=rtol=1e-6");
  ASSERT_EQ(row.counter_changes.size(), 2u);
  EXPECT_EQ(row.counter_changes[0], "f_evals 1000000000000 -> 1000000000001 (ratio 1+1.0e-12)");
  EXPECT_EQ(row.counter_changes[1], "newton_iters 7 -> 9 (ratio 1.28571)");  // 9/7
  EXPECT_EQ(row_named(r, "model=m, integrator=bdf2, setting=rtol=1e-7").presence,
            RowComparison::Presence::old_only);
  EXPECT_EQ(row_named(r, "model=m, integrator=bdf2, setting=rtol=1e-8").presence,
            RowComparison::Presence::new_only);
}

TEST(Compare, WallTimeVerdictFromBootstrapIntervals) {
  Pair p("verdict");
  // OLD intervals [0.9, 1.1] s. NEW: [0.5, 0.6] (disjoint, below: faster), [1.2, 1.3] (above:
  // slower), [1.0, 1.2] (overlap), [0.5, 0.6] from 3 runs (too few for a verdict: two samples
  // of 3 runs of one distribution have disjoint ranges with probability 1/10).
  std::string a = kHeader, b = kHeader;
  const char* lows[] = {"0.5", "1.2", "1.0", "0.5"};
  const char* highs[] = {"0.6", "1.3", "1.2", "0.6"};
  const char* runs[] = {"5", "5", "5", "3"};
  for (int k = 0; k < 4; ++k) {
    const std::string s = "m,rk4,h=" + std::to_string(k) + ",1e-05,40,10,ok,0,";
    a += s + "1,0.9,1.1,5\n";
    b += s + "1," + lows[k] + "," + highs[k] + "," + runs[k] + "\n";
  }
  write(p.old_dir / "wp" / "work_precision.csv", a);
  write(p.new_dir / "wp" / "work_precision.csv", b);
  const CompareResult r = compare_runs(p.old_dir, p.new_dir);
  EXPECT_TRUE(r.same());  // wall times are not compared
  ASSERT_EQ(r.rows.size(), 4u);
  EXPECT_EQ(r.rows[0].timing.verdict, "faster");
  EXPECT_EQ(r.rows[1].timing.verdict, "slower");
  EXPECT_EQ(r.rows[2].timing.verdict, "not resolved (intervals overlap)");
  EXPECT_EQ(r.rows[3].timing.verdict.rfind("not resolved (5 and 3 runs", 0), 0u)
      << r.rows[3].timing.verdict;
  EXPECT_DOUBLE_EQ(r.rows[1].timing.new_low, 1.2);
  EXPECT_DOUBLE_EQ(r.rows[1].timing.old_high, 1.1);
  EXPECT_EQ(r.rows[0].file, "wp/work_precision.csv");
}

TEST(Compare, RunRecordDifferences) {
  Pair p("records");
  write(p.old_dir / "convergence.csv", "model,integrator,h,error\nm,rk4,0.1,1e-05\n");
  write(p.new_dir / "convergence.csv", "model,integrator,h,error\nm,rk4,0.1,1e-05\n");
  write(p.old_dir / "convergence.json",
        R"({"experiment": "convergence", "spec": {"h": 0.1, "levels": 4}, "git_revision": "a",
            "threads": 2, "seed": null, "cpu_model": "X", "date": "1"})");
  write(p.new_dir / "convergence.json",
        R"({"experiment": "convergence", "spec": {"h": 0.1, "levels": 5}, "git_revision": "b",
            "threads": 2, "seed": null, "cpu_model": "Y", "date": "2"})");
  const CompareResult r = compare_runs(p.old_dir, p.new_dir);
  EXPECT_TRUE(r.same());  // the rows agree; the records are reported
  ASSERT_EQ(r.records.size(), 3u);
  EXPECT_EQ(r.records[0].key, "spec.levels");
  EXPECT_EQ(r.records[0].old_value, "4");
  EXPECT_EQ(r.records[0].new_value, "5");
  EXPECT_EQ(r.records[1].key, "git_revision");
  EXPECT_EQ(r.records[2].key, "cpu_model");
}

TEST(Compare, BadInput) {
  Pair p("bad");
  write(p.old_dir / "a.csv", "x\n1\n");
  write(p.new_dir / "b.csv", "x\n1\n");
  EXPECT_THROW(compare_runs(p.old_dir, p.new_dir), BadInput);            // no CSV of the same path
  EXPECT_THROW(compare_runs(p.old_dir / "a.csv", p.new_dir), BadInput);  // not a folder
  EXPECT_THROW(compare_runs(p.old_dir / "missing", p.new_dir), BadInput);
  write(p.new_dir / "a.csv", "x,y\n1\n");  // a row with fewer fields than its header
  EXPECT_THROW(compare_runs(p.old_dir, p.new_dir), BadInput);
  write(p.new_dir / "a.csv", "x\n1\n");
  CompareOptions negative;
  negative.rtol = -1;
  EXPECT_THROW(compare_runs(p.old_dir, p.new_dir, negative), BadInput);
  EXPECT_NO_THROW(compare_runs(p.old_dir, p.new_dir));
}

}  // namespace
}  // namespace stiffbench
