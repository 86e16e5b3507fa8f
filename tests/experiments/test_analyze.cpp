// `stiffbench analyze` (experiments/studies/analyze.hpp): the files it writes carry the figures
// of the method analysis (core/theory/method_analysis.hpp), checked here against independent
// computations — closed forms, published values, and exact rational arithmetic done outside
// stiffbench (Python's
// fractions module on the rooted trees, noted at each figure); methods without coefficients get
// a row instead of a failure; bad names are refused before anything runs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "cli/cli_main.hpp"
#include "experiments/build_info.hpp"
#include "experiments/commands/list_describe.hpp"
#include "experiments/framework/study.hpp"
#include "experiments/studies/analyze.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"

namespace fs = std::filesystem;
using namespace stiffbench;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A CSV as rows of named fields.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  std::vector<std::map<std::string, std::string>> of(const std::string& integrator) const {
    std::vector<std::map<std::string, std::string>> out;
    for (const auto& r : rows)
      if (r.at("integrator") == integrator) out.push_back(r);
    return out;
  }
  std::map<std::string, std::string> row(const std::string& integrator) const {
    const auto r = of(integrator);
    return r.empty() ? std::map<std::string, std::string>{} : r.front();
  }
};

// Fields of one CSV line; a quoted field (a tree "[t,[t]]", notes) may hold commas.
std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> f(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (ch == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') {
      f.back() += '"';
      ++i;
    } else if (ch == '"') {
      quoted = !quoted;
    } else if (ch == ',' && !quoted) {
      f.emplace_back();
    } else {
      f.back() += ch;
    }
  }
  return f;
}

Csv read_csv(const fs::path& p) {
  Csv c;
  std::stringstream ss(slurp(p));
  std::string line;
  std::getline(ss, line);
  c.header = split(line);
  while (std::getline(ss, line)) {
    if (line.empty()) continue;
    const auto f = split(line);
    std::map<std::string, std::string> r;
    for (std::size_t i = 0; i < c.header.size(); ++i) r[c.header[i]] = i < f.size() ? f[i] : "";
    c.rows.push_back(r);
  }
  return c;
}

double num(const std::map<std::string, std::string>& r, const std::string& column) {
  return std::stod(r.at(column));
}

