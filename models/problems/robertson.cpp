#include "models/problems/robertson.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

Robertson::Robertson(double k1, double k2, double k3) : k1_(k1), k2_(k2), k3_(k3) {
  require_input(k1 >= 0, "robertson: parameter 'k1' must be >= 0");
  require_input(k2 >= 0, "robertson: parameter 'k2' must be >= 0");
  require_input(k3 >= 0, "robertson: parameter 'k3' must be >= 0");
}

void Robertson::eval_rhs(double, CVecRef y, VecRef dydt) const {
  // The three reaction rates, each added to one species and subtracted from another, so the
  // components sum to zero up to round-off (the "mass" invariant).
  const double r1 = k1_ * y[0];         // A → B
  const double r2 = k2_ * y[1] * y[1];  // 2B → B + C
  const double r3 = k3_ * y[1] * y[2];  // B + C → A + C
  dydt[0] = -r1 + r3;
  dydt[1] = r1 - r3 - r2;
  dydt[2] = r2;
}

void Robertson::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  // The same 7 entries at every call, zero-valued ones included (y2 = y3 = 0 at t = 0).
  const std::vector<Eigen::Triplet<double>> t{{0, 0, -k1_},
                                              {0, 1, k3_ * y[2]},
                                              {0, 2, k3_ * y[1]},
                                              {1, 0, k1_},
                                              {1, 1, -k3_ * y[2] - 2 * k2_ * y[1]},
                                              {1, 2, -k3_ * y[1]},
                                              {2, 1, 2 * k2_ * y[1]}};
  jac.resize(3, 3);
  jac.setFromTriplets(t.begin(), t.end());
}

std::vector<Invariant> Robertson::invariants() const {
  return {{"mass", [](double, CVecRef y) { return y[0] + y[1] + y[2]; }}};
}

std::optional<double> Robertson::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

}  // namespace stiffbench

namespace stiffbench {

std::optional<OdeSystem::PublishedSolution> Robertson::published_solution() const {
  if (k1_ != 0.04 || k2_ != 3e7 || k3_ != 1e4) return std::nullopt;
  // IVP test set "rober" at t = 1e11 (the values in robertson.hpp).
  return PublishedSolution{
      1e11, Vec{{0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050e+00}},
      "IVP test set (Mazzia & Magherini), problem rober"};
}

ModelRegistry::Entry robertson_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "robertson",
               .description =
                   "Robertson's chemical kinetics (3 species, stiff); literature end time t = 1e11",
               .source = "Robertson 1966; Hairer & Wanner II §IV.10 (ROBER); IVP test set 'rober'",
               .size = fixed_problem_size},
      .params = {{"k1", P::real, "0.04", "rate constant of A → B", B::non_negative()},
                 {"k2", P::real, "3e7", "rate constant of 2B → B + C", B::non_negative()},
                 {"k3", P::real, "1e4", "rate constant of B + C → A + C", B::non_negative()}},
      .make = [](const Params& p) {
        return std::make_unique<Robertson>(p.real("k1"), p.real("k2"), p.real("k3"));
      }};
}

}  // namespace stiffbench
