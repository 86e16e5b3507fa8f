// Method files (integrators/method_file.hpp) and their coefficient expressions
// (integrators/coefficient_expr.hpp): parsing, the checks a bad file meets (each naming the
// file and the line), and the integrators they build.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/driver.hpp"
#include "core/types.hpp"
#include "integrators/coefficient_expr.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/rosenbrock.hpp"
#include "integrators/method_file.hpp"
#include "integrators/method_kinds.hpp"
#include "integrators/symplectic/composition.hpp"
#include "tests/test_support.hpp"

namespace stiffbench {
namespace {

// The message of the BadInput `f` throws ("" when it throws none).
template <class F>
std::string bad_input(F f) {
  try {
    f();
  } catch (const BadInput& e) {
    return e.what();
  }
  return "";
}

// ---- Expressions ------------------------------------------------------------------------------

// The evaluator performs the same long double operations as these expressions, in the same
// order, so the results are equal bit for bit.
TEST(CoefficientExpr, EvaluatesInLongDouble) {
  EXPECT_EQ(evaluate_coefficient("(3 - sqrt(3))/6"), (3.0L - std::sqrt(3.0L)) / 6.0L);
  EXPECT_EQ(evaluate_coefficient("1/3"), 1.0L / 3.0L);
  EXPECT_EQ(evaluate_coefficient("1 - 1/sqrt(2)"), 1.0L - 1.0L / std::sqrt(2.0L));
  EXPECT_EQ(evaluate_coefficient(" 2.5e-1 * 4 "), 1.0L);
  EXPECT_EQ(evaluate_coefficient("-2^2"), -4.0L);    // ^ binds tighter than unary minus
  EXPECT_EQ(evaluate_coefficient("2^3^2"), 512.0L);  // right associative: 2^9
  EXPECT_EQ(evaluate_coefficient("2^-2"), 0.25L);
  EXPECT_EQ(evaluate_coefficient("1 - 2 - 3"), -4.0L);  // left associative
  EXPECT_EQ(evaluate_coefficient("cbrt(2)"), std::cbrt(2.0L));
  // A long double third differs from the double one in its extra bits (64-bit significand on
  // x86), and rounds to the correctly rounded double.
  EXPECT_EQ(static_cast<double>(evaluate_coefficient("1/3")), 1.0 / 3.0);
  const CoefficientConstants k{{"g", 0.25L}, {"w", 2.0L}};
  EXPECT_EQ(evaluate_coefficient("w*g + 1/w", k), 1.0L);
}

TEST(CoefficientExpr, BadExpressionsNameTheExpressionAndPosition) {
  const std::string open = bad_input([] { evaluate_coefficient("(1 + 2"); });
  EXPECT_NE(open.find("\"(1 + 2\""), std::string::npos) << open;
  EXPECT_NE(open.find("position 7"), std::string::npos) << open;
  EXPECT_NE(open.find("expected ')'"), std::string::npos) << open;
  const std::string unknown = bad_input([] { evaluate_coefficient("1/sqr(2)"); });
  EXPECT_NE(unknown.find("unknown name 'sqr'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("position 3"), std::string::npos) << unknown;
  EXPECT_NE(bad_input([] { evaluate_coefficient("1/(2-2)"); }).find("division by zero"),
            std::string::npos);
  EXPECT_NE(bad_input([] { evaluate_coefficient("sqrt(-1)"); }).find("negative"),
            std::string::npos);
  EXPECT_NE(bad_input([] { evaluate_coefficient("2^0.5"); }).find("integer"), std::string::npos);
  EXPECT_NE(bad_input([] { evaluate_coefficient("1 2"); }).find("unexpected '2'"),
            std::string::npos);
  EXPECT_NE(bad_input([] { evaluate_coefficient(""); }).find("empty"), std::string::npos);
}

// ---- Files -------------------------------------------------------------------------------------

const char* kHeun3 = R"toml(name = "heun3"
kind = "explicit_rk"
order = 3
description = "Heun's third-order method"
reference = "K. Heun, Z. Math. Phys. 45 (1900) 23-38"
A = [[0, 0, 0], ["1/3", 0, 0], [0, "2/3", 0]]
b = ["1/4", 0, "3/4"]
c = [0, "1/3", "2/3"]
)toml";

// `s` with the first `from` replaced by `to`.
std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const std::size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

std::string with_order(int order) {
  return replaced(kHeun3, "order = 3", "order = " + std::to_string(order));
}

TEST(MethodFile, Heun3Parses) {
  const MethodDefinition m = parse_method_file(kHeun3, "heun3.toml");
  EXPECT_EQ(m.name, "heun3");
  EXPECT_EQ(m.kind, MethodKind::explicit_rk);
  EXPECT_EQ(m.order, 3);
  EXPECT_EQ(m.class_text, "explicit RK");
  EXPECT_FALSE(m.adaptive());
  EXPECT_EQ(m.tableau.a(1, 0), 1.0 / 3.0);
  EXPECT_EQ(m.tableau.a(2, 1), 2.0 / 3.0);
  EXPECT_EQ(m.tableau.b[0], 0.25);
  EXPECT_EQ(m.tableau.b[2], 0.75);
  EXPECT_EQ(m.tableau.c[2], 2.0 / 3.0);
  // The order conditions of order 3 hold (bᵀ1 = 1, bᵀc = 1/2, bᵀc² = 1/3, bᵀAc = 1/6 by hand:
  // 3/4·(2/3)² = 1/3, 3/4·2/3·1/3 = 1/6); of order 4 the worst is bᵀA²c = 0 against 1/24
  // (A²c = 0: the only nonzero entry of Ac is the third, and A's third column is 0).
  EXPECT_LE(m.tableau.order_defect(3), 1e-15);
  EXPECT_NEAR(m.tableau.order_defect(4), 1.0 / 24.0, 1e-15);
}

// Global error at t = 2 on Prothero–Robinson with λ = -1 (smooth, non-stiff; exact y = φ(t)),
// h = 0.1 and 0.05: a third-order method divides the error by 2³.
TEST(MethodFile, Heun3ReachesOrderThree) {
  const MethodDefinition m = parse_method_file(kHeun3, "heun3.toml");
  double err[2];
  for (int k = 0; k < 2; ++k) {
    auto sys = testing_support::model("prothero_robinson", {"lambda=-1"});
    auto integ = make_integrator(m);
    FixedStepOptions opt;
    opt.t_end = 2.0;
    opt.h = 0.1 / (1 << k);
    const RunResult r = run_fixed_step(*sys, *integ, opt);
    ASSERT_EQ(r.stats.status, Status::ok);
    Vec exact(sys->dimension());
    sys->exact(r.t, exact);
    err[k] = (r.y - exact).cwiseAbs().maxCoeff();
  }
  EXPECT_NEAR(std::log2(err[0] / err[1]), 3.0, 0.1) << err[0] << " " << err[1];
}

// The two-stage SDIRK of Alexander (γ = 1 - 1/√2) written with expressions gives the built-in
// sdirk2's coefficients (computed in double there) to one ulp.
TEST(MethodFile, Sdirk2MatchesTheBuiltInToOneUlp) {
  const char* text = R"toml(name = "my_sdirk2"
kind = "dirk"
order = 2
description = "two-stage SDIRK"
[constants]
g = "1 - 1/sqrt(2)"
)toml";
  // Keys after a table header belong to it: the coefficients go before [constants] in a real
  // file; here they are added at the top.
  const std::string file =
      std::string("A = [[\"g\", 0], [\"1 - g\", \"g\"]]\nb = [\"1 - g\", \"g\"]\n") + text;
  const MethodDefinition m = parse_method_file(file, "sdirk2.toml");
  const ButcherTableau& ref = implicit_tableau("sdirk2");
  ASSERT_EQ(m.tableau.stages(), 2);
  for (Index i = 0; i < 2; ++i) {
    for (Index j = 0; j < 2; ++j)
      EXPECT_LE(std::abs(m.tableau.a(i, j) - ref.a(i, j)),
                std::nextafter(std::abs(ref.a(i, j)), 1e300) - std::abs(ref.a(i, j)))
          << i << j;
    EXPECT_LE(std::abs(m.tableau.b[i] - ref.b[i]),
              std::nextafter(std::abs(ref.b[i]), 1e300) - std::abs(ref.b[i]));
    EXPECT_LE(std::abs(m.tableau.c[i] - ref.c[i]),
              std::nextafter(std::abs(ref.c[i]), 1e300) - std::abs(ref.c[i]));
  }
  EXPECT_EQ(m.class_text, "SDIRK");
  // The same parameters as the registered sdirk2 (Newton and linear solver).
  std::vector<std::string> mine, theirs;
  for (const ParamSpec& s : method_param_specs(m)) mine.push_back(s.key);
  for (const ParamSpec& s : integrator_registry().at("sdirk2").params) theirs.push_back(s.key);
  EXPECT_EQ(mine, theirs);
  const IntegratorRegistry::Entry e = method_registry_entry(m);
  EXPECT_EQ(e.info.name, "my_sdirk2");
  EXPECT_EQ(e.info.kind, "SDIRK");
  EXPECT_EQ(e.info.order, 2);
  EXPECT_EQ(e.info.family, Family::implicit);
  EXPECT_NE(e.make(resolve_params(e.params, Params::from_assignments({"linear_solver=cg"}), nullptr,
                                  "t")),
            nullptr);
}

// A file that defines its constants first: by TOML's rule every key after the [constants] header
// lands in that table; the format takes the file's top-level keys found there as what they are
// (a constant cannot take their names). The tableau is the same, bit for bit, as the one of the
// file with [constants] last, and messages still name the key's own line.
TEST(MethodFile, ConstantsFirstFileLoads) {
  const std::string keys = R"toml(name = "my_sdirk2"
kind = "dirk"
order = 2
description = "two-stage SDIRK"
A = [["g", 0], ["1 - g", "g"]]
b = ["1 - g", "g"]
)toml";
  const std::string constants = "[constants]\ng = \"1 - 1/sqrt(2)\"\n";
  const MethodDefinition first = parse_method_file(constants + keys, "first.toml");
  const MethodDefinition last = parse_method_file(keys + constants, "last.toml");
  EXPECT_EQ(first.name, "my_sdirk2");
  EXPECT_EQ(first.kind, MethodKind::dirk);
  EXPECT_EQ(first.order, 2);
  EXPECT_EQ(first.tableau.a, last.tableau.a);
  EXPECT_EQ(first.tableau.b, last.tableau.b);
  // g = 1 − 1/√2 (Alexander's SDIRK2): a_11 = g, b = (1 − g, g).
  EXPECT_NEAR(first.tableau.a(0, 0), 1.0 - 1.0 / std::sqrt(2.0), 1e-15);
  // `order` is on line 5 of the constants-first file; order 3 is refused there.
  const std::string msg = bad_input([&] {
    parse_method_file(constants + replaced(keys, "order = 2", "order = 3"), "first.toml");
  });
  EXPECT_NE(msg.find("first.toml:5: key 'order'"), std::string::npos) << msg;
}

// A key inside a table where it cannot belong names the table and says what to move.
TEST(MethodFile, MisplacedKeyNamesTheTable) {
  // A (a key of the Runge–Kutta kinds) after [constants] in a Rosenbrock file (line 3).
  const std::string ros = R"toml(name = "r"
kind = "rosenbrock"
order = 1
description = "d"
gamma = 1
alpha = [[0]]
gamma_offdiag = [[0]]
b = [1]
)toml";
  std::string msg =
      bad_input([&] { parse_method_file(ros + "[constants]\ng = 2\nA = [[1]]\n", "r.toml"); });
  EXPECT_NE(msg.find("r.toml:11: key 'A' is inside the table [constants] (TOML puts every key "
                     "after a [table] header into that table"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("'A' is a method-file key (of kind explicit_rk, dirk, irk), not a constant"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("write the method's keys before the [constants] header, or move the "
                     "[constants] table to the end of the file"),
            std::string::npos)
      << msg;
  // A value that is no coefficient.
  msg = bad_input([&] { parse_method_file(ros + "[constants]\nrows = [1, 2]\n", "r.toml"); });
  EXPECT_NE(msg.find("r.toml:10: key 'rows' is inside the table [constants]"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("a constant is a number or a string holding an expression"), std::string::npos)
      << msg;
  // The method's key both at the top level and inside [constants]: both lines named.
  msg = bad_input([&] { parse_method_file(ros + "[constants]\nb = [1]\n", "r.toml"); });
  EXPECT_NE(msg.find("r.toml:10: key 'b' is inside the table [constants]"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("and also at the top level (line 8)"), std::string::npos) << msg;
  // A constant named after one of the kind's keys is read as that key, and the message says so.
  const std::string dirk =
      "name = \"d\"\nkind = \"dirk\"\norder = 1\ndescription = \"d\"\nA = [[1]]\nb = [1]\n";
  msg = bad_input([&] { parse_method_file(dirk + "[constants]\nc = \"1/2\"\n", "d.toml"); });
  EXPECT_NE(msg.find("d.toml:8: key 'c': expected a list of coefficients (written inside the "
                     "table [constants], read as the method's top-level key: the format's keys "
                     "cannot name constants)"),
            std::string::npos)
      << msg;
  // A key of another kind whose string is no expression: named as misplaced, with the
  // expression's own error in case a constant was meant.
  msg =
      bad_input([&] { parse_method_file(dirk + "[constants]\nsolver = \"radau5\"\n", "d.toml"); });
  EXPECT_NE(msg.find("d.toml:8: key 'solver' is inside the table [constants]"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("'solver' is a method-file key (of kind irk), not a constant (as a "
                     "constant: "),
            std::string::npos)
      << msg;
  // An imex_ark file: a key after [implicit] that is no key of that table nor of the kind.
  const std::string imex = R"toml(name = "ie"
kind = "imex_ark"
order = 1
description = "d"
[explicit]
A = [[0, 0], [1, 0]]
b = [1, 0]
[implicit]
A = [[0, 0], [0, 1]]
b = [0, 1]
)toml";
  msg = bad_input([&] { parse_method_file(imex + "fsal = true\n", "ie.toml"); });
  EXPECT_NE(msg.find("ie.toml:11: key 'fsal' is inside the table [implicit]"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("write the top-level keys before the first [table] header"), std::string::npos)
      << msg;
  // The kind's own top-level keys written after [implicit] are read as such.
  const MethodDefinition m =
      parse_method_file(replaced(imex, "order = 1\n", "") + "order = 1\n", "ie.toml");
  EXPECT_EQ(m.order, 1);
}

TEST(MethodFile, OverclaimedOrderNamesFileLineAndCondition) {
  const std::string msg = bad_input([] { parse_method_file(with_order(4), "heun3.toml"); });
  EXPECT_NE(msg.find("heun3.toml:3:"), std::string::npos) << msg;  // line of `order`
  // The first violated condition of order 4, by hand: bᵀc³ = 3/4·(2/3)³ = 2/9 against 1/4, the
  // tree [t^3] (residual -1/36), comes before [[[t]]] in the order of rooted_trees().
  EXPECT_NE(msg.find("order 4 claimed but the condition of tree [t^3] (order 4) has residual "
                     "-0.0278"),
            std::string::npos)
      << msg;
}

TEST(MethodFile, BadFilesNameFileAndLine) {
  // b has 2 entries, A 3 rows (line 6).
  std::string s = replaced(kHeun3, "b = [\"1/4\", 0, \"3/4\"]", "b = [\"1/4\", \"3/4\"]");
  std::string msg = bad_input([&] { parse_method_file(s, "m.toml"); });
  EXPECT_NE(msg.find("m.toml:6: key 'A': 3 rows, need 2"), std::string::npos) << msg;

  // An entry above the diagonal of an explicit A (line 6).
  s = replaced(kHeun3, "[[0, 0, 0]", "[[0, 0, 1]");
  msg = bad_input([&] { parse_method_file(s, "m.toml"); });
  EXPECT_NE(msg.find("m.toml:6: key 'A'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("strictly lower triangular"), std::string::npos) << msg;
  EXPECT_NE(msg.find("row 1, column 3"), std::string::npos) << msg;

  // An unknown key (line 9) names the known ones.
  msg = bad_input([&] { parse_method_file(std::string(kHeun3) + "fsl = true\n", "m.toml"); });
  EXPECT_NE(msg.find("m.toml:9: unknown key 'fsl'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'fsal'"), std::string::npos) << msg;

  // A bad expression (line 7) names the expression.
  s = replaced(kHeun3, "\"3/4\"]", "\"3/(4\"]");
  msg = bad_input([&] { parse_method_file(s, "m.toml"); });
  EXPECT_NE(msg.find("m.toml:7: key 'b'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("\"3/(4\""), std::string::npos) << msg;

  // c that is not the row sums (line 8).
  s = replaced(kHeun3, "c = [0, \"1/3\", \"2/3\"]", "c = [0, \"1/3\", \"1/2\"]");
  msg = bad_input([&] { parse_method_file(s, "m.toml"); });
  EXPECT_NE(msg.find("m.toml:8: key 'c': c[3]"), std::string::npos) << msg;

  // A missing key, a TOML syntax error, a kind that does not exist.
  msg = bad_input([] { parse_method_file("kind = \"explicit_rk\"\n", "m.toml"); });
  EXPECT_NE(msg.find("m.toml: key 'name' missing"), std::string::npos) << msg;
  msg = bad_input([] { parse_method_file("name = \n", "m.toml"); });
  EXPECT_NE(msg.find("m.toml:1:"), std::string::npos) << msg;
  msg = bad_input([] { parse_method_file("kind = \"explicit\"\n", "m.toml"); });
  EXPECT_NE(msg.find("m.toml:1: key 'kind': unknown kind 'explicit'"), std::string::npos) << msg;
  msg = bad_input([] { load_method_file("/nonexistent/x.toml"); });
  EXPECT_NE(msg.find("/nonexistent/x.toml: cannot read"), std::string::npos) << msg;
}

TEST(MethodFile, DirkNeedsLowerTriangularA) {
  const char* text = R"toml(name = "x"
kind = "dirk"
order = 1
description = "d"
A = [[1, "1/2"], [0, 1]]
b = [0, 1]
)toml";
  const std::string msg = bad_input([&] { parse_method_file(text, "x.toml"); });
  EXPECT_NE(msg.find("x.toml:5: key 'A': a dirk method needs A lower triangular"),
            std::string::npos)
      << msg;
}

// ROS2 of Verwer et al. (γ = 1 + 1/√2, α21 = 1, γ21 = -2γ, b = (½, ½)) equals the built-in
// rosenbrock2; claimed order 3 is refused by its order-3 conditions.
TEST(MethodFile, RosenbrockFile) {
  const std::string text = R"toml(name = "my_ros2"
kind = "rosenbrock"
description = "ROS2"
gamma = "1 + 1/sqrt(2)"
alpha = [[0, 0], [1, 0]]
gamma_offdiag = [[0, 0], ["-2*(1 + 1/sqrt(2))", 0]]
b = ["1/2", "1/2"]
)toml";
  const MethodDefinition m = parse_method_file("order = 2\n" + text, "ros2.toml");
  const RosenbrockTableau& ref = rosenbrock2_tableau();
  EXPECT_NEAR(m.rosenbrock.gamma, ref.gamma, 1e-15);
  EXPECT_NEAR((m.rosenbrock.gamma_lower - ref.gamma_lower).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  EXPECT_EQ(m.rosenbrock.alpha, ref.alpha);
  EXPECT_EQ(m.rosenbrock.b, ref.b);
  EXPECT_EQ(m.class_text, "Rosenbrock");
  EXPECT_FALSE(m.adaptive());
  std::string msg = bad_input([&] { parse_method_file("order = 3\n" + text, "ros2.toml"); });
  EXPECT_NE(msg.find("ros2.toml:1: key 'order'"), std::string::npos) << msg;
  // ROS2 is of order 2 exactly: a condition of order 3 fails.
  EXPECT_NE(msg.find("order 3 claimed but the condition of tree"), std::string::npos) << msg;
  EXPECT_NE(msg.find("(order 3)"), std::string::npos) << msg;
  // ROS2 keeps order 2 for any W (by hand: bᵀα1 = 1/2, bᵀΓ1 = γ − γ = 0): w_order = 2 holds; a
  // W-order above the classical order is refused.
  EXPECT_EQ(parse_method_file("order = 2\nw_order = 2\n" + text, "ros2.toml").rosenbrock.w_order,
            2);
  msg = bad_input([&] { parse_method_file("order = 2\nw_order = 3\n" + text, "ros2.toml"); });
  EXPECT_NE(msg.find("ros2.toml:2: key 'w_order': W-order 3 claimed above the order 2"),
            std::string::npos)
      << msg;
  // ROS3P's coefficients: bᵀΓ1 = (2/3)γ + (1/3)(1/2 − 2γ) = 1/6 against 0 (and bᵀα1 = 1/3
  // against 1/2), so W-order 2 fails; the first condition in w_trees()' order is W[t]'s.
  const std::string ros3p = R"toml(name = "my_ros3p"
kind = "rosenbrock"
order = 3
w_order = 2
description = "ROS3P"
gamma = "g"
alpha = [[0, 0, 0], [1, 0, 0], [1, 0, 0]]
gamma_offdiag = [[0, 0, 0], [-1, 0, 0], ["-g", "1/2 - 2*g", 0]]
b = ["2/3", 0, "1/3"]
[constants]
g = "1/2 + sqrt(3)/6"
)toml";
  msg = bad_input([&] { parse_method_file(ros3p, "ros3p.toml"); });
  EXPECT_NE(msg.find("ros3p.toml:4: key 'w_order': Rosenbrock method 'my_ros3p': W-order 2 "
                     "claimed but the W-condition of tree W[t] (order 2) has residual 0.166667"),
            std::string::npos)
      << msg;
}

// Velocity Verlet as kick/drift coefficients, and yoshida4 as a composition γ = (c, 1 - 2c, c),
// c = 1/(2 - 2^(1/3)) (Yoshida 1990), equal to the built-in kick/drift form.
TEST(MethodFile, KickDriftFiles) {
  const MethodDefinition v = parse_method_file(R"toml(name = "vv"
kind = "kick_drift"
order = 2
description = "velocity Verlet"
kick = ["1/2", "1/2"]
drift = [1, 0]
)toml",
                                               "vv.toml");
  EXPECT_EQ(v.splitting.kick_drift.kick, (std::vector<double>{0.5, 0.5}));
  EXPECT_TRUE(v.splitting.velocity_independent);
  const MethodDefinition y = parse_method_file(R"toml(name = "y4"
kind = "kick_drift"
order = 4
description = "triple jump"
composition = ["1/(2 - cbrt(2))", "1 - 2/(2 - cbrt(2))", "1/(2 - cbrt(2))"]
)toml",
                                               "y4.toml");
  const auto ref_it = std::find_if(composition_methods().begin(), composition_methods().end(),
                                   [](const CompositionMethod& m) { return m.name == "yoshida4"; });
  ASSERT_NE(ref_it, composition_methods().end());
  const CompositionMethod& ref = *ref_it;
  ASSERT_EQ(y.splitting.kick_drift.kick.size(), ref.kick_drift.kick.size());
  for (std::size_t i = 0; i < ref.kick_drift.kick.size(); ++i) {
    EXPECT_NEAR(y.splitting.kick_drift.kick[i], ref.kick_drift.kick[i], 1e-15);
    EXPECT_NEAR(y.splitting.kick_drift.drift[i], ref.kick_drift.drift[i], 1e-15);
  }
  // Kicks that do not sum to 1.
  const std::string msg = bad_input([] {
    parse_method_file(
        "name = \"x\"\nkind = \"kick_drift\"\norder = 1\ndescription = \"x\"\n"
        "kick = [\"1/2\", \"1/4\"]\ndrift = [1, 0]\n",
        "x.toml");
  });
  EXPECT_NE(msg.find("x.toml:3: key 'order'"), std::string::npos) << msg;
}

// kind = "splitting", the old name of kick_drift, still reads for one version: the same method,
// with the same coefficients and the same steps.
TEST(MethodFile, OldKickDriftKindNameReadsTheSame) {
  const std::string body =
      "order = 4\ndescription = \"triple jump\"\n"
      "composition = [\"1/(2 - cbrt(2))\", \"1 - 2/(2 - cbrt(2))\", \"1/(2 - cbrt(2))\"]\n";
  const MethodDefinition now =
      parse_method_file("name = \"y4\"\nkind = \"kick_drift\"\n" + body, "now.toml");
  const MethodDefinition old =
      parse_method_file("name = \"y4\"\nkind = \"splitting\"\n" + body, "old.toml");
  EXPECT_EQ(now.kind, MethodKind::kick_drift);
  EXPECT_EQ(old.kind, MethodKind::kick_drift);
  EXPECT_EQ(to_string(old.kind), "kick_drift");
  EXPECT_EQ(old.splitting.kick_drift.kick, now.splitting.kick_drift.kick);
  EXPECT_EQ(old.splitting.kick_drift.drift, now.splitting.kick_drift.drift);
  EXPECT_EQ(old.splitting.velocity_independent, now.splitting.velocity_independent);
  EXPECT_EQ(old.class_text, now.class_text);
  EXPECT_TRUE(is_method_kind("splitting"));
  EXPECT_TRUE(is_method_kind("kick_drift"));

  auto sys = testing_support::model("kepler", {"e=0.5"});
  Vec y_now = sys->initial_state(), y_old = y_now;
  SolveStats s_now, s_old;
  auto a = make_integrator(now);
  auto b = make_integrator(old);
  a->reset(*sys, 0.0, y_now);
  b->reset(*sys, 0.0, y_old);
  for (int k = 0; k < 10; ++k) {
    ASSERT_EQ(a->step(*sys, 0.1 * k, y_now, 0.1, s_now), Status::ok);
    ASSERT_EQ(b->step(*sys, 0.1 * k, y_old, 0.1, s_old), Status::ok);
  }
  EXPECT_EQ(y_old, y_now);  // bit for bit
}

// Fixed-step runs of `a` and `b` on Kepler (e = 0.5, t = 1, h = 0.05): the largest difference of
// the final states.
double run_difference(Integrator& a, Integrator& b) {
  Vec y[2];
  Integrator* integ[2] = {&a, &b};
  for (int k = 0; k < 2; ++k) {
    auto sys = testing_support::model("kepler", {"e=0.5"});
    FixedStepOptions opt;
    opt.t_end = 1.0;
    opt.h = 0.05;
    const RunResult r = run_fixed_step(*sys, *integ[k], opt);
    EXPECT_EQ(r.stats.status, Status::ok);
    y[k] = r.y;
  }
  return (y[0] - y[1]).cwiseAbs().maxCoeff();
}

// Gauss–Legendre with 2 stages (Hairer–Nørsett–Wanner I, §II.7: c = 1/2 ∓ √3/6,
// A = [[1/4, 1/4 - √3/6], [1/4 + √3/6, 1/4]], b = (1/2, 1/2)) as a file runs as the built-in
// gauss4 does (the same class and coefficients to an ulp: the states agree to round-off), and
// takes gauss4's parameters.
TEST(MethodFile, IrkGaussFileRunsLikeGauss4) {
  const MethodDefinition m = parse_method_file(R"toml(name = "my_gauss4"
kind = "irk"
order = 4
stage_order = 2
description = "2-stage Gauss"
A = [["1/4", "1/4 - sqrt(3)/6"], ["1/4 + sqrt(3)/6", "1/4"]]
b = ["1/2", "1/2"]
c = ["1/2 - sqrt(3)/6", "1/2 + sqrt(3)/6"]
)toml",
                                               "g.toml");
  EXPECT_EQ(m.class_text, "implicit RK");
  EXPECT_FALSE(m.adaptive());
  auto mine = make_integrator(m);
  auto builtin = testing_support::make("gauss4");
  EXPECT_LE(run_difference(*mine, *builtin), 1e-13);
  std::vector<std::string> keys, theirs;
  for (const ParamSpec& s : method_param_specs(m)) keys.push_back(s.key);
  for (const ParamSpec& s : integrator_registry().at("gauss4").params) theirs.push_back(s.key);
  EXPECT_EQ(keys, theirs);
}

// The 3-stage Radau IIA tableau (Hairer & Wanner II, Table IV.5.6) with solver = "radau5" runs
// as the built-in radau5, fixed step and adaptive.
TEST(MethodFile, IrkRadauFileRunsLikeRadau5) {
  const MethodDefinition m = parse_method_file(R"toml(name = "my_radau5"
kind = "irk"
solver = "radau5"
order = 5
stage_order = 3
description = "Radau IIA, 3 stages"
A = [["(88 - 7*sqrt(6))/360", "(296 - 169*sqrt(6))/1800", "(-2 + 3*sqrt(6))/225"],
     ["(296 + 169*sqrt(6))/1800", "(88 + 7*sqrt(6))/360", "(-2 - 3*sqrt(6))/225"],
     ["(16 - sqrt(6))/36", "(16 + sqrt(6))/36", "1/9"]]
b = ["(16 - sqrt(6))/36", "(16 + sqrt(6))/36", "1/9"]
c = ["(4 - sqrt(6))/10", "(4 + sqrt(6))/10", 1]
)toml",
                                               "r.toml");
  EXPECT_TRUE(m.adaptive());
  auto mine = make_integrator(m);
  auto builtin = testing_support::make("radau5");
  EXPECT_TRUE(mine->supports_adaptive());
  EXPECT_LE(run_difference(*mine, *builtin), 1e-13);
  const IntegratorRegistry::Entry e = method_registry_entry(m);
  EXPECT_EQ(e.info.kind, "Radau IIA (RADAU5)");
  EXPECT_EQ(e.info.description, "Radau IIA, 3 stages");
}

TEST(MethodFile, IrkNeedsAnInvertibleA) {
  const std::string msg = bad_input([] {
    parse_method_file(R"toml(name = "x"
kind = "irk"
order = 1
description = "singular"
A = [[0, 0], ["1/2", "1/2"]]
b = ["1/2", "1/2"]
c = [0, 1]
)toml",
                      "x.toml");
  });
  EXPECT_NE(msg.find("x.toml:5: key 'A': an irk method needs an invertible A"), std::string::npos)
      << msg;
}

}  // namespace
}  // namespace stiffbench
