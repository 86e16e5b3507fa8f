// The stability-region experiment (experiments/studies/region.hpp): limits against the published
// values of docs/reference-values.md and their closed forms, region.csv points checked against R(z)
// recomputed independently from each tableau (ButcherTableau::stability), the polyline contract of
// the CSV, the fitted box, and the refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/build_info.hpp"
#include "experiments/studies/region.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/implicit/dirk.hpp"
#include "tests/experiments/method_file_copy.hpp"

namespace stiffbench {
namespace {

const RegionMethod& method(const RegionResult& r, const std::string& name) {
  for (const auto& m : r.methods)
    if (m.integrator == name) return m;
  throw std::logic_error("no method " + name);
}

const ButcherTableau& tableau(const std::string& name) {
  for (const auto& t : explicit_tableaux())
    if (t.name == name) return t;
  return implicit_tableau(name);
}

RegionSpec four_methods() {
  RegionSpec spec;
  spec.integrators = {"rk4", "heun", "kutta3", "sdirk3"};
  spec.resolution = 200;  // enough for the contract; the command's default is 400
  return spec;
}

// docs/reference-values.md, "Linear stability": rk4 real −2.7853, imaginary 2√2 = 2.8284; kutta3
// real −2.5127, imaginary √3 = 1.7321; heun real −2 (R(−2) = 1 − 2 + 2 = 1) and unstable on the
// whole imaginary axis (|R(iy)|² = 1 + y⁴/4); sdirk3 is A-stable (Alexander 1977).
TEST(RegionExperiment, LimitsMatchPublishedValues) {
  const RegionResult r = run_region(four_methods());
  ASSERT_EQ(r.methods.size(), 4u);
  const auto& rk4 = method(r, "rk4");
  ASSERT_TRUE(rk4.real_axis && rk4.imaginary_axis);
  EXPECT_NEAR(-rk4.real_axis->limit, -2.7853, 1e-3);
  EXPECT_NEAR(rk4.imaginary_axis->limit, 2.0 * std::numbers::sqrt2, 1e-3);
  EXPECT_NEAR(rk4.oscillator.limit, 2.0 * std::numbers::sqrt2, 1e-3);  // same ray, hω = y
  EXPECT_EQ(rk4.a_stable, std::optional<bool>(false));
  const auto& kutta3 = method(r, "kutta3");
  EXPECT_NEAR(-kutta3.real_axis->limit, -2.5127, 1e-3);
  EXPECT_NEAR(kutta3.imaginary_axis->limit, std::sqrt(3.0), 1e-3);
  const auto& heun = method(r, "heun");
  EXPECT_NEAR(-heun.real_axis->limit, -2.0, 1e-3);
  EXPECT_EQ(heun.imaginary_axis->limit, 0.0);
  EXPECT_FALSE(heun.imaginary_axis->unbounded);
  const auto& sdirk3 = method(r, "sdirk3");
  EXPECT_EQ(sdirk3.a_stable, std::optional<bool>(true));
  EXPECT_TRUE(sdirk3.real_axis->unbounded);
  EXPECT_TRUE(sdirk3.imaginary_axis->unbounded);

  // The limits table in the contract order, with the signed numbers.
  const Table t = region_limits_table(r);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"integrator", "family", "kind", "real_axis_limit",
                                                 "imaginary_axis_limit", "oscillator_limit",
                                                 "a_stable", "limits"}));
  EXPECT_EQ(t.rows[0][7], "exact");
  EXPECT_EQ(t.rows[0][0], "rk4");
  EXPECT_NEAR(std::stod(t.rows[0][3]), -2.7853, 1e-3);
  EXPECT_EQ(t.rows[3][3], "-inf");
  EXPECT_EQ(t.rows[3][4], "inf");
  EXPECT_EQ(t.rows[3][6], "yes");
}

