#include "integrators/register.hpp"

#include <map>

#include "integrators/adaptive/embedded_rk.hpp"
#include "integrators/explicit/explicit_rk.hpp"
#include "integrators/explicit/tableaux.hpp"
#include "integrators/fluid/stable_fluids.hpp"
#include "integrators/graphics/projective_dynamics.hpp"
#include "integrators/graphics/xpbd.hpp"
#include "integrators/implicit/baraff_witkin.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/gauss.hpp"
#include "integrators/implicit/linearly_implicit.hpp"
#include "integrators/implicit/radau5.hpp"
#include "integrators/reference/gsl.hpp"
#include "integrators/reference/sundials.hpp"
#include "integrators/symplectic/composition.hpp"
#include "integrators/symplectic/rattle.hpp"
#include "integrators/symplectic/splitting.hpp"
#include "integrators/symplectic/verlet.hpp"

namespace stiffbench {

void register_explicit_integrators(IntegratorRegistry& reg) {
  static const std::map<std::string, std::string> descriptions = {
      {"euler", "explicit (forward) Euler"},
      {"heun", "Heun's method (explicit trapezoidal rule)"},
      {"midpoint", "explicit midpoint rule"},
      {"ralston", "Ralston's second-order method (minimum error bound)"},
      {"kutta3", "Kutta's third-order method"},
      {"ssprk3", "strong-stability-preserving RK3 (Shu-Osher)"},
      {"rk4", "classic fourth-order Runge-Kutta"},
      {"rk38", "Kutta's 3/8-rule fourth-order method"},
  };
  for (const ButcherTableau& t : explicit_tableaux()) {
    const std::string desc = descriptions.at(t.name);
    auto make = [t, desc](const Params&) { return std::make_unique<ExplicitRungeKutta>(t, desc); };
    const MethodInfo info = ExplicitRungeKutta(t, desc).info();
    reg.add({info, {}, make});
  }
  // Embedded pairs: fixed-step with --h, adaptive with rtol/atol (integrators/adaptive/).
  static const std::map<std::string, std::string> embedded = {
      {"bs3", "Bogacki-Shampine 3(2) embedded pair, FSAL; adaptive or fixed step"},
      {"dopri5", "Dormand-Prince 5(4) embedded pair, FSAL; adaptive or fixed step"},
      {"cash_karp", "Cash-Karp 5(4) embedded pair, fifth-order solution; adaptive or fixed step"},
      {"rkf45", "Runge-Kutta-Fehlberg 4(5), fourth-order solution; adaptive or fixed step"},
  };
  for (const ButcherTableau& t : embedded_tableaux()) {
    const std::string desc = embedded.at(t.name);
    auto make = [t, desc](const Params& p) {
      return std::make_unique<EmbeddedRungeKutta>(t, desc, read_controller_options(p));
    };
    reg.add({EmbeddedRungeKutta(t, desc, {}).info(), controller_param_specs(), make});
  }
}

void register_symplectic_integrators(IntegratorRegistry& reg) {
  static const std::map<std::string, std::pair<bool, std::string>> props = {
      {"symplectic_euler",
       {false, "symplectic Euler, velocity first: v+ = v + h a(t, x, v), x+ = x + h v+"}},
      {"symplectic_euler_x",
       {false, "symplectic Euler, position first: x+ = x + h v, v+ = v + h a(t+h, x+, v)"}},
      {"velocity_verlet", {true, "velocity Verlet (kick-drift-kick), first-same-as-last"}},
  };
  for (const SplittingCoefficients& c : splitting_methods()) {
    const auto& [vel_indep, desc] = props.at(c.name);
    auto make = [c, vel_indep = vel_indep, desc = desc](const Params&) {
      return std::make_unique<SplittingIntegrator>(c, vel_indep, desc);
    };
    reg.add({SplittingIntegrator(c, vel_indep, desc).info(), {}, make});
  }
  // Compositions of velocity Verlet (composition.hpp): velocity-independent forces only.
  for (const CompositionMethod& m : composition_methods()) {
    auto make = [c = m.splitting, desc = m.description](const Params&) {
      return std::make_unique<SplittingIntegrator>(c, true, desc);
    };
    reg.add({SplittingIntegrator(m.splitting, true, m.description).info(), {}, make});
  }
  reg.add({PositionVerlet().info(), {}, [](const Params&) {
             return std::make_unique<PositionVerlet>();
           }});
  reg.add({Leapfrog().info(), {}, [](const Params&) { return std::make_unique<Leapfrog>(); }});
  // RATTLE: constrained systems only (holonomic_constraints(), core/constraints.hpp).
  reg.add({Rattle({}).info(), rattle_param_specs(),
           [](const Params& p) { return std::make_unique<Rattle>(read_rattle_options(p)); }});
}

void register_implicit_integrators(IntegratorRegistry& reg) {
  static const std::map<std::string, std::string> descriptions = {
      {"backward_euler", "backward (implicit) Euler with Newton; L-stable"},
      {"implicit_midpoint", "implicit midpoint rule; A-stable, symplectic, no damping"},
      {"trapezoidal", "trapezoidal rule (Crank-Nicolson); A-stable, no damping at infinity"},
      {"sdirk2", "two-stage SDIRK, gamma = 1 - 1/sqrt(2); L-stable, stiffly accurate"},
      {"sdirk3", "three-stage SDIRK of Alexander (1977); L-stable, stiffly accurate"},
  };
  const auto newton_specs = implicit_param_specs(true);
  const auto linear_specs = implicit_param_specs(false);
  for (const ButcherTableau& t : implicit_tableaux()) {
    const std::string desc = descriptions.at(t.name);
    auto make = [t, desc](const Params& p) {
      return std::make_unique<DirkIntegrator>(t, desc, read_implicit_options(p, true));
    };
    reg.add({DirkIntegrator(t, desc, {}).info(), newton_specs, make});
  }
  // ESDIRK pairs with an embedded estimate: fixed step with --h, adaptive with rtol/atol.
  static const std::map<std::string, std::string> esdirk = {
      {"trbdf2",
       "TR-BDF2 (Bank et al. 1985, IEEE Trans. CAD 4; as an ESDIRK 2(3) pair after Hosea & "
       "Shampine 1996, Appl. Numer. Math. 20), gamma = 2 - sqrt(2); L-stable, stiffly "
       "accurate, FSAL; adaptive or fixed step"},
      {"esdirk43",
       "ESDIRK4(3)6L[2]SA, implicit part of ARK4(3)6L[2]SA (Kennedy & Carpenter 2003, Appl. "
       "Numer. Math. 44), gamma = 1/4; L-stable, stiffly accurate, FSAL; adaptive or fixed step"},
  };
  const auto esdirk_specs = esdirk_param_specs();
  for (const ButcherTableau& t : esdirk_tableaux()) {
    const std::string desc = esdirk.at(t.name);
    auto make = [t, desc](const Params& p) {
      return std::make_unique<DirkIntegrator>(t, desc, read_implicit_options(p, true),
                                              read_controller_options(p), read_error_filter(p));
    };
    reg.add({DirkIntegrator(t, desc, {}).info(), esdirk_specs, make});
  }
  reg.add({Bdf2Integrator({}).info(), newton_specs, [](const Params& p) {
             return std::make_unique<Bdf2Integrator>(read_implicit_options(p, true));
           }});
  reg.add({SemiImplicitEuler({}).info(), linear_specs, [](const Params& p) {
             return std::make_unique<SemiImplicitEuler>(read_implicit_options(p, false));
           }});
  const std::string ros_desc =
      "ROS2 Rosenbrock method (Verwer et al. 1999), gamma = 1 + 1/sqrt(2); L-stable";
  reg.add({Rosenbrock(rosenbrock2_tableau(), ros_desc, {}).info(), linear_specs,
           [ros_desc](const Params& p) {
             return std::make_unique<Rosenbrock>(rosenbrock2_tableau(), ros_desc,
                                                 read_implicit_options(p, false));
           }});
  // Rosenbrock pairs with an embedded estimate: fixed-step with --h, adaptive with rtol/atol.
  std::vector<ParamSpec> ros_adaptive_specs = controller_param_specs();
  ros_adaptive_specs.insert(ros_adaptive_specs.end(), linear_specs.begin(), linear_specs.end());
  const std::vector<std::pair<const RosenbrockTableau*, std::string>> ros_pairs = {
      {&ros3p_tableau(),
       "ROS3P Rosenbrock 3(2) of Lang & Verwer (BIT 41, 2001): 3 stages (2 f evaluations), "
       "gamma = 1/2 + sqrt(3)/6, A-stable, R(inf) = 1 - sqrt(3); adaptive (rtol/atol) or fixed "
       "step. Its error estimate is zero on linear autonomous problems (the embedded method has "
       "the same stability function): there only h_max limits the adaptive step"},
      {&rodas4_tableau(),
       "RODAS4 Rosenbrock 4(3) of Hairer & Wanner (Solving ODEs II, 2nd ed., Springer 1996; "
       "code RODAS): 6 stages, gamma = 1/4, L-stable, stiffly accurate; adaptive (rtol/atol) "
       "or fixed step"},
  };
  for (const auto& [tab, desc] : ros_pairs) {
    auto make = [tab = tab, desc = desc](const Params& p) {
      return std::make_unique<Rosenbrock>(*tab, desc, read_implicit_options(p, false),
                                          read_controller_options(p));
    };
    reg.add({Rosenbrock(*tab, desc, {}).info(), ros_adaptive_specs, make});
  }
  reg.add({Radau5({}).info(), radau5_param_specs(),
           [](const Params& p) { return std::make_unique<Radau5>(read_radau5_options(p)); }});
  for (const int s : {2, 3}) {
    reg.add({GaussCollocation(s, {}).info(), gauss_param_specs(), [s](const Params& p) {
               return std::make_unique<GaussCollocation>(s, read_gauss_options(p));
             }});
  }
  // Baraff–Witkin is velocity-form by construction (no `form`), and its single Krylov solve
  // defaults to a relative 1e-6 (baraff_witkin.hpp).
  std::vector<ParamSpec> bw_specs;
  for (ParamSpec s : linear_specs) {
    if (s.key == "system_form") continue;
    if (s.key == "linear_solver")
      s.help =
          "auto (ldlt up to 2000 dofs, cg above for symmetric force Jacobians; "
          "dense_lu/sparse_lu otherwise), dense_lu, sparse_lu, ldlt, cg, bicgstab, gmres";
    if (s.key == "krylov_tol") {
      s.default_value = "1e-6";
      s.help =
          "relative residual of the Krylov solve (warm-started from the previous step's "
          "dv); 1e-6 keeps the solve error far below the method's O(h) error";
    }
    bw_specs.push_back(s);
  }
  reg.add({BaraffWitkin({}).info(), bw_specs, [](const Params& p) {
             return std::make_unique<BaraffWitkin>(read_implicit_options(p, false));
           }});
}

// The graphics community's solvers for stiff springs (integrators/graphics/): they work on the
// system's springs and refuse models that do not list them.
void register_graphics_integrators(IntegratorRegistry& reg) {
  reg.add({Xpbd({}).info(), xpbd_param_specs(),
           [](const Params& p) { return std::make_unique<Xpbd>(read_xpbd_options(p)); }});
  reg.add({ProjectiveDynamics({}).info(), projective_dynamics_param_specs(), [](const Params& p) {
             return std::make_unique<ProjectiveDynamics>(read_projective_dynamics_options(p));
           }});
}

void register_splitting_integrators(IntegratorRegistry& reg) {
  reg.add(
      {StableFluids().info(), {}, [](const Params&) { return std::make_unique<StableFluids>(); }});
}

void register_reference_integrators(IntegratorRegistry& reg) {
  register_sundials_integrators(reg);
  register_gsl_integrators(reg);
}

}  // namespace stiffbench
