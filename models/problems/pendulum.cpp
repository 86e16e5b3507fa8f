#include "models/problems/pendulum.hpp"

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

}  // namespace stiffbench