// The imaginary-axis limits of the embedded pairs from the roots of |P(iy)|² − 1
// (exact rational arithmetic, Python fractions, on the published tableaux): cash_karp
// |P(iy)|² − 1 = +y⁶/3600 + ..., rkf45 +5y⁶/936 + ... (both 0: unstable next to 0; the sampled
// search reported 0.1386 and 0.0849), dopri5 −y⁶/1800 + y⁸/1600 − y¹⁰/14400 + y¹²/360000, whose
// first positive root is y = 0.997189008632529915... (bisected in rationals). bdf2 (no R = P/Q)
// is marked sampled.
TEST(RegionExperiment, EmbeddedPairsImaginaryLimitsAreExact) {
  RegionSpec spec;
  spec.integrators = {"cash_karp", "rkf45", "dopri5", "bdf2"};
  spec.resolution = 40;
  const RegionResult r = run_region(spec);
  EXPECT_EQ(method(r, "cash_karp").imaginary_axis->limit, 0.0);
  EXPECT_EQ(method(r, "rkf45").imaginary_axis->limit, 0.0);
  EXPECT_EQ(method(r, "cash_karp").oscillator.limit, 0.0);
  EXPECT_NEAR(method(r, "dopri5").imaginary_axis->limit, 0.997189008632529915, 1e-12);
  EXPECT_NEAR(method(r, "dopri5").oscillator.limit, 0.997189008632529915, 1e-12);
  const Table t = region_limits_table(r);
  ASSERT_EQ(t.rows.size(), 4u);
  EXPECT_EQ(t.rows[0][4], "0");
  EXPECT_EQ(t.rows[1][4], "0");
  EXPECT_NEAR(std::stod(t.rows[2][4]), 0.997189008632529915, 1e-12);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(t.rows[static_cast<std::size_t>(k)][7], "exact");
  EXPECT_EQ(t.rows[3][7], "sampled");
}

std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& file) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream f(file);
  for (std::string line; std::getline(f, line);) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

// Every point of region.csv lies on |R(z)| = 1, with R recomputed from the tableau (not through
// core/linear_stability); consecutive points of one polyline are neighbours (rows in order);
// `nan` rows only separate polylines of one method; each method's curve reaches the published
// real-axis limit and encloses the box's share of the imaginary axis it should.
TEST(RegionExperiment, CsvPointsLieOnTheBoundaryInOrder) {
  const RegionSpec spec = four_methods();
  const RegionResult r = run_region(spec);
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_region_test") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  write_region_outputs(dir, spec, r);
  const auto rows = read_csv(dir / "region.csv");
  ASSERT_GT(rows.size(), 1u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"integrator", "re", "im"}));
  // A polyline step never exceeds a grid cell's diagonal (each segment joins crossings on two
  // edges of one cell).
  const double cell = std::max((r.box.re_max - r.box.re_min), (r.box.im_max - r.box.im_min)) /
                      spec.resolution * std::numbers::sqrt2 * 1.0001;
  std::map<std::string, int> points, breaks;
  std::map<std::string, double> min_re;
  double worst = 0.0;
  std::complex<double> prev;
  bool has_prev = false;  // a point of the current polyline precedes
  std::string prev_name;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 3u) << i;
    const std::string& name = rows[i][0];
    if (name != prev_name) has_prev = false;
    prev_name = name;
    if (rows[i][1] == "nan") {
      EXPECT_EQ(rows[i][2], "nan");
      EXPECT_TRUE(has_prev) << "break row without a polyline before it, row " << i;
      ASSERT_TRUE(i + 1 < rows.size() && rows[i + 1][0] == name) << "break row at the end";
      ++breaks[name];
      has_prev = false;
      continue;
    }
    const std::complex<double> z(std::stod(rows[i][1]), std::stod(rows[i][2]));
    EXPECT_GE(z.real(), r.box.re_min);
    EXPECT_LE(z.real(), r.box.re_max);
    EXPECT_GE(z.imag(), r.box.im_min);
    EXPECT_LE(z.imag(), r.box.im_max);
    const double dev = std::abs(std::abs(tableau(name).stability(z)) - 1.0);
    worst = std::max(worst, dev);
    EXPECT_LE(dev, 1e-6) << name << " at " << z;
    if (has_prev) {
      EXPECT_LE(std::abs(z - prev), cell) << name << " row " << i;
    }
    prev = z;
    has_prev = true;
    ++points[name];
    min_re[name] = std::min(min_re.count(name) ? min_re[name] : 0.0, z.real());
  }
  EXPECT_LE(worst, 1e-6);
  for (const char* name : {"rk4", "heun", "kutta3", "sdirk3"}) EXPECT_GT(points[name], 100) << name;
  // One closed curve for each explicit method. sdirk3 has two: the boundary of its bounded
  // instability region in the right half-plane, and a small stable island around the real
  // zero of its R(z) inside it.
  EXPECT_EQ(breaks["rk4"], 0);
  EXPECT_EQ(breaks["heun"], 0);
  EXPECT_EQ(breaks["kutta3"], 0);
  EXPECT_EQ(breaks["sdirk3"], 1);
  // The leftmost boundary points are the real-axis limits (docs/reference-values.md).
  EXPECT_NEAR(min_re["rk4"], -2.7853, 1e-3);
  EXPECT_NEAR(min_re["kutta3"], -2.5127, 1e-3);
  EXPECT_NEAR(min_re["heun"], -2.0, 1e-3);
  EXPECT_GE(min_re["sdirk3"], -1e-6);  // A-stable: nothing unstable in the left half-plane

  const auto limits = read_csv(dir / "region_limits.csv");
  ASSERT_EQ(limits.size(), 5u);
  EXPECT_EQ(limits[0][0], "integrator");
  EXPECT_TRUE(std::filesystem::exists(dir / "region.md"));
  EXPECT_TRUE(std::filesystem::exists(dir / "region.json"));
  std::filesystem::remove_all(dir);
}

