#include "models/problems/pendulum.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

void Pendulum::eval_acceleration(double, CVecRef x, CVecRef, VecRef a) const {
  a[0] = -(g_ / length_) * std::sin(x[0]);
}

void Pendulum::stiffness_block(double, CVecRef x, CVecRef, SparseMat& k) const {
  k.resize(1, 1);
  k.setZero();
  k.insert(0, 0) = -(g_ / length_) * std::cos(x[0]);
}

void Pendulum::damping_block(double, CVecRef, CVecRef, SparseMat& d) const {
  d.resize(1, 1);
  d.setZero();
}

std::vector<Invariant> Pendulum::invariants() const {
  return {{"energy", [this](double, CVecRef y) {
             return 0.5 * length_ * length_ * y[1] * y[1] + g_ * length_ * (1 - std::cos(y[0]));
           }}};
}

std::optional<double> Pendulum::stiffness(double, CVecRef y) const {
  return std::sqrt(g_ / length_ * std::abs(std::cos(y[0])));
}

ModelRegistry::Entry pendulum_entry() {
  using P = ParamType;
  using B = Bounds;
  return {.info = {.name = "pendulum",
                   .description = "nonlinear pendulum θ'' = -(g/L) sin θ",
                   .mechanical = true,
                   .source = "no closed form used; convergence needs --reference",
                   .size = fixed_problem_size},
          .params = {{"g", P::real, "1", "gravitational acceleration", B::positive()},
                     {"length", P::real, "1", "pendulum length L", B::positive()},
                     {"theta0", P::real, "1", "initial angle (rad)", B::any()},
                     {"omega0", P::real, "0", "initial angular velocity (rad/s)", B::any()}},
          .make = [](const Params& p) {
            return std::make_unique<Pendulum>(p.real("g"), p.real("length"), p.real("theta0"),
                                              p.real("omega0"));
          }};
}

}  // namespace stiffbench