fs::path fresh(const std::string& name) {
  // Per process: parallel test runs on one machine must not share the folder.
  const fs::path d =
      fs::temp_directory_path() / ("stiffbench_analyze_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

int cli(std::vector<std::string> args) {
  args.insert(args.begin(), "stiffbench");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return cli_main(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

// rk4, ssprk3 and dopri5 through the study pipeline (run_study, as the command runs them).
TEST(AnalyzeStudy, WritesTheAnalysisOfRk4Ssprk3Dopri5) {
  const fs::path dir = fresh("three");
  StudyTarget target;
  target.integrators = {"rk4", "ssprk3", "dopri5"};
  std::ostringstream out;
  StudyContext ctx;
  ctx.out = &out;
  const auto job = run_study("analyze", target, Params{}, dir, ctx);
  for (const char* f : {"analyze.csv", "analyze.md", "analyze.json", "analyze_conditions.csv",
                        "analyze_dispersion.csv"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;

  const Csv csv = read_csv(dir / "analyze.csv");
  ASSERT_EQ(csv.rows.size(), 3u);
  EXPECT_EQ(csv.header, analyze_table(AnalyzeResult{}).columns);
  const auto rk4 = csv.row("rk4"), ssprk3 = csv.row("ssprk3"), dopri5 = csv.row("dopri5");
  EXPECT_EQ(rk4.at("kind"), "explicit_rk");
  EXPECT_EQ(rk4.at("order"), "4");
  EXPECT_EQ(rk4.at("stage_order"), "1");  // explicit: C(1) only (c_i = row sums)
  EXPECT_EQ(dopri5.at("order"), "5");
  EXPECT_EQ(dopri5.at("embedded_order"), "4");
  EXPECT_EQ(dopri5.at("fsal"), "yes");  // last row of A = b (Dormand & Prince 1980)
  EXPECT_EQ(rk4.at("fsal"), "no");

  // rk4: R(x) = 1 on the negative axis at the real root of x³ + 4x² + 12x + 24 = 0, bisected in
  // 50-digit decimal arithmetic outside stiffbench: x = −2.78529356340528162...; on the
  // imaginary axis |R(iy)|² = 1 − y⁶/72 + y⁸/576, limit 2√2.
  EXPECT_NEAR(num(rk4, "real_axis_limit"), 2.785293563405282, 1e-12);
  EXPECT_NEAR(num(rk4, "imaginary_axis_limit"), 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(rk4.at("p_coefficients"),
            "1;1;0.5;" + format_full(1.0 / 6) + ";" + format_full(1.0 / 24));
  EXPECT_EQ(rk4.at("q_coefficients"), "1");
  EXPECT_EQ(rk4.at("a_stable"), "no");
  EXPECT_EQ(rk4.at("r_infinity"), "inf");  // polynomial R: |R(z)| → ∞
  // Error coefficients τ(t) = (bᵀΦ(t) − 1/γ(t))/σ(t) over the 9 trees of order 5, in exact
  // rational arithmetic (Python fractions, trees enumerated independently): ‖τ⁽⁵⁾‖₂ =
  // 0.014504582343198211 (the 1.45e-2 of the literature), max |τ⁽⁵⁾| = 1/120; of order 6:
  // ‖τ⁽⁶⁾‖₂ = 0.016035314699606992, max 1/144.
  EXPECT_NEAR(num(rk4, "error_norm_2"), 0.014504582343198211, 1e-14);
  EXPECT_NEAR(num(rk4, "error_norm_max"), 1.0 / 120, 1e-15);
  EXPECT_NEAR(num(rk4, "error_norm_2_next"), 0.016035314699606992, 1e-14);
  EXPECT_NEAR(num(rk4, "error_norm_max_next"), 1.0 / 144, 1e-15);
  EXPECT_NEAR(num(rk4, "residual_order_5"), 1.0 / 80, 1e-15);  // the same computation
  EXPECT_LT(num(rk4, "residual_order_4"), 1e-15);
  EXPECT_EQ(num(rk4, "max_coefficient"), 1.0);  // c_4 = a_43 = 1

  // ssprk3 (Shu & Osher 1988): SSP coefficient 1, the optimum of three-stage third-order
  // methods (Gottlieb & Shu 1998); ‖τ⁽⁴⁾‖₂ = 0.07216878364870322 and max 1/24 (fractions).
  EXPECT_NEAR(num(ssprk3, "ssp_coefficient"), 1.0, 1e-9);
  EXPECT_EQ(ssprk3.at("order"), "3");
  EXPECT_NEAR(num(ssprk3, "error_norm_2"), 0.07216878364870322, 1e-14);
  EXPECT_NEAR(num(ssprk3, "error_norm_max"), 1.0 / 24, 1e-15);
  // R = 1 + z + z²/2 + z³/6: |R(iy)|² = 1 − y⁴/12 + y⁶/36, imaginary limit √3.
  EXPECT_NEAR(num(ssprk3, "imaginary_axis_limit"), std::sqrt(3.0), 1e-12);

  // dopri5: ‖τ⁽⁶⁾‖₂ = 3.9908016093435990e-4 (fractions; Dormand & Prince 1980 publish
  // 3.99e-4), max |τ⁽⁶⁾| = 1/3600; R = Σ_{k≤5} z^k/k! + z⁶/600, imaginary limit 0.997189008633
  // (docs/commands/region.md: the first positive root of |P(iy)|² − 1).
  EXPECT_NEAR(num(dopri5, "error_norm_2"), 3.990801609343599e-4, 1e-16);
  EXPECT_NEAR(num(dopri5, "error_norm_max"), 1.0 / 3600, 1e-17);
  EXPECT_NEAR(num(dopri5, "imaginary_axis_limit"), 0.997189008633, 1e-11);
  EXPECT_NEAR(num(dopri5, "real_axis_limit"), 3.3065678926, 1e-9);
  EXPECT_EQ(dopri5.at("ssp_coefficient"), "0");  // a negative coefficient (a_42 = −56/15)

  // Conditions: one row per rooted tree up to order 8 (1 + 1 + 2 + 4 + 9 + 20 + 48 + 115).
  const Csv cond = read_csv(dir / "analyze_conditions.csv");
  EXPECT_EQ(cond.header, (std::vector<std::string>{"integrator", "order", "tree", "residual",
                                                   "error_coefficient", "set"}));
  ASSERT_EQ(cond.of("rk4").size(), 200u);
  double worst5 = 0;
  for (const auto& r : cond.of("rk4"))
    if (r.at("order") == "5") worst5 = std::max(worst5, std::abs(num(r, "residual")));
  EXPECT_NEAR(worst5, 1.0 / 80, 1e-15);

  // Dispersion: 121 points per method on [1e-2, 10]; rk4's |R(iν)| recomputed here from the
  // Taylor polynomial (std::complex), its phase error against arg R(iν) − ν (unwrapped: small
  // below ν = 2, where arg R stays within (−π, π)).
  const Csv disp = read_csv(dir / "analyze_dispersion.csv");
  const auto curve = disp.of("rk4");
  ASSERT_EQ(curve.size(), 121u);
  EXPECT_NEAR(num(curve.front(), "nu"), 1e-2, 1e-15);
  EXPECT_NEAR(num(curve.back(), "nu"), 10.0, 1e-12);
  for (const auto& r : curve) {
    const double nu = num(r, "nu");
    const std::complex<double> z(0, nu);
    const std::complex<double> R = 1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0;
    EXPECT_NEAR(num(r, "amplification"), std::abs(R), 1e-12 * std::abs(R)) << nu;
    if (nu < 2) {
      EXPECT_NEAR(num(r, "phase_error"), std::arg(R) - nu, 1e-12) << nu;
    }
  }
  // The terminal summary names every method with its order (no W-order: not a Rosenbrock
  // method) and limits.
  EXPECT_NE(out.str().find("| rk4 | explicit_rk | 4 | - | 1 |"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("2.785293563405282"), std::string::npos) << out.str();
  // ssprk3's SSP coefficient 1 (Shu & Osher 1988) comes from a bisection: printed with its
  // relative tolerance, which the CSV gives in its own column (none for rk4's exact 0).
  EXPECT_NE(out.str().find("| 1 (bisection, relative +-1e-12) |"), std::string::npos) << out.str();
  EXPECT_EQ(ssprk3.at("ssp_relative_tolerance"), "1e-12");
  EXPECT_EQ(rk4.at("ssp_relative_tolerance"), "");
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(dir / "analyze.png"));
  }
  fs::remove_all(dir);
}

// BDF2 is not defined by a tableau: a row saying so, with what its stability data give (A-stable,
// Dahlquist's second barrier: the A-stable linear multistep method of order 2), and a library
// reference one with nothing but the reason.
TEST(AnalyzeStudy, MethodsWithoutCoefficientsGetARow) {
  AnalyzeSpec spec;
  spec.integrators = {"bdf2", "cvode_bdf", "heun"};
  const AnalyzeResult r = run_analyze(spec);
  const Table t = analyze_table(r);
  ASSERT_EQ(t.rows.size(), 3u);
  std::map<std::string, std::string> bdf2, cvode;
  for (std::size_t i = 0; i < t.columns.size(); ++i) {
    bdf2[t.columns[i]] = t.rows[0][i];
    cvode[t.columns[i]] = t.rows[1][i];
  }
  EXPECT_EQ(bdf2.at("kind"), "not coefficient-defined");
  EXPECT_EQ(bdf2.at("claimed_order"), "2");
  EXPECT_EQ(bdf2.at("order"), "");
  EXPECT_EQ(bdf2.at("a_stable"), "yes");
  EXPECT_EQ(bdf2.at("real_axis_limit"), "unbounded");
  EXPECT_NE(bdf2.at("notes").find("linear multistep"), std::string::npos) << bdf2.at("notes");
  EXPECT_EQ(cvode.at("kind"), "not coefficient-defined");
  EXPECT_EQ(cvode.at("a_stable"), "");
  EXPECT_NE(cvode.at("notes").find("library"), std::string::npos) << cvode.at("notes");
  EXPECT_EQ(t.rows[2][1], "explicit_rk");  // heun is analysed as usual
  // Neither has a curve; heun's is there.
  const Table d = analyze_dispersion_table(r);
  ASSERT_FALSE(d.rows.empty());
  for (const auto& row : d.rows) EXPECT_EQ(row[0], "heun");
}

// `analyze ros3p,rodas4,esdirk43`: the summary prints the W-order of the Rosenbrock methods and
// the embedded formula's |R(∞)| and A-/L-stability beside the main formula's. Checked against
// independent computations: ros3p's W-order 1 by hand (bᵀα1 = (2/3)·0 + (1/3)·1 = 1/3, not the
// 1/2 of the W-condition of [t]); the embedded |R̂(∞)| of rodas4 as |1 − b̂ᵀ(α + Γ)⁻¹1| and of
// esdirk43 as |R̂(−1e9)|, R̂(z) = 1 + z b̂ᵀ(I − zM)⁻¹1 evaluated with Eigen (Hairer & Wanner II,
// IV.7); the esdirk43 row of a method without W-order shows "-".
TEST(AnalyzeStudy, WOrderAndEmbeddedStabilityInTheSummary) {
  const fs::path dir = fresh("worder");
  StudyTarget target;
  target.integrators = {"ros3p", "rodas4", "esdirk43"};
  std::ostringstream out;
  StudyContext ctx;
  ctx.out = &out;
  run_study("analyze", target, Params{}, dir, ctx);
  const std::string text = out.str();
  EXPECT_NE(text.find("| W-order |"), std::string::npos) << text;
  EXPECT_NE(text.find("| embedded abs R(inf) | embedded A/L-stable |"), std::string::npos) << text;
  const Csv csv = read_csv(dir / "analyze.csv");
  const auto ros3p = csv.row("ros3p"), rodas4 = csv.row("rodas4"), esdirk = csv.row("esdirk43");
  EXPECT_EQ(ros3p.at("order"), "3");
  EXPECT_EQ(ros3p.at("w_order"), "1");
  EXPECT_EQ(esdirk.at("w_order"), "");
  EXPECT_NE(text.find("| ros3p | rosenbrock | 3 | 1 |"), std::string::npos) << text;

  using cd = std::complex<double>;
  const auto r_hat = [](const Mat& m, const Vec& w, cd z) {
    const Eigen::Index s = w.size();
    const Eigen::MatrixXcd lhs = Eigen::MatrixXcd::Identity(s, s) - z * m.cast<cd>();
    const Eigen::VectorXcd k = lhs.partialPivLu().solve(Eigen::VectorXcd::Ones(s));
    return 1.0 + z * w.cast<cd>().dot(k);
  };
  {
    const auto integ = integrator_registry().create("rodas4", Params{});
    const RosenbrockTableau& r = *integ->rosenbrock_tableau();
    const Mat m = r.alpha + r.gamma_full();
    const double r_inf =
        std::abs(1.0 - r.b_embedded.dot(m.fullPivLu().solve(Vec::Ones(r.stages()))));
    EXPECT_NEAR(num(rodas4, "embedded_r_infinity"), r_inf, 1e-12);
    EXPECT_NE(text.find("| " + format_full(num(rodas4, "embedded_r_infinity")) + " |"),
              std::string::npos)
        << text;
  }
  {
    const auto integ = integrator_registry().create("esdirk43", Params{});
    const ButcherTableau& t = *integ->butcher_tableau();
    EXPECT_NEAR(num(esdirk, "embedded_r_infinity"), std::abs(r_hat(t.a, t.b_embedded, cd(-1e9, 0))),
                1e-7);
    // The main formula: stiffly accurate and L-stable (Kennedy & Carpenter 2003), R(∞) = 0.
    EXPECT_EQ(esdirk.at("r_infinity"), "0");
    for (const char* c : {"embedded_a_stable", "embedded_l_stable"})
      EXPECT_TRUE(esdirk.at(c) == "yes" || esdirk.at(c) == "no") << c;
  }
  // The conditions file carries the W-conditions, marked as such.
  const Csv cond = read_csv(dir / "analyze_conditions.csv");
  bool w_tree = false;
  for (const auto& row : cond.rows)
    if (row.at("integrator") == "ros3p" && row.at("set") == "W" && row.at("tree") == "[t]") {
      w_tree = true;
      EXPECT_NEAR(std::stod(row.at("residual")), 1.0 / 3 - 0.5, 1e-15);
    }
  EXPECT_TRUE(w_tree);
  fs::remove_all(dir);
}

// Rosenbrock and kick/drift methods are read through their own coefficients: rodas4 (Hairer &
// Wanner II, §IV.7: order 4, embedded 3, stiffly accurate, so R(∞) = 0 and L-stable) and
// velocity Verlet (order 2; on x'' = −ω²x its step map has half-trace 1 − (hω)²/2, stable while
// |1 − (hω)²/2| <= 1, i.e. hω <= 2).
TEST(AnalyzeStudy, RosenbrockAndSplittingRows) {
  AnalyzeSpec spec;
  spec.integrators = {"rodas4", "velocity_verlet"};
  const Table t = analyze_table(run_analyze(spec));
  ASSERT_EQ(t.rows.size(), 2u);
  std::map<std::string, std::string> ros, vv;
  for (std::size_t i = 0; i < t.columns.size(); ++i) {
    ros[t.columns[i]] = t.rows[0][i];
    vv[t.columns[i]] = t.rows[1][i];
  }
  EXPECT_EQ(ros.at("kind"), "rosenbrock");
  EXPECT_EQ(ros.at("order"), "4");
  EXPECT_EQ(ros.at("embedded_order"), "3");
  EXPECT_EQ(ros.at("stage_order"), "");  // not defined for Rosenbrock methods
  EXPECT_EQ(ros.at("r_infinity"), "0");
  EXPECT_EQ(ros.at("l_stable"), "yes");
  EXPECT_EQ(vv.at("kind"), "splitting");
  EXPECT_EQ(vv.at("order"), "2");
  EXPECT_NEAR(std::stod(vv.at("oscillator_limit")), 2.0, 1e-12);
  EXPECT_EQ(vv.at("p_coefficients"), "");  // no scalar R(z)
}

// IMEX pairs (kind imex_ark): the pair's order from the additive order conditions, then each
// table alone. Figures:
//   - ark436l2sa, ARK4(3)6L[2]SA of Kennedy & Carpenter (2003): order 4, embedded order 3,
//     stiffly accurate (published). Its implicit table is esdirk43's, so that row must repeat
//     esdirk43's own analysis. The explicit table's imaginary-axis limit 4.000729197218431 was
//     found outside stiffbench (Python, the published rationals, R(iy) stage by stage and a
//     bisection on |R(iy)| <= 1); here R(iy) = 1 + z bᵀ(I − zA)⁻¹1 is also solved directly on
//     both sides of the reported limit (not through R's polynomial, which the analysis uses).
//   - imex_ssp2_222 (Pareschi & Russo 2005): its explicit table is Heun's, R = 1 + z + z²/2:
//     stable on [−2, 0], |R(iy)|² = 1 + y⁴/4 > 1 for y ≠ 0 (imaginary limit 0), SSP
//     coefficient 1. Its implicit table [[γ, 0], [1 − 2γ, γ]], b = (1/2, 1/2), γ = 1 − 1/√2 has
//     R(∞) = 1 − bᵀA⁻¹1 = 1 − (4γ − 1)/(2γ²) = 0, as 2γ² − 4γ + 1 = 0.
TEST(AnalyzeStudy, ImexPairsGetTheirOrderAndEachTableAlone) {
  AnalyzeSpec spec;
  spec.integrators = {"ark436l2sa", "imex_ssp2_222", "esdirk43"};
  const AnalyzeResult r = run_analyze(spec);
  const Table t = analyze_table(r);
  ASSERT_EQ(t.rows.size(), 7u);
  std::map<std::string, std::map<std::string, std::string>> row;
  for (const auto& v : t.rows)
    for (std::size_t i = 0; i < t.columns.size(); ++i) row[v[0]][t.columns[i]] = v[i];
  EXPECT_EQ(t.rows[1][0], "ark436l2sa:explicit");  // the tables right after their pair
  EXPECT_EQ(t.rows[2][0], "ark436l2sa:implicit");

  const auto& ark = row.at("ark436l2sa");
  EXPECT_EQ(ark.at("kind"), "imex_ark");
  EXPECT_EQ(ark.at("order"), "4");
  EXPECT_EQ(ark.at("embedded_order"), "3");
  EXPECT_EQ(ark.at("stiffly_accurate"), "yes");
  EXPECT_EQ(ark.at("error_norm_2"), "");      // no error coefficients for the coloured trees
  EXPECT_EQ(ark.at("p_coefficients"), "");    // no stability function of its own
  EXPECT_EQ(ark.at("residual_order_7"), "");  // conditions to order 6
  const auto& ex = row.at("ark436l2sa:explicit");
  EXPECT_EQ(ex.at("kind"), "explicit_rk");
  EXPECT_EQ(ex.at("order"), "4");
  const double limit = num(ex, "imaginary_axis_limit");
  EXPECT_NEAR(limit, 4.000729197218431, 1e-12);
  const auto integ = integrator_registry().create("ark436l2sa", Params{});
  const ButcherTableau& e = integ->additive_tableau()->explicit_table;
  auto abs_r = [&](double y) {
    const Eigen::Index s = e.a.rows();
    const std::complex<double> z(0.0, y);
    const Eigen::MatrixXcd m =
        Eigen::MatrixXcd::Identity(s, s) - z * e.a.cast<std::complex<double>>();
    const Eigen::VectorXcd k = m.partialPivLu().solve(Eigen::VectorXcd::Ones(s));
    return std::abs(1.0 + z * e.b.cast<std::complex<double>>().dot(k));
  };
  EXPECT_LE(abs_r(limit * (1 - 1e-6)), 1.0);
  EXPECT_GT(abs_r(limit * (1 + 1e-6)), 1.0);
  const auto& im = row.at("ark436l2sa:implicit");
  const auto& esdirk = row.at("esdirk43");
  for (const char* c :
       {"kind", "order", "stage_order", "error_norm_2", "q_coefficients", "r_infinity", "l_stable"})
    EXPECT_EQ(im.at(c), esdirk.at(c)) << c;

  const auto& heun = row.at("imex_ssp2_222:explicit");
  EXPECT_NEAR(num(heun, "real_axis_limit"), 2.0, 1e-12);
  EXPECT_EQ(num(heun, "imaginary_axis_limit"), 0.0);
  EXPECT_NEAR(num(heun, "ssp_coefficient"), 1.0, 1e-10);
  const auto& sdirk = row.at("imex_ssp2_222:implicit");
  EXPECT_NEAR(num(sdirk, "r_infinity"), 0.0, 1e-12);
  EXPECT_EQ(sdirk.at("l_stable"), "yes");
  EXPECT_EQ(row.at("imex_ssp2_222").at("order"), "2");

  // The conditions file names the coupling conditions and gives them no error coefficient.
  bool coupling = false;
  for (const auto& c : analyze_conditions_table(r).rows)
    if (c[0] == "ark436l2sa") {
      EXPECT_EQ(c[4], "") << c[2];
      coupling = coupling ||
                 (c[2].find("AI") != std::string::npos && c[2].find("bE") != std::string::npos);
    }
  EXPECT_TRUE(coupling);
  // Convergence tables show the analysed order beside the claimed one for IMEX pairs too.
  ASSERT_TRUE(coefficient_analysis(*integ).has_value());
  EXPECT_EQ(coefficient_analysis(*integ)->order, 4);
}

// A pair whose tables are each of order 2 but do not couple: explicit Heun (c = 0, 1) and the
// implicit table [[0, 0], [0, 1/2]], b = (0, 1) (c = 0, 1/2; order 2 alone: Σb = 1, bᵀc = 1/2).
// The coupling conditions of order 2 (by hand): bE·AI·1 = 1/2 has residual
// (1/2)(0) + (1/2)(1/2) − 1/2 = −1/4, and bI·AE·1 = 1/2 has residual 0·0 + 1·1 − 1/2 = 1/2; so
// the pair has order 1 and its largest residual of order 2 is 1/2.
TEST(AnalyzeStudy, AnImexPairThatDoesNotCoupleHasTheLowerOrder) {
  AdditiveTableau t;
  t.name = "uncoupled";
  t.order = 2;
  t.explicit_table.a = Mat{{0.0, 0.0}, {1.0, 0.0}};
  t.explicit_table.b = Vec{{0.5, 0.5}};
  t.explicit_table.c = Vec{{0.0, 1.0}};
  t.implicit_table.a = Mat{{0.0, 0.0}, {0.0, 0.5}};
  t.implicit_table.b = Vec{{0.0, 1.0}};
  t.implicit_table.c = Vec{{0.0, 0.5}};
  EXPECT_EQ(analyze_runge_kutta(t.explicit_table, "explicit_rk").order, 2);
  EXPECT_EQ(analyze_runge_kutta(t.implicit_table, "dirk").order, 2);
  const MethodAnalysis m = analyze_additive(t);
  EXPECT_EQ(m.kind, "imex_ark");
  EXPECT_EQ(m.order, 1);
  ASSERT_GE(m.residual_by_order.size(), 2u);
  EXPECT_NEAR(m.residual_by_order[1], 0.5, 1e-15);
}

// The default set: every integrator with coefficients or stability data, without the library
// references.
TEST(AnalyzeStudy, DefaultSetHasTheCoefficientMethods) {
  const auto names = analyze_integrators();
  auto has = [&](const std::string& n) {
    return std::find(names.begin(), names.end(), n) != names.end();
  };
  EXPECT_TRUE(has("rk4"));
  EXPECT_TRUE(has("radau5"));
  EXPECT_TRUE(has("bdf2"));
  EXPECT_TRUE(has("ark324l2sa"));  // IMEX pairs: their tables (kind imex_ark)
  EXPECT_FALSE(has("cvode_bdf"));
}

// The command line: positional names (comma- or space-separated) and --integrators together;
// an unknown name is bad input (exit 2) and nothing is written.
TEST(AnalyzeStudy, CommandLineNamesAndRefusals) {
  const fs::path dir = fresh("cli");
  ASSERT_EQ(cli({"analyze", "rk4,heun", "kutta3", "--integrators", "sdirk3", "--out", dir.string(),
                 "--nu-points", "11"}),
            0);
  const Csv csv = read_csv(dir / "analyze.csv");
  ASSERT_EQ(csv.rows.size(), 4u);
  EXPECT_EQ(csv.rows[0].at("integrator"), "sdirk3");  // --integrators first, then positional
  EXPECT_EQ(csv.rows[1].at("integrator"), "rk4");
  EXPECT_EQ(csv.rows[3].at("integrator"), "kutta3");
  // sdirk3 (Alexander 1977): L-stable, |R(∞)| = 0 and stiffly accurate.
  EXPECT_EQ(csv.rows[0].at("kind"), "dirk");
  EXPECT_EQ(csv.rows[0].at("l_stable"), "yes");
  EXPECT_EQ(csv.rows[0].at("stiffly_accurate"), "yes");
  EXPECT_EQ(read_csv(dir / "analyze_dispersion.csv").of("heun").size(), 11u);

  const fs::path bad = fresh("bad");
  EXPECT_EQ(cli({"analyze", "rk4,rk5x", "--out", bad.string()}), 2);
  EXPECT_FALSE(fs::exists(bad / "analyze.csv"));
  EXPECT_EQ(cli({"analyze", "rk4", "rk4", "--out", bad.string()}), 2);  // listed twice
  EXPECT_EQ(cli({"analyze", "rk4", "--nu-points", "1", "--out", bad.string()}), 2);
  EXPECT_EQ(cli({"analyze", "rk4", "--param", "newton_tol=1e-3", "--out", bad.string()}), 2);
  fs::remove_all(dir);
  fs::remove_all(bad);
}

// The report's region section comes with the analysis: the built-in suite holds an analyze
// section just before the regions.
TEST(AnalyzeStudy, ReportSuiteHasTheAnalysisBesideTheRegions) {
  const auto sections = load_report_suite({}, true);
  std::size_t analysis = sections.size(), regions = sections.size();
  for (std::size_t i = 0; i < sections.size(); ++i) {
    if (sections[i].spec.kind == "analyze") analysis = i;
    if (sections[i].spec.kind == "region") regions = i;
  }
  ASSERT_LT(analysis, sections.size());
  ASSERT_LT(regions, sections.size());
  EXPECT_EQ(analysis + 1, regions);
  EXPECT_EQ(sections[analysis].name, "method_analysis");
}

// A study's inputs from resolve_inputs: a method file (sdirk3's coefficients under another name),
// a variant of a built-in method and a user's integrator object, through the pipeline
// (analyze_study); each row of analyze.csv carries its label, and the file's method has sdirk3's
// figures.
TEST(AnalyzeStudy, RunsFromResolvedInputsWithAMethodFileAVariantAndAnObject) {
  const fs::path dir = fresh("inputs");
  fs::create_directories(dir / "methods");
  std::string toml = slurp(fs::path(STIFFBENCH_SOURCE_DIR) / "methods" / "sdirk3.toml");
  const std::string key = "name = \"sdirk3\"";
  ASSERT_NE(toml.find(key), std::string::npos);
  toml.replace(toml.find(key), key.size(), "name = \"test_analyze_sdirk3\"");
  const fs::path file = dir / "methods" / "test_analyze_sdirk3.toml";
  std::ofstream(file) << toml;

  StudyTarget target;
  target.integrators = {file.string(), "dopri5{rtol=1e-8}"};
  ButcherTableau heun = explicit_tableaux().front();
  for (const auto& t : explicit_tableaux())
    if (t.name == "heun") heun = t;
  heun.name = "test_analyze_heun_object";
  target.objects.integrators = {
      [heun] { return std::make_unique<ExplicitRungeKutta>(heun, "heun as an object"); }};
  AnalyzeSpec spec;
  spec.points = 11;
  const AnalyzeResult r = analyze_study(resolve_inputs(target), spec, dir / "out");
  ASSERT_EQ(r.methods.size(), 3u);
  const Csv csv = read_csv(dir / "out" / "analyze.csv");
  ASSERT_EQ(csv.rows.size(), 3u);
  EXPECT_EQ(csv.rows[0].at("integrator"), "test_analyze_sdirk3");
  EXPECT_EQ(csv.rows[1].at("integrator"), "dopri5{rtol=1e-8}");
  EXPECT_EQ(csv.rows[2].at("integrator"), "test_analyze_heun_object");
  EXPECT_EQ(csv.rows[0].at("kind"), "dirk");
  EXPECT_EQ(csv.rows[0].at("order"), "3");
  EXPECT_EQ(csv.rows[0].at("l_stable"), "yes");
  EXPECT_EQ(csv.rows[1].at("order"), "5");
  EXPECT_EQ(csv.rows[2].at("order"), "2");
  EXPECT_EQ(read_csv(dir / "out" / "analyze_dispersion.csv").of("test_analyze_heun_object").size(),
            11u);
  const std::string json = slurp(dir / "out" / "analyze.json");
  EXPECT_NE(json.find("test_analyze_sdirk3.toml"), std::string::npos);  // the file recorded
  fs::remove_all(dir);
}