// The fitted box holds every bounded boundary of the chosen methods: for rk4 alone its region
// spans [−2.7853, ~0.1] × [−2.92, 2.92] (the rk4 boundary's highest point has Im ≈ 2.92, above
// the imaginary-axis crossing at 2√2); with sdirk3 the box reaches its instability region's
// rightmost point where R(x) = −1 on the positive real axis.
TEST(RegionExperiment, FittedBoxHoldsEveryBoundedBoundary) {
  RegionSpec spec;
  spec.integrators = {"rk4"};
  spec.resolution = 100;
  const RegionResult r = run_region(spec);
  EXPECT_TRUE(r.box_fitted);
  EXPECT_LT(r.box.re_min, -2.7853);
  EXPECT_GT(r.box.re_min, -4.0);  // not needlessly wide: 10% margin, rounded to 0.5
  EXPECT_GT(r.box.im_max, 2.92);
  EXPECT_EQ(r.box.im_min, -r.box.im_max);
  // Every polyline is closed inside the box (none was cut by it).
  for (const auto& line : method(r, "rk4").boundary)
    EXPECT_LT(std::abs(line.front() - line.back()), 0.1);

  // sdirk3's rightmost unstable point: R(x) = −1 for real x > 0, found by bisection on the
  // tableau's R between the pole 1/γ ≈ 2.29 (|R| → ∞) and 20 (|R| < 1, L-stable).
  const ButcherTableau& t = implicit_tableau("sdirk3");
  double lo = 3.0, hi = 20.0;  // |R(3)| > 1 > |R(20)|
  ASSERT_GT(std::abs(t.stability(lo)), 1.0);
  ASSERT_LT(std::abs(t.stability(hi)), 1.0);
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (std::abs(t.stability(mid)) > 1.0 ? lo : hi) = mid;
  }
  spec.integrators = {"rk4", "sdirk3"};
  const RegionResult both = run_region(spec);
  EXPECT_GT(both.box.re_max, lo);
  EXPECT_LT(both.box.re_max, 1.3 * lo + 0.5);
}

// Methods of mechanical systems only have no region in the z-plane: no rows in region.csv, and
// the oscillator limit hω < 2 of docs/reference-values.md (trace of the step matrix 2 − h²ω²).
TEST(RegionExperiment, MechanicalOnlyMethodsHaveOnlyTheOscillatorLimit) {
  RegionSpec spec;
  spec.integrators = {"velocity_verlet", "euler"};
  spec.box = RegionBox{-3, 1, -2, 2};
  spec.resolution = 50;
  const RegionResult r = run_region(spec);
  const auto& vv = method(r, "velocity_verlet");
  EXPECT_FALSE(vv.has_region);
  EXPECT_TRUE(vv.boundary.empty());
  EXPECT_FALSE(vv.real_axis.has_value());
  EXPECT_FALSE(vv.a_stable.has_value());
  EXPECT_NEAR(vv.oscillator.limit, 2.0, 1e-6);
  const Table t = region_table(r);
  for (const auto& row : t.rows) EXPECT_EQ(row[0], "euler");
  EXPECT_FALSE(t.rows.empty());
  const Table l = region_limits_table(r);
  EXPECT_EQ(l.rows[0][3], "");  // not applicable
  EXPECT_EQ(l.rows[0][6], "");
  EXPECT_NEAR(std::stod(l.rows[0][5]), 2.0, 1e-6);
}

