// `stiffbench fidelity` (experiments/studies/fidelity.hpp): the analytic damping and phase of one
// step on the undamped oscillator against closed forms derived here, the measured curve from
// harmonic_oscillator runs against the same closed forms, the recurrence fit on synthetic
// sequences, the modal analysis against the spring chain's known frequencies, the per-mode
// agreement on a cloth, and the refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>

#include "core/types.hpp"
#include "experiments/framework/resolve.hpp"
#include "experiments/studies/fidelity.hpp"

namespace stiffbench {
namespace {

using cd = std::complex<double>;

// The closed forms (x'' = −ω²x, ν = hω, first-order form y' = λy with λ = iω, z = iν):
//   backward Euler   y_{n+1} = y_n + zy_{n+1}  ⇒  μ = 1/(1 − iν), |μ| = 1/√(1 + ν²),
//                    arg μ = atan ν;
//   trapezoidal      μ = (1 + iν/2)/(1 − iν/2): |μ| = 1 (numerator and denominator are
//                    conjugates), arg μ = 2·atan(ν/2), so the period error is ν/(2 atan(ν/2)) − 1;
//   velocity Verlet  on (x, hv): kick ½, drift 1, kick ½ gives the matrix
//                    [[1 − ν²/2, 1], [−ν²(1 − ν²/4), 1 − ν²/2]] of determinant 1 and half-trace
//                    1 − ν²/2; for ν < 2 the eigenvalues are e^{±iθ} with cos θ = 1 − ν²/2, so
//                    |μ| = 1 and θ = arccos(1 − ν²/2);
//   symplectic Euler the same trace and determinant (kick 1 then drift 1: [[1 − ν², 1], [−ν², 1]]),
//                    so the same μ;
//   rk4              μ = 1 + z + z²/2 + z³/6 + z⁴/24 at z = iν;
//   bdf2             (3/2)y_{n+2} − 2y_{n+1} + ½y_n = z y_{n+2}: μ is the root of larger modulus
//                    of (3/2 − z)ζ² − 2ζ + ½ = 0, by the quadratic formula.
cd closed_form(const std::string& name, double nu) {
  const cd z(0.0, nu);
  if (name == "backward_euler") return 1.0 / (1.0 - z);
  if (name == "trapezoidal") return (1.0 + 0.5 * z) / (1.0 - 0.5 * z);
  if (name == "velocity_verlet" || name == "symplectic_euler") {
    const double c = 1.0 - 0.5 * nu * nu;
    return {c, std::sqrt(1.0 - c * c)};
  }
  if (name == "rk4") return 1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0;
  if (name == "bdf2") {
    const cd a = 1.5 - z, b = -2.0, c = 0.5;
    const cd d = std::sqrt(b * b - 4.0 * a * c);
    const cd r1 = (-b + d) / (2.0 * a), r2 = (-b - d) / (2.0 * a);
    const cd r = std::abs(r1) >= std::abs(r2) ? r1 : r2;
    return r.imag() < 0 ? std::conj(r) : r;
  }
  throw std::logic_error("no closed form for " + name);
}

FidelitySpec oscillator_spec(std::vector<std::string> integrators) {
  FidelitySpec s;
  s.integrators = std::move(integrators);
  s.nu_min = 1e-2;
  s.nu_max = 1.9;  // velocity Verlet's closed form above holds for ν < 2
  s.curve_points = 9;
  s.steps = 300;
  return s;
}

TEST(Fidelity, AnalyticCurvesMatchTheClosedForms) {
  const std::vector<std::string> names = {"backward_euler",  "trapezoidal",     "bdf2", "rk4",
                                          "velocity_verlet", "symplectic_euler"};
  FidelitySpec s = oscillator_spec(names);
  s.measure = false;
  const FidelityResult r = run_fidelity(s);
  std::map<std::string, int> count;
  for (const auto& p : r.curve) {
    ASSERT_EQ(p.source, "analytic");
    ++count[p.integrator];
    const cd mu = closed_form(p.integrator, p.r.nu);
    EXPECT_NEAR(p.r.amplification, std::abs(mu), 1e-10) << p.integrator << " nu " << p.r.nu;
    EXPECT_NEAR(p.r.phase, std::arg(mu), 1e-10) << p.integrator << " nu " << p.r.nu;
  }
  for (const auto& n : names) EXPECT_EQ(count[n], s.curve_points) << n;
  // The required statements in their own form.
  for (const auto& p : r.curve) {
    const double nu = p.r.nu;
    if (p.integrator == "backward_euler") {
      EXPECT_NEAR(p.r.amplification, 1.0 / std::sqrt(1.0 + nu * nu), 1e-10);
    }
    if (p.integrator == "trapezoidal") {
      EXPECT_NEAR(p.r.amplification, 1.0, 1e-10);
      EXPECT_NEAR(p.r.period_error, nu / (2.0 * std::atan(nu / 2.0)) - 1.0, 1e-10);
      EXPECT_NEAR(p.r.damping_ratio, 0.0, 1e-10);
    }
    if (p.integrator == "velocity_verlet") {
      EXPECT_NEAR(p.r.amplification, 1.0, 1e-10);
      EXPECT_NEAR(p.r.phase, std::acos(1.0 - nu * nu / 2.0), 1e-10);
    }
  }
}

TEST(Fidelity, MeasuredCurvesLieOnTheClosedForms) {
  const std::vector<std::string> names = {"backward_euler",  "trapezoidal", "bdf2",
                                          "sdirk3",          "rk4",         "velocity_verlet",
                                          "symplectic_euler"};
  const FidelityResult r = run_fidelity(oscillator_spec(names));
  std::map<std::string, int> measured;
  for (const auto& p : r.curve) {
    if (p.source != "measured") continue;
    ++measured[p.integrator];
    if (p.integrator == "sdirk3") continue;  // no closed form here; checked against analytic below
    const cd mu = closed_form(p.integrator, p.r.nu);
    EXPECT_NEAR(p.r.amplification, std::abs(mu), 1e-6) << p.integrator << " nu " << p.r.nu;
    EXPECT_NEAR(p.r.phase, std::arg(mu), 1e-6) << p.integrator << " nu " << p.r.nu;
  }
  for (const auto& n : names) EXPECT_EQ(measured[n], 9) << n;
  // sdirk3: measured against its own analytic curve (R(iν) from its tableau).
  for (const auto& m : r.curve) {
    if (m.integrator != "sdirk3" || m.source != "measured") continue;
    for (const auto& a : r.curve)
      if (a.integrator == "sdirk3" && a.source == "analytic" && a.r.nu == m.r.nu) {
        EXPECT_NEAR(m.r.amplification, a.r.amplification, 1e-6);
        EXPECT_NEAR(m.r.phase, a.r.phase, 1e-6);
      }
  }
}

TEST(Fidelity, RecurrenceFitRecoversAKnownMultiplier) {
  // x_n = Re(c μ^n) + Re(d η^n) with |η| < |μ|: an order-2 fit is not exact while η^n matters,
  // the order-4 fit is, and its dominant root is μ.
  const cd mu = std::polar(0.97, 0.3), eta = std::polar(0.4, 2.0);
  std::vector<double> x, v;
  for (int n = 0; n < 200; ++n) {
    x.push_back((cd(1.0, 0.5) * std::pow(mu, n) + cd(0.3, -0.2) * std::pow(eta, n)).real());
    v.push_back((cd(-0.2, 1.0) * std::pow(mu, n) + cd(0.1, 0.4) * std::pow(eta, n)).real());
  }
  const RecurrenceFit f = fit_step_multiplier({x, v}, 0);
  ASSERT_TRUE(f.ok) << f.reason;
  EXPECT_EQ(f.order, 4);
  EXPECT_NEAR(std::abs(f.multiplier - mu), 0.0, 1e-10);
  // A single geometric pair: order 2.
  std::vector<double> y;
  for (int n = 0; n < 100; ++n) y.push_back((cd(1.0, 2.0) * std::pow(mu, n)).real());
  const RecurrenceFit g = fit_step_multiplier({y}, 0);
  ASSERT_TRUE(g.ok);
  EXPECT_EQ(g.order, 2);
  EXPECT_NEAR(std::abs(g.multiplier - mu), 0.0, 1e-12);
}

TEST(Fidelity, ModesOfTheSpringChainAreItsKnownFrequencies) {
  // A fixed–fixed chain of N unit masses and springs k: ω_j = 2√(k/m) sin(jπ/(2(N+1)))
  // (the tridiagonal matrix's eigenvalues). Backward Euler per mode against its closed form.
  FidelitySpec s;
  s.integrators = {"backward_euler"};
  s.model = "spring_chain";
  s.params = Params{{"n", "24"}, {"mode", "0"}};
  s.measure = false;
  s.curve_points = 2;
  s.modes = 20;
  s.h = {0.5};
  const FidelityResult r = run_fidelity(s);
  ASSERT_EQ(r.modes.size(), 20u);
  for (const auto& m : r.modes) {
    const double w = 2.0 * std::sin(m.mode * std::numbers::pi / (2.0 * 25.0));
    EXPECT_NEAR(m.omega, w, 1e-10) << "mode " << m.mode;
    ASSERT_TRUE(m.measured) << m.note;
    const cd mu = closed_form("backward_euler", 0.5 * w);
    EXPECT_NEAR(m.measured->amplification, std::abs(mu), 1e-4) << "mode " << m.mode;
    EXPECT_NEAR(m.measured->phase, std::arg(mu), 1e-4) << "mode " << m.mode;
  }
}

TEST(Fidelity, ClothModesAgreeWithTheCurveWithinFivePercent) {
  // The mode check on a small cloth (the command runs it on n = 16): each linear mode of a
  // linear method evolves on its own, so the measured damping ratio and frequency of every
  // mode match the analytic curve at ν = hω_k up to the run's nonlinearity (amplitude 1e-7).
  // The defaults load the cloth (gravity, a random perturbation): the model's rest state
  // (gravity=0, perturbation=0) is applied, as the command does.
  FidelitySpec s;
  s.integrators = {"backward_euler", "bdf2"};
  s.model = "cloth";
  s.params = Params{{"n", "6"}};
  std::vector<std::string> applied;
  EXPECT_EQ(with_rest_state(inputs_of(s), s, &applied).params.values(),
            (Params{{"n", "6"}, {"gravity", "0"}, {"perturbation", "0"}}.values()));
  EXPECT_EQ(applied, (std::vector<std::string>{"gravity=0", "perturbation=0"}));
  s.measure = false;
  s.curve_points = 2;
  s.modes = 20;
  const FidelityResult r = run_fidelity(s);
  ASSERT_EQ(r.mode_steps_used.size(), 2u);
  ASSERT_EQ(r.modes.size(), 2u * 2u * 20u);
  for (const auto& m : r.modes) {
    ASSERT_TRUE(m.measured && m.predicted) << m.integrator << " mode " << m.mode << m.note;
    const double dd = std::abs(m.measured->damping_ratio - m.predicted->damping_ratio) /
                      std::abs(m.predicted->damping_ratio);
    EXPECT_LT(dd, 0.05) << m.integrator << " h " << m.h << " mode " << m.mode;
    EXPECT_LT(std::abs(m.measured->phase / m.predicted->phase - 1.0), 0.05);
  }
}

// The measured damping of an undamped method (trapezoidal rule, exact ξ̄ = 0) on the cloth's
// modes is the modes' nonlinear coupling: the spring forces are nonlinear in the displacement, so
// relative to the motion their quadratic part is O(ε). Theory: ξ̄_measured ∝ amplitude, so
// 100 times the amplitude gives about 100 times the largest |ξ̄| (checked within a factor 2);
// at the default 1e-7 every mode is within 5% of the 1e-4 floor the summary uses, and so are the
// lightly damped sdirk3's (ξ̄ down to 2.6e-5 at ν = 0.1).
TEST(Fidelity, ModesNonlinearCouplingScalesWithTheAmplitude) {
  FidelitySpec s;
  s.integrators = {"trapezoidal", "sdirk3"};
  s.model = "cloth";
  s.params = Params{{"n", "6"}, {"gravity", "0"}, {"perturbation", "0"}};
  s.measure = false;
  s.curve_points = 2;
  s.modes = 10;
  EXPECT_DOUBLE_EQ(s.amplitude, 1e-7);
  const auto largest_trapezoidal_damping = [](const FidelityResult& r) {
    double most = 0;
    for (const auto& m : r.modes)
      if (m.integrator == "trapezoidal" && m.measured)
        most = std::max(most, std::abs(m.measured->damping_ratio));
    return most;
  };
  const FidelityResult fine = run_fidelity(s);
  for (const auto& m : fine.modes) {
    ASSERT_TRUE(m.measured && m.predicted) << m.integrator << " mode " << m.mode << m.note;
    const double dd = std::abs(m.measured->damping_ratio - m.predicted->damping_ratio) /
                      std::max(std::abs(m.predicted->damping_ratio), 1e-4);
    EXPECT_LT(dd, 0.05) << m.integrator << " h " << m.h << " mode " << m.mode;
  }
  s.amplitude = 1e-5;
  const FidelityResult coarse = run_fidelity(s);
  const double ratio = largest_trapezoidal_damping(coarse) / largest_trapezoidal_damping(fine);
  EXPECT_GT(ratio, 50.0);
  EXPECT_LT(ratio, 200.0);
}

TEST(Fidelity, RefusesBadInput) {
  FidelitySpec s = oscillator_spec({"backward_euler"});
  s.nu_min = 2;
  s.nu_max = 1;
  EXPECT_THROW(run_fidelity(s), BadInput);
  s = oscillator_spec({"backward_euler"});
  s.model = "cloth";  // gravity set explicitly: not at rest, and the rest state is not applied
  s.params = Params{{"n", "4"}, {"gravity", "1"}};
  try {
    run_fidelity(s);
    ADD_FAILURE() << "a cloth under gravity is not at rest";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("its rest state: gravity=0, perturbation=0"),
              std::string::npos)
        << e.what();
  }
  s.params = Params{{"n", "4"}, {"gravity", "0"}, {"perturbation", "0"}, {"damping", "0.1"}};
  EXPECT_THROW(run_fidelity(s), BadInput);  // damped
  s.model = "robertson";
  s.params = Params{};
  EXPECT_THROW(run_fidelity(s), BadInput);  // not mechanical
  s = oscillator_spec({"backward_euler"});
  s.params = Params{{"no_such_key", "1"}};
  EXPECT_THROW(run_fidelity(s), BadInput);
}

TEST(Fidelity, SpringMethodsAreMeasuredOnASpringAndOthersAreNamed) {
  // xpbd needs springs: measured on a spring_chain of one mass (linear in 1D). With its
  // iterations converged XPBD is the variational form of backward Euler (Macklin, Müller &
  // Chentanez 2016: x_{n+1} minimises ½|x − x̃|²_M + h²·E(x), x̃ = x_n + h v_n, and
  // v_{n+1} = (x_{n+1} − x_n)/h, which on a linear spring is backward Euler's step), so its
  // measured curve is backward Euler's closed form. lie needs a split: named, not measured.
  FidelitySpec s = oscillator_spec({"xpbd", "lie"});
  s.params = Params{{"iterations", "60"}};
  s.nu_max = 1.0;
  const FidelityResult r = run_fidelity(s);
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_EQ(r.skipped[0].first, "lie");
  ASSERT_EQ(r.measured_on.size(), 1u);
  EXPECT_EQ(r.measured_on[0].second, "spring_chain n=1");
  int measured = 0;
  for (const auto& p : r.curve) {
    EXPECT_EQ(p.integrator, "xpbd");
    EXPECT_EQ(p.source, "measured");  // no coefficients: no analytic curve
    ++measured;
    const cd mu = closed_form("backward_euler", p.r.nu);
    EXPECT_NEAR(p.r.amplification, std::abs(mu), 1e-6) << "nu " << p.r.nu;
    EXPECT_NEAR(p.r.phase, std::arg(mu), 1e-6) << "nu " << p.r.nu;
  }
  EXPECT_GE(measured, 7);  // of 9 (a step whose fit is refused is listed in r.unfitted)
}

// The study on inputs resolved once: a method file given by its path (Ralston's method under
// another name) and a variant of a built-in method, their curves under their labels.
TEST(Fidelity, RunsFromResolvedInputsWithAMethodFileAndAVariant) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("stiffbench_fidelity_inputs_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "fidelity_ralston.toml";
  std::ofstream(file) << "name = \"fidelity_ralston\"\nkind = \"explicit_rk\"\n"
                      << "class = \"explicit RK\"\norder = 2\nstage_order = 1\n"
                      << "description = \"Ralston's method under another name\"\n"
                      << "A = [[0, 0], [\"2/3\", 0]]\nb = [\"1/4\", \"3/4\"]\n";
  StudyTarget t;
  t.integrators = {file.string(), "backward_euler{newton_max_iter=30}"};
  const StudyInputs in = resolve_inputs(t);
  FidelitySpec spec = oscillator_spec({});
  spec.curve_points = 3;
  const FidelityResult r = run_fidelity(in, spec);
  std::map<std::string, std::map<std::string, int>> count;  // integrator, source -> points
  for (const auto& p : r.curve) ++count[p.integrator][p.source];
  using Counts = std::map<std::string, int>;
  EXPECT_EQ(count["fidelity_ralston"], (Counts{{"analytic", 3}, {"measured", 3}}));
  EXPECT_EQ(count["backward_euler{newton_max_iter=30}"],
            (Counts{{"analytic", 3}, {"measured", 3}}));
  EXPECT_EQ(count.size(), 2u);
  ASSERT_EQ(r.analytic.size(), 2u);
  EXPECT_EQ(r.analytic[0].integrator, "fidelity_ralston");
  EXPECT_EQ(r.analytic[1].integrator, "backward_euler{newton_max_iter=30}");
  for (const auto& a : r.analytic) {
    EXPECT_EQ(a.measured, 3) << a.integrator;
    EXPECT_LT(a.max_da, 1e-6) << a.integrator;  // the measured points lie on the analytic curve
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stiffbench
