#include "models/problems/e5.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

E5::E5(double a, double b, double c, double m) : a_(a), b_(b), c_(c), m_(m) {
  require_input(a >= 0, "e5: parameter 'a' must be >= 0");
  require_input(b >= 0, "e5: parameter 'b' must be >= 0");
  require_input(c >= 0, "e5: parameter 'c' must be >= 0");
  require_input(m >= 0, "e5: parameter 'm' must be >= 0");
}

void E5::eval_rhs(double, CVecRef y, VecRef dydt) const {
  // The four reaction rates, shared so that y2' - y3' - y4' = 0 to round-off.
  const double ra = a_ * y[0];              // A y1
  const double rb = b_ * y[0] * y[2];       // B y1 y3
  const double rm = m_ * c_ * y[1] * y[2];  // M C y2 y3
  const double rc = c_ * y[3];              // C y4
  dydt[0] = -ra - rb;
  dydt[1] = ra - rm;
  dydt[2] = ra - rb - rm + rc;
  dydt[3] = rb - rc;
}

void E5::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  const double mc = m_ * c_;
  const std::vector<Eigen::Triplet<double>> t{{0, 0, -a_ - b_ * y[2]},
                                              {0, 2, -b_ * y[0]},
                                              {1, 0, a_},
                                              {1, 1, -mc * y[2]},
                                              {1, 2, -mc * y[1]},
                                              {2, 0, a_ - b_ * y[2]},
                                              {2, 1, -mc * y[2]},
                                              {2, 2, -b_ * y[0] - mc * y[1]},
                                              {2, 3, c_},
                                              {3, 0, b_ * y[2]},
                                              {3, 2, b_ * y[0]},
                                              {3, 3, -c_}};
  jac.resize(4, 4);
  jac.setFromTriplets(t.begin(), t.end());
}

std::vector<Invariant> E5::invariants() const {
  return {{"y2-y3-y4", [](double, CVecRef y) { return y[1] - y[2] - y[3]; }}};
}

std::optional<double> E5::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

ModelRegistry::Entry e5_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "e5",
               .description =
                   "E5 chemical pyrolysis (4 species, badly scaled); literature end time t = 1e13",
               .source = "Enright, Hull & Lindberg 1975; Hairer & Wanner II §IV.10 (E5)",
               .size = fixed_problem_size},
      .params = {{"a", P::real, "7.89e-10", "rate constant A", B::non_negative()},
                 {"b", P::real, "1.1e7", "rate constant B", B::non_negative()},
                 {"c", P::real, "1.13e3", "rate constant C", B::non_negative()},
                 {"m", P::real, "1e6", "factor M of the M·C y2 y3 rate", B::non_negative()}},
      .make = [](const Params& p) {
        return std::make_unique<E5>(p.real("a"), p.real("b"), p.real("c"), p.real("m"));
      }};
}

}  // namespace stiffbench