// An IMEX pair has no region of its own: named, it is drawn as its two tables alone. Figures:
// imex_ssp2_222's explicit table is Heun's (R = 1 + z + z²/2: stable on [-2, 0], unstable near 0
// on the imaginary axis), its implicit one L-stable (R(∞) = 0, tests/experiments/test_analyze);
// ark436l2sa's explicit imaginary-axis limit 4.000729197218431 was found outside stiffbench
// (Python on the published rationals, test_analyze.cpp says how); its implicit table (esdirk43's)
// is A-stable.
TEST(RegionExperiment, ImexPairsAreDrawnAsTheirTwoTables) {
  RegionSpec spec;
  spec.integrators = {"imex_ssp2_222", "ark436l2sa"};
  spec.resolution = 40;
  const RegionResult r = run_region(spec);
  ASSERT_EQ(r.methods.size(), 4u);
  const auto& heun = method(r, "imex_ssp2_222:explicit");
  EXPECT_NEAR(heun.real_axis->limit, 2.0, 1e-12);
  EXPECT_EQ(heun.imaginary_axis->limit, 0.0);
  EXPECT_EQ(heun.family, "imex");
  EXPECT_TRUE(*method(r, "imex_ssp2_222:implicit").a_stable);
  EXPECT_NEAR(method(r, "ark436l2sa:explicit").imaginary_axis->limit, 4.000729197218431, 1e-12);
  EXPECT_TRUE(*method(r, "ark436l2sa:implicit").a_stable);
  EXPECT_FALSE(method(r, "ark436l2sa:explicit").boundary.empty());
}

