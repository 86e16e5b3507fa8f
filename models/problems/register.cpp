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

namespace {

// Fixed-size problems: at most 20 unknowns (POLLU), whatever their parameters.
ModelSize fixed_size(const Params&) { return ModelSize{20, 4096, 400, "fixed size"}; }

}  // namespace

void register_problem_models(ModelRegistry& reg) {
  using P = ParamType;
  using B = Bounds;
  reg.add({.info = {.name = "dahlquist",
                    .description = "y' = λy with complex λ as a 2-dimensional real system",
                    .exact = true,
                    .source = "Dahlquist 1963; exact solution exp(λt) y0",
                    .size = fixed_size},
           .params = {{"lambda_re", P::real, "-1", "real part of λ", B::any()},
                      {"lambda_im", P::real, "0", "imaginary part of λ", B::any()},
                      {"y0_re", P::real, "1", "real part of y(0)", B::any()},
                      {"y0_im", P::real, "0", "imaginary part of y(0)", B::any()}},
           .make = [](const Params& p) {
             return std::make_unique<Dahlquist>(
                 std::complex<double>(p.real("lambda_re"), p.real("lambda_im")),
                 std::complex<double>(p.real("y0_re"), p.real("y0_im")));
           }});
  reg.add({.info = {.name = "harmonic_oscillator",
                    .description = "m x'' + γ x' + k x = 0 (undamped by default)",
                    .mechanical = true,
                    .exact = true,
                    .source = "closed-form solution for under-, critically and overdamped cases",
                    .size = fixed_size},
           .params = {{"m", P::real, "1", "mass", B::positive()},
                      {"k", P::real, "1", "spring stiffness", B::positive()},
                      {"gamma", P::real, "0", "viscous damping coefficient γ", B::non_negative()},
                      {"x0", P::real, "1", "initial position", B::any()},
                      {"v0", P::real, "0", "initial velocity", B::any()}},
           .make = [](const Params& p) {
             return std::make_unique<HarmonicOscillator>(p.real("m"), p.real("k"), p.real("gamma"),
                                                         p.real("x0"), p.real("v0"));
           }});
  reg.add({.info = {.name = "kepler",
                    .description =
                        "planar two-body orbit starting at pericentre (period 2π by default)",
                    .mechanical = true,
                    .exact = true,
                    .source = "exact solution through Kepler's equation (Goldstein §3.8)",
                    .size = fixed_size},
           .params = {{"e", P::real, "0", "eccentricity", B::in_closed_open(0, 1)},
                      {"gm", P::real, "1", "gravitational parameter GM", B::positive()},
                      {"a", P::real, "1", "semi-major axis", B::positive()}},
           .make = [](const Params& p) {
             return std::make_unique<Kepler>(p.real("e"), p.real("gm"), p.real("a"));
           }});
  reg.add({.info = {.name = "pendulum",
                    .description = "nonlinear pendulum θ'' = -(g/L) sin θ",
                    .mechanical = true,
                    .source = "no closed form used; convergence needs --reference",
                    .size = fixed_size},
           .params = {{"g", P::real, "1", "gravitational acceleration", B::positive()},
                      {"length", P::real, "1", "pendulum length L", B::positive()},
                      {"theta0", P::real, "1", "initial angle (rad)", B::any()},
                      {"omega0", P::real, "0", "initial angular velocity (rad/s)", B::any()}},
           .make = [](const Params& p) {
             return std::make_unique<Pendulum>(p.real("g"), p.real("length"), p.real("theta0"),
                                               p.real("omega0"));
           }});
  reg.add({.info = {.name = "prothero_robinson",
                    .description = "y' = λ(y - φ(t)) + φ'(t): stiffness knob λ, exact y = φ",
                    .exact = true,
                    .source = "Prothero & Robinson, Math. Comp. 28 (1974)",
                    .size = fixed_size},
           .params = {{"lambda", P::real, "-1e6", "stiffness λ (the Jacobian)", B::any()},
                      {"phi", P::text, "sin", "φ(t)", {"sin", "cos", "exp"}},
                      {"y0_offset", P::real, "0",
                       "y(0) - φ(0); the exact solution adds offset·e^{λt}", B::any()}},
           .make = [](const Params& p) {
             const std::string& name = p.text("phi");
             const auto phi = name == "sin"   ? ProtheroRobinson::Phi::sin
                              : name == "cos" ? ProtheroRobinson::Phi::cos
                                              : ProtheroRobinson::Phi::exp;
             return std::make_unique<ProtheroRobinson>(p.real("lambda"), phi, p.real("y0_offset"));
           }});
  // Classic stiff test problems (Hairer & Wanner II §IV.10; IVP test set of Mazzia &
  // Magherini). Each model's end_time() is the literature end time, used when --t-end is
  // omitted.
  reg.add(
      {.info =
           {.name = "robertson",
            .description =
                "Robertson's chemical kinetics (3 species, stiff); literature end time t = 1e11",
            .source = "Robertson 1966; Hairer & Wanner II §IV.10 (ROBER); IVP test set 'rober'",
            .size = fixed_size},
       .params = {{"k1", P::real, "0.04", "rate constant of A → B", B::non_negative()},
                  {"k2", P::real, "3e7", "rate constant of 2B → B + C", B::non_negative()},
                  {"k3", P::real, "1e4", "rate constant of B + C → A + C", B::non_negative()}},
       .make = [](const Params& p) {
         return std::make_unique<Robertson>(p.real("k1"), p.real("k2"), p.real("k3"));
       }});
  reg.add(
      {.info = {.name = "hires",
                .description =
                    "HIRES plant photomorphogenesis (8 species); literature end time t = 321.8122",
                .source = "Schäfer 1975; Hairer & Wanner II §IV.10 (HIRES); IVP test set 'hires'",
                .size = fixed_size},
       .params = {},
       .make = [](const Params&) { return std::make_unique<Hires>(); }});
  reg.add(
      {.info = {.name = "van_der_pol",
                .description = "van der Pol oscillator, scaled y2' = ((1-y1²)y2 - y1)/ε with ε = "
                               "1/μ² (default) or "
                               "classical y2' = μ(1-y1²)y2 - y1; literature end time t = 2 "
                               "(scaled) or t = 2μ (form=mu)",
                .source =
                    "Hairer & Wanner II §IV.10 (VDPOL, ε = 1e-6); IVP test set 'vdpol' (μ = 1000)",
                .size = fixed_size},
       .params = {{"form",
                   P::text,
                   "scaled",
                   "scaled (time x = t/μ, ε = 1/μ²) or mu (classical)",
                   {"scaled", "mu"}},
                  {"mu", P::real, "1000",
                   "damping parameter μ; the scaled form uses ε = 1/μ² (1000: ε = 1e-6)",
                   B::positive()}},
       .make = [](const Params& p) {
         const auto form =
             p.text("form") == "scaled" ? VanDerPol::Form::scaled : VanDerPol::Form::mu;
         return std::make_unique<VanDerPol>(form, p.real("mu"));
       }});
  reg.add(
      {.info = {.name = "orego",
                .description =
                    "Oregonator (Belousov–Zhabotinskii reaction); literature end time t = 360",
                .source =
                    "Field & Noyes 1974; Hairer & Wanner II §IV.10 (OREGO); IVP test set 'orego'",
                .size = fixed_size},
       .params = {{"s", P::real, "77.27", "time-scale ratio s", B::positive()},
                  {"w", P::real, "0.161", "rate w", B::non_negative()},
                  {"q", P::real, "8.375e-6", "rate q", B::non_negative()}},
       .make = [](const Params& p) {
         return std::make_unique<Orego>(p.real("s"), p.real("w"), p.real("q"));
       }});
  reg.add(
      {.info = {.name = "e5",
                .description =
                    "E5 chemical pyrolysis (4 species, badly scaled); literature end time t = 1e13",
                .source = "Enright, Hull & Lindberg 1975; Hairer & Wanner II §IV.10 (E5)",
                .size = fixed_size},
       .params = {{"a", P::real, "7.89e-10", "rate constant A", B::non_negative()},
                  {"b", P::real, "1.1e7", "rate constant B", B::non_negative()},
                  {"c", P::real, "1.13e3", "rate constant C", B::non_negative()},
                  {"m", P::real, "1e6", "factor M of the M·C y2 y3 rate", B::non_negative()}},
       .make = [](const Params& p) {
         return std::make_unique<E5>(p.real("a"), p.real("b"), p.real("c"), p.real("m"));
       }});
  reg.add({.info = {.name = "pollution",
                    .description = "POLLU air-pollution chemistry (20 species, 25 reactions); "
                                   "literature end time t = 60",
                    .source = "Verwer 1994 (SIAM J. Sci. Comput. 15); IVP test set 'pollu'",
                    .size = fixed_size},
           .params = {},
           .make = [](const Params&) { return std::make_unique<Pollution>(); }});
  reg.add(
      {.info =
           {.name = "kaps",
            .description =
                "Kaps' problem y1' = -(2 + 1/ε) y1 + y2²/ε, y2' = y1 - y2 - y2², exact "
                "(e^{-2t}, e^{-t}) for every ε; split=stiff: the 1/ε terms implicit; end time 1",
            .exact = true,
            .source = "Kaps & Rentrop, Numer. Math. 33 (1979); Hairer & Wanner II §IV.15 (order "
                      "reduction)",
            .size = fixed_size},
       .params = {{"eps", P::real, "1e-6", "stiffness parameter ε", B::positive()},
                  {"split",
                   P::text,
                   "stiff",
                   "additive split f = f_E + f_I: stiff (f_I = the 1/ε terms, f_E the rest)",
                   {"stiff"}}},
       .make = [](const Params& p) {
         p.text("split");  // one split (stiff): nothing to choose
         return std::make_unique<Kaps>(p.real("eps"));
       }});
  reg.add(
      {.info =
           {.name = "advection_diffusion",
            .description =
                "1D periodic u_t + a u_x = ν u_xx - r u on [0,1), central differences on n cells, "
                "initial sin(2πk x); split=advection: advection explicit, diffusion and reaction "
                "implicit; end time 1",
            .exact = true,
            .source =
                "method of lines; exact solution of the ODE e^{μt} sin(θj - ωt) from the circulant "
                "operator's Fourier modes",
            // advection_diffusion: n unknowns, the tridiagonal Jacobian (3n nonzeros of 12 bytes).
            .size =
                [](const Params& p) {
                  const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                  return ModelSize{n, 12.0 * 3.0 * n + 32.0 * n, 3.0 * n,
                                   "n=" + std::to_string(p.integer("n"))};
                }},
       .params = {{"n", P::integer, "256", "cells N (Δx = 1/N)", B::in(3, 10000000)},
                  {"a", P::real, "1", "advection speed a", B::any()},
                  {"nu", P::real, "1e-4", "diffusion coefficient ν", B::non_negative()},
                  {"r", P::real, "0", "reaction (decay) rate r", B::non_negative()},
                  {"k", P::integer, "1", "wave number of the initial mode sin(2πk x)",
                   B::in(0, 1e9)},
                  {"split",
                   P::text,
                   "advection",
                   "additive split f = f_E + f_I: advection (advection explicit; diffusion and "
                   "reaction implicit)",
                   {"advection"}}},
       .make = [](const Params& p) {
         p.text("split");  // one split (advection): nothing to choose
         return std::make_unique<AdvectionDiffusion>(static_cast<int>(p.integer("n")), p.real("a"),
                                                     p.real("nu"), p.real("r"),
                                                     static_cast<int>(p.integer("k")));
       }});
  reg.add(
      {.info =
           {.name = "brusselator",
            .description =
                "1D Brusselator with diffusion: u' = 1 + u²v - 4u + α(N+1)² Δu, v' = 3u - u²v + "
                "α(N+1)² Δv on N interior points, u = 1, v = 3 at both ends, u(0) = 1 + sin(2πx), "
                "v(0) = 3; unknowns interleaved (banded Jacobian); end time 10",
            .source =
                "Hairer, Nørsett & Wanner I §I.16; Hairer & Wanner II §IV.1 (BRUSS, N = 500 in "
                "§IV.10)",
            // brusselator: 2n unknowns, the banded Jacobian (8n - 4 nonzeros of 12 bytes).
            .size =
                [](const Params& p) {
                  const double n = std::max(static_cast<double>(p.integer("n")), 0.0);
                  return ModelSize{2.0 * n, 12.0 * 8.0 * n + 64.0 * n, 8.0 * n,
                                   "n=" + std::to_string(p.integer("n"))};
                }},
       .params = {{"n", P::integer, "32", "interior grid points N (x_i = i/(N+1); 2N unknowns)",
                   B::in(1, 10000000)},
                  {"alpha", P::real, "0.02", "diffusion coefficient α (1/50 in the literature)",
                   B::positive()}},
       .make = [](const Params& p) {
         return std::make_unique<Brusselator>(static_cast<int>(p.integer("n")), p.real("alpha"));
       }});
}

}  // namespace stiffbench
