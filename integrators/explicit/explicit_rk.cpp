#include "integrators/explicit/explicit_rk.hpp"

namespace stiffbench {

ExplicitRungeKutta::ExplicitRungeKutta(ButcherTableau tableau, std::string description)
    : Integrator({tableau.name,
                  Family::explicit_rk,
                  tableau.order,
                  tableau.stages(),
                  {},
                  std::move(description)}),
      tableau_(std::move(tableau)) {
  if (!tableau_.is_explicit())
    throw std::logic_error("tableau '" + tableau_.name + "' is not explicit");
}

void ExplicitRungeKutta::reset(const OdeSystem& sys, double, CVecRef) {
  check_compatible(info(), sys);
  k_.resize(sys.dimension(), tableau_.stages());
  ytmp_.resize(sys.dimension());
}

Status ExplicitRungeKutta::step(const OdeSystem& sys, double t, VecRef y, double h, SolveStats&) {
  const int s = tableau_.stages();
  for (int i = 0; i < s; ++i) {
    ytmp_ = y;
    for (int j = 0; j < i; ++j)
      if (const double aij = tableau_.a(i, j); aij != 0.0) ytmp_.noalias() += (h * aij) * k_.col(j);
    sys.rhs(t + tableau_.c[i] * h, ytmp_, k_.col(i));
  }
  for (int i = 0; i < s; ++i)
    if (const double bi = tableau_.b[i]; bi != 0.0) y.noalias() += (h * bi) * k_.col(i);
  return Status::ok;
}

}  // namespace stiffbench