// lie and strang have no R of one hλ (their parts need not commute); region draws their
// explicit sub-integrator (rk4 by default) over one step h: lie takes one rk4 step, so rk4's real
// and imaginary-axis limits (2.785293563405282 and 2.828427124746190 = 2√2, from R(z) = Σ z^k/k!,
// k ≤ 4); strang takes two half steps, R(z/2)², so exactly twice those limits.
TEST(RegionExperiment, SplittingsAreDrawnAsTheirExplicitSubIntegrator) {
  RegionSpec spec;
  spec.integrators = {"lie", "strang", "rk4"};
  spec.resolution = 40;
  const RegionResult r = run_region(spec);
  ASSERT_EQ(r.methods.size(), 3u);
  const auto& rk4 = method(r, "rk4");
  const auto& lie = method(r, "lie:explicit");
  const auto& strang = method(r, "strang:explicit");
  EXPECT_NEAR(rk4.imaginary_axis->limit, 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(lie.real_axis->limit, rk4.real_axis->limit, 1e-12);
  EXPECT_NEAR(lie.imaginary_axis->limit, 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(strang.real_axis->limit, 2.0 * rk4.real_axis->limit, 1e-11);
  EXPECT_NEAR(strang.imaginary_axis->limit, 4.0 * std::sqrt(2.0), 1e-11);
  EXPECT_EQ(lie.family, "splitting");  // drawn in the splitting schemes panel
  EXPECT_FALSE(strang.boundary.empty());
  // The report says what the NAME:explicit rows are.
  const auto dir = std::filesystem::temp_directory_path() /
                   (std::string("sb_region_split") + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  write_region_outputs(dir, spec, r);
  std::ifstream in(dir / "region.md");
  std::stringstream md;
  md << in.rdbuf();
  std::filesystem::remove_all(dir);
  EXPECT_NE(md.str().find("for lie and strang their explicit sub-integrator"), std::string::npos)
      << md.str();
}

// Methods with the same |R(z)| are reported as such (all two-stage second-order explicit RK
// methods have R = 1 + z + z²/2).
TEST(RegionExperiment, IdenticalStabilityFunctionsAreNamed) {
  RegionSpec spec;
  spec.integrators = {"heun", "midpoint", "rk4", "rk38", "kutta3"};
  spec.resolution = 20;
  const RegionResult r = run_region(spec);
  EXPECT_EQ(method(r, "heun").same_as, "");
  EXPECT_EQ(method(r, "midpoint").same_as, "heun");
  EXPECT_EQ(method(r, "rk38").same_as, "rk4");
  EXPECT_EQ(method(r, "kutta3").same_as, "");
}

// run_region refuses before computing anything (resolve_inputs names an unknown integrator).
void expect_bad_input(const RegionSpec& spec, const std::string& must_name) {
  try {
    run_region(spec);
    ADD_FAILURE() << "no BadInput; expected one naming " << must_name;
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find(must_name), std::string::npos) << e.what();
  }
}

TEST(RegionExperiment, RefusesIntegratorsWithoutStabilityDataAndBadBoxes) {
  RegionSpec spec;
  spec.integrators = {"rk4", "cvode_bdf"};
  expect_bad_input(spec, "'cvode_bdf' has no fixed stability region");
  spec.integrators = {"gsl_rk8pd"};
  expect_bad_input(spec, "gsl_rk8pd");
  spec.integrators = {"no_such_method"};
  expect_bad_input(spec, "no_such_method");
  spec.integrators = {"rk4", "rk4"};
  expect_bad_input(spec, "listed twice");
  spec.integrators = {"rk4"};
  spec.box = RegionBox{1, -1, -1, 1};
  expect_bad_input(spec, "--box");
  spec.box.reset();
  spec.resolution = 5;
  expect_bad_input(spec, "--resolution");

  const RegionBox b = parse_region_box("-6,3,-4.5,4.5");
  EXPECT_EQ(b.re_min, -6);
  EXPECT_EQ(b.re_max, 3);
  EXPECT_EQ(b.im_min, -4.5);
  EXPECT_EQ(b.im_max, 4.5);
  EXPECT_THROW(parse_region_box("-6,3,-4.5"), BadInput);
  EXPECT_THROW(parse_region_box("-6,3,x,4.5"), BadInput);
  EXPECT_THROW(parse_region_box("-6,3,-4.5,4.5,1"), BadInput);
}

// The default set: every registered integrator with stability data, none of the libraries.
TEST(RegionExperiment, DefaultIntegratorsAreThoseWithStabilityData) {
  const auto names = region_integrators();
  EXPECT_NE(std::find(names.begin(), names.end(), "rk4"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "bdf2"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "velocity_verlet"), names.end());
  EXPECT_EQ(std::find(names.begin(), names.end(), "cvode_bdf"), names.end());
  EXPECT_EQ(std::find(names.begin(), names.end(), "gsl_rk4"), names.end());
}

// A study's inputs from resolve_inputs: a method file (bs3's coefficients under another name), a
// variant of a built-in method and a user's integrator object; each row carries its label, and
// the file's method has bs3's region.
TEST(RegionExperiment, RunsFromResolvedInputsWithAMethodFileAVariantAndAnObject) {
  const std::string file = testing_support::renamed_method_file("bs3", "test_region_bs3");

  StudyTarget target;
  target.integrators = {file, "sdirk3{newton=full}", "bs3"};
  ButcherTableau heun = tableau("heun");
  heun.name = "test_region_heun_object";
  target.objects.integrators = {
      [heun] { return std::make_unique<ExplicitRungeKutta>(heun, "heun as an object"); }};
  RegionSpec spec;
  spec.resolution = 20;
  const RegionResult r = run_region(resolve_inputs(target), spec);
  std::vector<std::string> labels;
  for (const auto& m : r.methods) labels.push_back(m.integrator);
  EXPECT_EQ(labels, (std::vector<std::string>{"test_region_bs3", "sdirk3{newton=full}", "bs3",
                                              "test_region_heun_object"}));
  EXPECT_EQ(method(r, "test_region_bs3").same_as, "");
  EXPECT_EQ(method(r, "bs3").same_as, "test_region_bs3");
  EXPECT_EQ(method(r, "sdirk3{newton=full}").a_stable, std::optional<bool>(true));
  EXPECT_NEAR(method(r, "test_region_heun_object").real_axis->limit, 2.0, 1e-12);
  EXPECT_EQ(method(r, "test_region_heun_object").family, "explicit");
  EXPECT_EQ(method(r, "sdirk3{newton=full}").family, "implicit");
  std::filesystem::remove_all(std::filesystem::path(file).parent_path());
}

}  // namespace
}  // namespace stiffbench
