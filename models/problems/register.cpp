#include <algorithm>

#include "models/problems/advection_diffusion.hpp"
#include "models/problems/brusselator.hpp"
#include "models/problems/dahlquist.hpp"
#include "models/problems/e5.hpp"
#include "models/problems/harmonic_oscillator.hpp"
#include "models/problems/hires.hpp"
#include "models/problems/kaps.hpp"
#include "models/problems/kepler.hpp"
#include "models/problems/orego.hpp"
#include "models/problems/pendulum.hpp"
#include "models/problems/pollution.hpp"
#include "models/problems/prothero_robinson.hpp"
#include "models/problems/robertson.hpp"
#include "models/problems/van_der_pol.hpp"
#include "models/register.hpp"

namespace stiffbench {

void register_problem_models(ModelRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  reg.add({{"dahlquist", "y' = λy with complex λ as a 2-dimensional real system", false, true,
            "Dahlquist 1963; exact solution exp(λt) y0"},
           {{"lambda_re", P::real, "-1", "real part of λ", B::any()},
            {"lambda_im", P::real, "0", "imaginary part of λ", B::any()},
            {"y0_re", P::real, "1", "real part of y(0)", B::any()},
            {"y0_im", P::real, "0", "imaginary part of y(0)", B::any()}},
           [](const Params& p) {
             return std::make_unique<Dahlquist>(
                 std::complex<double>(p.real("lambda_re"), p.real("lambda_im")),
                 std::complex<double>(p.real("y0_re"), p.real("y0_im")));
           }});
  reg.add({{"harmonic_oscillator", "m x'' + γ x' + k x = 0 (undamped by default)", true, true,
            "closed-form solution for under-, critically and overdamped cases"},
           {{"m", P::real, "1", "mass", B::positive()},
            {"k", P::real, "1", "spring stiffness", B::positive()},
            {"gamma", P::real, "0", "viscous damping coefficient γ", B::non_negative()},
            {"x0", P::real, "1", "initial position", B::any()},
            {"v0", P::real, "0", "initial velocity", B::any()}},
           [](const Params& p) {
             return std::make_unique<HarmonicOscillator>(p.real("m"), p.real("k"), p.real("gamma"),
                                                         p.real("x0"), p.real("v0"));
           }});
  reg.add({{"kepler", "planar two-body orbit starting at pericentre (period 2π by default)", true,
            true, "exact solution through Kepler's equation (Goldstein §3.8)"},
           {{"e", P::real, "0", "eccentricity", B::in_closed_open(0, 1)},
            {"gm", P::real, "1", "gravitational parameter GM", B::positive()},
            {"a", P::real, "1", "semi-major axis", B::positive()}},
           [](const Params& p) {
             return std::make_unique<Kepler>(p.real("e"), p.real("gm"), p.real("a"));
           }});
  reg.add({{"pendulum", "nonlinear pendulum θ'' = -(g/L) sin θ", true, false,
            "no closed form used; convergence needs --reference"},
           {{"g", P::real, "1", "gravitational acceleration", B::positive()},
            {"length", P::real, "1", "pendulum length L", B::positive()},
            {"theta0", P::real, "1", "initial angle (rad)", B::any()},
            {"omega0", P::real, "0", "initial angular velocity (rad/s)", B::any()}},
           [](const Params& p) {
             return std::make_unique<Pendulum>(p.real("g"), p.real("length"), p.real("theta0"),
                                               p.real("omega0"));
           }});
  reg.add({{"prothero_robinson", "y' = λ(y - φ(t)) + φ'(t): stiffness knob λ, exact y = φ", false,
            true, "Prothero & Robinson, Math. Comp. 28 (1974)"},
           {{"lambda", P::real, "-1e6", "stiffness λ (the Jacobian)", B::any()},
            {"phi", P::text, "sin", "φ(t)", {"sin", "cos", "exp"}},
            {"y0_offset", P::real, "0", "y(0) - φ(0); the exact solution adds offset·e^{λt}",
             B::any()}},
           [](const Params& p) {
             const std::string& name = p.text("phi");
             const auto phi = name == "sin"   ? ProtheroRobinson::Phi::sin
                              : name == "cos" ? ProtheroRobinson::Phi::cos
                                              : ProtheroRobinson::Phi::exp;
             return std::make_unique<ProtheroRobinson>(p.real("lambda"), phi, p.real("y0_offset"));
           }});
  // Classic stiff test problems (Hairer & Wanner II §IV.10; IVP test set of Mazzia &
  // Magherini). Each model's end_time() is the literature end time, used when --t-end is
  // omitted.
  reg.add({{"robertson",
            "Robertson's chemical kinetics (3 species, stiff); literature end time t = 1e11", false,
            false, "Robertson 1966; Hairer & Wanner II §IV.10 (ROBER); IVP test set 'rober'"},
           {{"k1", P::real, "0.04", "rate constant of A → B", B::non_negative()},
            {"k2", P::real, "3e7", "rate constant of 2B → B + C", B::non_negative()},
            {"k3", P::real, "1e4", "rate constant of B + C → A + C", B::non_negative()}},
           [](const Params& p) {
             return std::make_unique<Robertson>(p.real("k1"), p.real("k2"), p.real("k3"));
           }});
  reg.add({{"hires", "HIRES plant photomorphogenesis (8 species); literature end time t = 321.8122",
            false, false, "Schäfer 1975; Hairer & Wanner II §IV.10 (HIRES); IVP test set 'hires'"},
           {},
           [](const Params&) { return std::make_unique<Hires>(); }});
  reg.add(
      {{"van_der_pol",
        "van der Pol oscillator, scaled y2' = ((1-y1²)y2 - y1)/ε with ε = 1/μ² (default) or "
        "classical y2' = μ(1-y1²)y2 - y1; literature end time t = 2 (scaled) or t = 2μ (form=mu)",
        false, false,
        "Hairer & Wanner II §IV.10 (VDPOL, ε = 1e-6); IVP test set 'vdpol' (μ = 1000)"},
       {{"form",
         P::text,
         "scaled",
         "scaled (time x = t/μ, ε = 1/μ²) or mu (classical)",
         {"scaled", "mu"}},
        {"mu", P::real, "1000",
         "damping parameter μ; the scaled form uses ε = 1/μ² (1000: ε = 1e-6)", B::positive()}},
       [](const Params& p) {
         const auto form =
             p.text("form") == "scaled" ? VanDerPol::Form::scaled : VanDerPol::Form::mu;
         return std::make_unique<VanDerPol>(form, p.real("mu"));
       }});
  reg.add(
      {{"orego", "Oregonator (Belousov–Zhabotinskii reaction); literature end time t = 360", false,
        false, "Field & Noyes 1974; Hairer & Wanner II §IV.10 (OREGO); IVP test set 'orego'"},
       {{"s", P::real, "77.27", "time-scale ratio s", B::positive()},
        {"w", P::real, "0.161", "rate w", B::non_negative()},
        {"q", P::real, "8.375e-6", "rate q", B::non_negative()}},
       [](const Params& p) {
         return std::make_unique<Orego>(p.real("s"), p.real("w"), p.real("q"));
       }});
  reg.add({{"e5", "E5 chemical pyrolysis (4 species, badly scaled); literature end time t = 1e13",
            false, false, "Enright, Hull & Lindberg 1975; Hairer & Wanner II §IV.10 (E5)"},
           {{"a", P::real, "7.89e-10", "rate constant A", B::non_negative()},
            {"b", P::real, "1.1e7", "rate constant B", B::non_negative()},
            {"c", P::real, "1.13e3", "rate constant C", B::non_negative()},
            {"m", P::real, "1e6", "factor M of the M·C y2 y3 rate", B::non_negative()}},
           [](const Params& p) {
             return std::make_unique<E5>(p.real("a"), p.real("b"), p.real("c"), p.real("m"));
           }});
  reg.add({{"pollution",
            "POLLU air-pollution chemistry (20 species, 25 reactions); literature end time t = 60",
            false, false, "Verwer 1994 (SIAM J. Sci. Comput. 15); IVP test set 'pollu'"},
           {},
           [](const Params&) { return std::make_unique<Pollution>(); }});
  reg.add({{"kaps",
            "Kaps' problem y1' = -(2 + 1/ε) y1 + y2²/ε, y2' = y1 - y2 - y2², exact "
            "(e^{-2t}, e^{-t}) for every ε; split=stiff: the 1/ε terms implicit; end time 1",
            false, true,
            "Kaps & Rentrop, Numer. Math. 33 (1979); Hairer & Wanner II §IV.15 (order reduction)"},
           {{"eps", P::real, "1e-6", "stiffness parameter ε", B::positive()},
            {"split",
             P::text,
             "stiff",
             "additive split f = f_E + f_I: stiff (f_I = the 1/ε terms, f_E the rest)",
             {"stiff"}}},
           [](const Params& p) {
             p.text("split");  // one split (stiff): nothing to choose
             return std::make_unique<Kaps>(p.real("eps"));
           }});
  reg.add({{"advection_diffusion",
            "1D periodic u_t + a u_x = ν u_xx - r u on [0,1), central differences on n cells, "
            "initial sin(2πk x); split=advection: advection explicit, diffusion and reaction "
            "implicit; end time 1",
            false, true,
            "method of lines; exact solution of the ODE e^{μt} sin(θj - ωt) from the circulant "
            "operator's Fourier modes"},
           {{"n", P::integer, "256", "cells N (Δx = 1/N)", B::in(3, 10000000)},
            {"a", P::real, "1", "advection speed a", B::any()},
            {"nu", P::real, "1e-4", "diffusion coefficient ν", B::non_negative()},
            {"r", P::real, "0", "reaction (decay) rate r", B::non_negative()},
            {"k", P::integer, "1", "wave number of the initial mode sin(2πk x)", B::in(0, 1e9)},
            {"split",
             P::text,
             "advection",
             "additive split f = f_E + f_I: advection (advection explicit; diffusion and "
             "reaction implicit)",
             {"advection"}}},
           [](const Params& p) {
             p.text("split");  // one split (advection): nothing to choose
             return std::make_unique<AdvectionDiffusion>(static_cast<int>(p.integer("n")),
                                                         p.real("a"), p.real("nu"), p.real("r"),
                                                         static_cast<int>(p.integer("k")));
           }});
  reg.add({{"brusselator",
            "1D Brusselator with diffusion: u' = 1 + u²v - 4u + α(N+1)² Δu, v' = 3u - u²v + "
            "α(N+1)² Δv on N interior points, u = 1, v = 3 at both ends, u(0) = 1 + sin(2πx), "
            "v(0) = 3; unknowns interleaved (banded Jacobian); end time 10",
            false, false,
            "Hairer, Nørsett & Wanner I §I.16; Hairer & Wanner II §IV.1 (BRUSS, N = 500 in "
            "§IV.10)"},
           {{"n", P::integer, "32", "interior grid points N (x_i = i/(N+1); 2N unknowns)",
             B::in(1, 10000000)},
            {"alpha", P::real, "0.02", "diffusion coefficient α (1/50 in the literature)",
             B::positive()}},
           [](const Params& p) {
             return std::make_unique<Brusselator>(static_cast<int>(p.integer("n")),
                                                  p.real("alpha"));
           }});
  // advection_diffusion: n unknowns, the tridiagonal Jacobian (3n nonzeros of 12 bytes).
  reg.find_mutable("advection_diffusion")->info.size = [](const Params& p) {
    const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
    return ModelSize{n, 12.0 * 3.0 * n + 32.0 * n, 3.0 * n, "n=" + std::to_string(p.integer("n"))};
  };
  // brusselator: 2n unknowns, the banded Jacobian (8n - 4 nonzeros of 12 bytes).
  reg.find_mutable("brusselator")->info.size = [](const Params& p) {
    const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
    return ModelSize{2.0 * n, 12.0 * 8.0 * n + 64.0 * n, 8.0 * n,
                     "n=" + std::to_string(p.integer("n"))};
  };
  // Fixed-size problems: at most 20 unknowns (POLLU), whatever their parameters.
  for (const auto& name : reg.names()) {
    auto* e = reg.find_mutable(name);
    if (!e->info.size)
      e->info.size = [](const Params&) { return ModelSize{20, 4096, 400, "fixed size"}; };
  }
}

}  // namespace stiffbench
