#include "integrators/register.hpp"

#include <utility>
#include <vector>

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
#include "integrators/method_entry.hpp"
#include "integrators/reference/gsl.hpp"
#include "integrators/reference/sundials.hpp"
#include "integrators/symplectic/composition.hpp"
#include "integrators/symplectic/kick_drift.hpp"
#include "integrators/symplectic/rattle.hpp"
#include "integrators/symplectic/verlet.hpp"

namespace stiffbench {

namespace {

// Registers `entry` with the MethodInfo of `probe` (an instance made from the entry) plus the
// entry's description, kind and reference.
template <class Entry, class Make>
void add_method(IntegratorRegistry& reg, const Entry& entry, const Integrator& probe,
                std::vector<ParamSpec> specs, Make make) {
  add_built_in_integrator(reg,
                          {with_text(probe.info(), entry.text), std::move(specs), std::move(make)});
}

// Registers a method implemented as a class with the MethodInfo of `probe`, which its
// constructor builds with its description, kind and reference (method_info() and the class's
// MethodText, next to the constructor).
template <class Make>
void add_class(IntegratorRegistry& reg, const Integrator& probe, std::vector<ParamSpec> specs,
               Make make) {
  add_built_in_integrator(reg, {probe.info(), std::move(specs), std::move(make)});
}

}  // namespace

// Explicit Runge-Kutta methods from their table (integrators/explicit/tableaux.hpp); the
// embedded pairs run fixed-step with --h or adaptively with rtol/atol (integrators/adaptive/).
void register_explicit_integrators(IntegratorRegistry& reg) {
  for (const ExplicitRkMethod& m : explicit_rk_methods()) {
    const ButcherTableau& t = *m.coefficients;
    const std::string desc = m.text.description.str();
    if (!m.adaptive()) {
      auto make = [t, desc](const Params&) {
        return std::make_unique<ExplicitRungeKutta>(t, desc);
      };
      add_method(reg, m, ExplicitRungeKutta(t, desc), {}, make);
    } else {
      auto make = [t, desc](const Params& p) {
        return std::make_unique<EmbeddedRungeKutta>(t, desc, read_controller_options(p));
      };
      add_method(reg, m, EmbeddedRungeKutta(t, desc, {}), controller_param_specs(), make);
    }
  }
}

void register_symplectic_integrators(IntegratorRegistry& reg) {
  for (const KickDriftMethod& m : kick_drift_methods()) {
    const KickDriftScheme& c = *m.coefficients;
    const std::string desc = m.text.description.str();
    auto make = [c, desc](const Params&) {
      return std::make_unique<KickDriftIntegrator>(c.kick_drift, c.velocity_independent, desc);
    };
    add_method(reg, m, KickDriftIntegrator(c.kick_drift, c.velocity_independent, desc), {}, make);
  }
  // Compositions of velocity Verlet (composition.hpp): velocity-independent forces only.
  for (const CompositionEntry& m : composition_entries()) {
    auto make = [c = m.coefficients->kick_drift, desc = m.text.description.str()](const Params&) {
      return std::make_unique<KickDriftIntegrator>(c, true, desc);
    };
    add_method(reg, m,
               KickDriftIntegrator(m.coefficients->kick_drift, true, m.text.description.str()), {},
               make);
  }
  add_class(reg, PositionVerlet(), {},
            [](const Params&) { return std::make_unique<PositionVerlet>(); });
  add_class(reg, Leapfrog(), {}, [](const Params&) { return std::make_unique<Leapfrog>(); });
  // RATTLE: constrained systems only (holonomic_constraints(), core/constraints.hpp).
  add_class(reg, Rattle({}), rattle_param_specs(),
            [](const Params& p) { return std::make_unique<Rattle>(read_rattle_options(p)); });
}

void register_implicit_integrators(IntegratorRegistry& reg) {
  const auto newton_specs = implicit_param_specs(true);
  const auto linear_specs = implicit_param_specs(false);
  // DIRK methods (dirk.hpp); the ESDIRK pairs with an embedded estimate run fixed-step with --h
  // or adaptively with rtol/atol.
  const auto esdirk_specs = esdirk_param_specs();
  for (const DirkMethod& m : dirk_methods()) {
    const ButcherTableau& t = *m.coefficients;
    const std::string desc = m.text.description.str();
    if (!m.adaptive()) {
      auto make = [t, desc](const Params& p) {
        return std::make_unique<DirkIntegrator>(t, desc, read_implicit_options(p, true));
      };
      add_method(reg, m, DirkIntegrator(t, desc, {}), newton_specs, make);
    } else {
      auto make = [t, desc](const Params& p) {
        return std::make_unique<DirkIntegrator>(t, desc, read_implicit_options(p, true),
                                                read_controller_options(p), read_error_filter(p));
      };
      add_method(reg, m, DirkIntegrator(t, desc, {}), esdirk_specs, make);
    }
  }
  add_class(reg, Bdf2Integrator({}), newton_specs, [](const Params& p) {
    return std::make_unique<Bdf2Integrator>(read_implicit_options(p, true));
  });
  add_class(reg, SemiImplicitEuler({}), linear_specs, [](const Params& p) {
    return std::make_unique<SemiImplicitEuler>(read_implicit_options(p, false));
  });
  // Rosenbrock methods (linearly_implicit.hpp); the pairs with an embedded estimate run
  // fixed-step with --h or adaptively with rtol/atol.
  std::vector<ParamSpec> ros_adaptive_specs = controller_param_specs();
  ros_adaptive_specs.insert(ros_adaptive_specs.end(), linear_specs.begin(), linear_specs.end());
  for (const RosenbrockMethod& m : rosenbrock_methods()) {
    const RosenbrockTableau* tab = &*m.coefficients;
    const std::string desc = m.text.description.str();
    if (!m.adaptive()) {
      auto make = [tab, desc](const Params& p) {
        return std::make_unique<Rosenbrock>(*tab, desc, read_implicit_options(p, false));
      };
      add_method(reg, m, Rosenbrock(*tab, desc, {}), linear_specs, make);
    } else {
      auto make = [tab, desc](const Params& p) {
        return std::make_unique<Rosenbrock>(*tab, desc, read_implicit_options(p, false),
                                            read_controller_options(p));
      };
      add_method(reg, m, Rosenbrock(*tab, desc, {}), ros_adaptive_specs, make);
    }
  }
  add_class(reg, Radau5({}), radau5_param_specs(),
            [](const Params& p) { return std::make_unique<Radau5>(read_radau5_options(p)); });
  // Fully implicit RK from a tableau (gauss.hpp): Gauss-Legendre collocation, fixed step.
  for (const GaussMethod& m : gauss_methods()) {
    const ButcherTableau& t = *m.coefficients;
    const std::string desc = m.text.description.str();
    auto make = [t, desc](const Params& p) {
      return std::make_unique<ImplicitRungeKutta>(t, desc, read_gauss_options(p));
    };
    add_method(reg, m, ImplicitRungeKutta(t, desc, {}), gauss_param_specs(), make);
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
  add_class(reg, BaraffWitkin({}), bw_specs, [](const Params& p) {
    return std::make_unique<BaraffWitkin>(read_implicit_options(p, false));
  });
}

// The graphics community's solvers for stiff springs (integrators/graphics/): they work on the
// system's springs and refuse models that do not list them.
void register_graphics_integrators(IntegratorRegistry& reg) {
  add_class(reg, Xpbd({}), xpbd_param_specs(),
            [](const Params& p) { return std::make_unique<Xpbd>(read_xpbd_options(p)); });
  add_class(reg, ProjectiveDynamics({}), projective_dynamics_param_specs(), [](const Params& p) {
    return std::make_unique<ProjectiveDynamics>(read_projective_dynamics_options(p));
  });
}

void register_operator_splitting_integrators(IntegratorRegistry& reg) {
  add_class(reg, StableFluids(), {},
            [](const Params&) { return std::make_unique<StableFluids>(); });
}

void register_reference_integrators(IntegratorRegistry& reg) {
  register_sundials_integrators(reg);
  register_gsl_integrators(reg);
}

}  // namespace stiffbench
