#include "integrators/register.hpp"

#include <utility>
#include <vector>

#include "integrators/fluid/stable_fluids.hpp"
#include "integrators/graphics/projective_dynamics.hpp"
#include "integrators/graphics/xpbd.hpp"
#include "integrators/implicit/baraff_witkin.hpp"
#include "integrators/implicit/bdf2.hpp"
#include "integrators/implicit/dirk.hpp"
#include "integrators/implicit/rosenbrock.hpp"
#include "integrators/method_entry.hpp"
#include "integrators/method_file.hpp"
#include "integrators/reference/gsl.hpp"
#include "integrators/reference/sundials.hpp"
#include "integrators/splitting/operator_splitting.hpp"
#include "integrators/symplectic/rattle.hpp"
#include "integrators/symplectic/verlet.hpp"

namespace stiffbench {

namespace {

// Registers the built-in method files of `kind` (methods/*.toml, built_in_methods(): in file
// name order) with the MethodInfo, parameters and factory of method_registry_entry().
void add_methods(IntegratorRegistry& reg, MethodKind kind) {
  for (const MethodDefinition& m : built_in_methods())
    if (m.kind == kind) add_built_in_integrator(reg, method_registry_entry(m));
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

// Explicit Runge-Kutta methods from their files; the embedded pairs run fixed-step with --h or
// adaptively with rtol/atol (integrators/adaptive/).
void register_explicit_integrators(IntegratorRegistry& reg) {
  add_methods(reg, MethodKind::explicit_rk);
}

void register_symplectic_integrators(IntegratorRegistry& reg) {
  // Kick/drift methods and compositions of velocity Verlet from their files (kick_drift.hpp,
  // composition.hpp).
  add_methods(reg, MethodKind::kick_drift);
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
  // DIRK methods from their files (dirk.hpp); the ESDIRK pairs with an embedded estimate run
  // fixed-step with --h or adaptively with rtol/atol.
  add_methods(reg, MethodKind::dirk);
  add_class(reg, Bdf2Integrator({}), newton_specs, [](const Params& p) {
    return std::make_unique<Bdf2Integrator>(read_implicit_options(p, true));
  });
  add_class(reg, SemiImplicitEuler({}), linear_specs, [](const Params& p) {
    return std::make_unique<SemiImplicitEuler>(read_implicit_options(p, false));
  });
  // Rosenbrock methods from their files (rosenbrock.hpp); the pairs with an embedded
  // estimate run fixed-step with --h or adaptively with rtol/atol.
  add_methods(reg, MethodKind::rosenbrock);
  // Fully implicit RK from their files: Gauss-Legendre collocation (ImplicitRungeKutta, fixed
  // step, gauss.hpp) and Radau IIA run by RADAU5 (solver = "radau5", radau5.hpp).
  add_methods(reg, MethodKind::irk);
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
  // Additive (IMEX) Runge-Kutta methods from their files (Family::imex, integrators/imex/
  // imex_ark.hpp): split models only; their implicit stages take the implicit family's Newton and
  // linear-solver parameters.
  add_methods(reg, MethodKind::imex_ark);
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
  // lie and strang on a model's additive split (integrators/splitting/operator_splitting.hpp).
  register_splitting_integrators(reg);
}

void register_reference_integrators(IntegratorRegistry& reg) {
  register_sundials_integrators(reg);
  register_gsl_integrators(reg);
}

}  // namespace stiffbench
