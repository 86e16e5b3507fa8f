#include "models/register.hpp"
#include "models/problems/dahlquist.hpp"
#include "models/problems/harmonic_oscillator.hpp"
#include "models/problems/kepler.hpp"
#include "models/problems/pendulum.hpp"
#include "models/problems/prothero_robinson.hpp"

namespace stiffbench {

void register_problem_models(ModelRegistry& reg) {
  using P = ParamType;
  reg.add({{"dahlquist", "y' = λy with complex λ as a 2-dimensional real system", false, true,
            "Dahlquist 1963; exact solution exp(λt) y0"},
           {{"lambda_re", P::real, "-1", "real part of λ"},
            {"lambda_im", P::real, "0", "imaginary part of λ"},
            {"y0_re", P::real, "1", "real part of y(0)"},
            {"y0_im", P::real, "0", "imaginary part of y(0)"}},
           [](const Params& p) {
             return std::make_unique<Dahlquist>(
                 std::complex<double>(p.real("lambda_re"), p.real("lambda_im")),
                 std::complex<double>(p.real("y0_re"), p.real("y0_im")));
           }});
  reg.add({{"harmonic_oscillator", "m x'' + γ x' + k x = 0 (undamped by default)", true, true,
            "closed-form solution for under-, critically and overdamped cases"},
           {{"m", P::real, "1", "mass"},
            {"k", P::real, "1", "spring stiffness"},
            {"gamma", P::real, "0", "viscous damping coefficient γ (>= 0)"},
            {"x0", P::real, "1", "initial position"},
            {"v0", P::real, "0", "initial velocity"}},
           [](const Params& p) {
             return std::make_unique<HarmonicOscillator>(p.real("m"), p.real("k"), p.real("gamma"),
                                                         p.real("x0"), p.real("v0"));
           }});
  reg.add({{"kepler", "planar two-body orbit starting at pericentre (period 2π by default)", true,
            true, "exact solution through Kepler's equation (Goldstein §3.8)"},
           {{"e", P::real, "0", "eccentricity, 0 <= e < 1"},
            {"gm", P::real, "1", "gravitational parameter GM"},
            {"a", P::real, "1", "semi-major axis"}},
           [](const Params& p) {
             return std::make_unique<Kepler>(p.real("e"), p.real("gm"), p.real("a"));
           }});
  reg.add({{"pendulum", "nonlinear pendulum θ'' = -(g/L) sin θ", true, false,
            "no closed form used; convergence needs --reference"},
           {{"g", P::real, "1", "gravitational acceleration"},
            {"length", P::real, "1", "pendulum length L (> 0)"},
            {"theta0", P::real, "1", "initial angle (rad)"},
            {"omega0", P::real, "0", "initial angular velocity (rad/s)"}},
           [](const Params& p) {
             require_input(p.real("length") > 0, "pendulum: parameter 'length' must be > 0");
             return std::make_unique<Pendulum>(p.real("g"), p.real("length"), p.real("theta0"),
                                               p.real("omega0"));
           }});
  reg.add({{"prothero_robinson", "y' = λ(y - φ(t)) + φ'(t): stiffness knob λ, exact y = φ", false,
            true, "Prothero & Robinson, Math. Comp. 28 (1974)"},
           {{"lambda", P::real, "-1e6", "stiffness λ (the Jacobian)"},
            {"phi", P::text, "sin", "φ(t)", {"sin", "cos", "exp"}},
            {"y0_offset", P::real, "0", "y(0) - φ(0); the exact solution adds offset·e^{λt}"}},
           [](const Params& p) {
             const std::string& name = p.text("phi");
             const auto phi = name == "sin"   ? ProtheroRobinson::Phi::sin
                              : name == "cos" ? ProtheroRobinson::Phi::cos
                                              : ProtheroRobinson::Phi::exp;
             return std::make_unique<ProtheroRobinson>(p.real("lambda"), phi, p.real("y0_offset"));
           }});
}

}  // namespace stiffbench
