#include "models/problems/hires.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

Vec Hires::initial_state() const {
  Vec y = Vec::Zero(8);
  y[0] = 1.0;
  y[7] = 0.0057;
  return y;
}

void Hires::eval_rhs(double, CVecRef y, VecRef f) const {
  // The one nonlinear reaction, shared so that y7' + y8' = 0 to round-off.
  const double r = 280.0 * y[5] * y[7];
  f[0] = -1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007;
  f[1] = 1.71 * y[0] - 8.75 * y[1];
  f[2] = -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4];
  f[3] = 8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3];
  f[4] = -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6];
  f[5] = -r + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6];
  f[6] = r - 1.81 * y[6];
  f[7] = -r + 1.81 * y[6];
}

void Hires::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  const double d6 = 280.0 * y[7];  // ∂(280 y6 y8)/∂y6
  const double d8 = 280.0 * y[5];  // ∂(280 y6 y8)/∂y8

  // One line per row of J (0-based indices).
  // clang-format off
  const std::vector<Eigen::Triplet<double>> t{
      {0, 0, -1.71}, {0, 1, 0.43}, {0, 2, 8.32},
      {1, 0, 1.71}, {1, 1, -8.75},
      {2, 2, -10.03}, {2, 3, 0.43}, {2, 4, 0.035},
      {3, 1, 8.32}, {3, 2, 1.71}, {3, 3, -1.12},
      {4, 4, -1.745}, {4, 5, 0.43}, {4, 6, 0.43},
      {5, 3, 0.69}, {5, 4, 1.71}, {5, 5, -0.43 - d6}, {5, 6, 0.69}, {5, 7, -d8},
      {6, 5, d6}, {6, 6, -1.81}, {6, 7, d8},
      {7, 5, -d6}, {7, 6, 1.81}, {7, 7, -d8}};
  // clang-format on
  jac.resize(8, 8);
  jac.setFromTriplets(t.begin(), t.end());
}

std::vector<Invariant> Hires::invariants() const {
  return {{"y7+y8", [](double, CVecRef y) { return y[6] + y[7]; }}};
}

std::optional<double> Hires::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

}  // namespace stiffbench

namespace stiffbench {

std::optional<OdeSystem::PublishedSolution> Hires::published_solution() const {
  // IVP test set "hires" (the values in hires.hpp).
  return PublishedSolution{321.8122,
                           Vec{{0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4,
                                0.1175651343283149e-2, 0.2386356198831331e-2, 0.6238968252742796e-2,
                                0.2849998395185769e-2, 0.2850001604814231e-2}},
                           "IVP test set (Mazzia & Magherini), problem hires"};
}

ModelRegistry::Entry hires_entry() {
  return {
      .info = {.name = "hires",
               .description =
                   "HIRES plant photomorphogenesis (8 species); literature end time t = 321.8122",
               .source = "Schäfer 1975; Hairer & Wanner II §IV.10 (HIRES); IVP test set 'hires'",
               .size = fixed_problem_size},
      .params = {},
      .make = [](const Params&) { return std::make_unique<Hires>(); }};
}

}  // namespace stiffbench
