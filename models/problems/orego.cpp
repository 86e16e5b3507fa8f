#include "models/problems/orego.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

Orego::Orego(double s, double w, double q) : s_(s), w_(w), q_(q) {
  require_input(s > 0, "orego: parameter 's' must be > 0");
  require_input(w >= 0, "orego: parameter 'w' must be >= 0");
  require_input(q >= 0, "orego: parameter 'q' must be >= 0");
}

void Orego::eval_rhs(double, CVecRef y, VecRef dydt) const {
  dydt[0] = s_ * (y[1] + y[0] * (1 - q_ * y[0] - y[1]));
  dydt[1] = (y[2] - (1 + y[0]) * y[1]) / s_;
  dydt[2] = w_ * (y[0] - y[2]);
}

void Orego::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  const std::vector<Eigen::Triplet<double>> t{{0, 0, s_ * (1 - 2 * q_ * y[0] - y[1])},
                                              {0, 1, s_ * (1 - y[0])},
                                              {1, 0, -y[1] / s_},
                                              {1, 1, -(1 + y[0]) / s_},
                                              {1, 2, 1 / s_},
                                              {2, 0, w_},
                                              {2, 2, -w_}};
  jac.resize(3, 3);
  jac.setFromTriplets(t.begin(), t.end());
}

std::optional<double> Orego::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

}  // namespace stiffbench

namespace stiffbench {

std::optional<OdeSystem::PublishedSolution> Orego::published_solution() const {
  // Hairer & Wanner; IVP test set "orego" at t = 360 (the values in orego.hpp).
  return PublishedSolution{
      360.0, Vec{{0.1000814870318523e+01, 0.1228178521549917e+04, 0.1320554942846706e+03}},
      "IVP test set (Mazzia & Magherini), problem orego"};
}

ModelRegistry::Entry orego_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "orego",
               .description =
                   "Oregonator (Belousov–Zhabotinskii reaction); literature end time t = 360",
               .source =
                   "Field & Noyes 1974; Hairer & Wanner II §IV.10 (OREGO); IVP test set 'orego'",
               .size = fixed_problem_size},
      .params = {{"s", P::real, "77.27", "time-scale ratio s", B::positive()},
                 {"w", P::real, "0.161", "rate w", B::non_negative()},
                 {"q", P::real, "8.375e-6", "rate q", B::non_negative()}},
      .make = [](const Params& p) {
        return std::make_unique<Orego>(p.real("s"), p.real("w"), p.real("q"));
      }};
}

}  // namespace stiffbench
