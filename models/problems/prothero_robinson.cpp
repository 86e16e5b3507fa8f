#include "models/problems/prothero_robinson.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

double ProtheroRobinson::phi(double t) const {
  switch (phi_) {
    case Phi::sin:
      return std::sin(t);
    case Phi::cos:
      return std::cos(t);
    case Phi::exp:
      return std::exp(t);
  }
  return 0;
}

double ProtheroRobinson::phi_dot(double t) const {
  switch (phi_) {
    case Phi::sin:
      return std::cos(t);
    case Phi::cos:
      return -std::sin(t);
    case Phi::exp:
      return std::exp(t);
  }
  return 0;
}

void ProtheroRobinson::eval_rhs(double t, CVecRef y, VecRef dydt) const {
  dydt[0] = lambda_ * (y[0] - phi(t)) + phi_dot(t);
}

void ProtheroRobinson::eval_jacobian(double, CVecRef, SparseMat& jac) const {
  jac.resize(1, 1);
  jac.setZero();
  jac.insert(0, 0) = lambda_;
}

std::optional<SplitInfo> ProtheroRobinson::imex_split() const {
  return SplitInfo{"stiff", "φ'(t) (independent of y)", "λ(y - φ(t)) (the stiff term)"};
}

void ProtheroRobinson::exact(double t, VecRef y) const {
  y[0] = phi(t) + offset_ * std::exp(lambda_ * t);
}

ModelRegistry::Entry prothero_robinson_entry() {
  using P = ParamType;
  using B = Bounds;
  return {.info = {.name = "prothero_robinson",
                   .description = "y' = λ(y - φ(t)) + φ'(t): stiffness knob λ, exact y = φ",
                   .exact = true,
                   .source = "Prothero & Robinson, Math. Comp. 28 (1974)",
                   .size = fixed_problem_size},
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
          }};
}

}  // namespace stiffbench
