#include "core/integrator.hpp"

#include "core/springs.hpp"

namespace stiffbench {

std::string to_string(Family f) {
  switch (f) {
    case Family::explicit_rk:
      return "explicit";
    case Family::implicit:
      return "implicit";
    case Family::symplectic:
      return "symplectic";
    case Family::operator_splitting:
      return "splitting";
    case Family::imex:
      return "imex";
    case Family::reference:
      return "reference";
    case Family::graphics:
      return "graphics";
  }
  return "?";
}

std::string describe_requirements(const Requirements& r) {
  std::vector<std::string> parts;
  if (r.mechanical) parts.emplace_back("mechanical system");
  if (r.velocity_independent) parts.emplace_back("velocity-independent acceleration");
  if (r.jacobian) parts.emplace_back("Jacobian");
  if (r.constraints) parts.emplace_back("holonomic constraints");
  if (r.spring_network) parts.emplace_back("spring network");
  if (r.grid_fluid) parts.emplace_back("grid fluid operators (fluid_2d)");
  if (r.split) parts.emplace_back("additive split f = f_E + f_I");
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? ", " : "") + parts[i];
  return out.empty() ? "-" : out;
}

Status Integrator::advance_to(const OdeSystem&, double, VecRef, SolveStats&) {
  throw BadInput("integrator '" + info_.name + "' has no adaptive mode: give --h");
}

void check_compatible(const MethodInfo& info, const OdeSystem& sys) {
  const std::string who = "integrator '" + info.name + "'";
  const MechanicalSystem* mech = sys.as_mechanical();
  if (info.requires_.mechanical && !mech) {
    throw BadInput(who + " needs a mechanical system (y = [x; v]); model '" + sys.name() +
                   "' is not one");
  }
  if (info.requires_.velocity_independent && mech && mech->velocity_dependent()) {
    throw BadInput(
        who + " needs an acceleration that does not depend on velocity; model '" + sys.name() +
        "' has velocity-dependent forces (damping, drag or viscosity): use symplectic_euler "
        "or a general method");
  }
  if (info.requires_.jacobian && !sys.has_jacobian()) {
    throw BadInput(who + " needs an analytic Jacobian; model '" + sys.name() + "' has none");
  }
  if (info.requires_.constraints && !(mech && mech->holonomic_constraints())) {
    throw BadInput(who +
                   " needs holonomic constraints g(x) = 0 (a constrained mechanical system, "
                   "e.g. pendulum_chain with constrained=true); model '" +
                   sys.name() + "' offers none");
  }
  if (info.requires_.spring_network && !sys.spring_network()) {
    throw BadInput(who +
                   " needs a spring network (a mass-spring model listing its springs, "
                   "e.g. cloth, spring_chain, soft_cube, pendulum_chain); model '" +
                   sys.name() + "' is not one");
  }
  if (info.requires_.spring_network && !sys.spring_network()->other_forces.empty()) {
    throw BadInput(who + " works on a network's springs, gravity and point damping alone; model '" +
                   sys.name() + "' also has " + sys.spring_network()->other_forces);
  }
  if (info.requires_.grid_fluid && !sys.as_grid_fluid()) {
    throw BadInput(who +
                   " runs only on grid fluid models (fluid_2d): it composes their "
                   "advection, diffusion and projection operators; model '" +
                   sys.name() + "' has none");
  }
  if (info.requires_.split && !sys.has_imex_split()) {
    throw BadInput(who +
                   " needs a model with an additive split f = f_E + f_I (e.g. kaps, "
                   "advection_diffusion, or cloth with split=springs; `stiffbench describe MODEL` "
                   "names a model's splits); model '" +
                   sys.name() + "' has none");
  }
}

}  // namespace stiffbench
