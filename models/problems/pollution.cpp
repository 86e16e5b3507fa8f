#include "models/problems/pollution.hpp"
#include "models/problems/problem_entry.hpp"

#include <array>
#include <cmath>
#include <string>

namespace stiffbench {

namespace {

// One mass-action reaction: r = k·y[a] (first order, b = 0) or k·y[a]·y[b], and its net
// stoichiometry. Species numbers are the literature's 1-based ones (0 ends a list).
struct Reaction {
  double k;
  int a, b;
  std::array<std::pair<int, int>, 5> nu;  // (species, net change)
};

// Verwer (1994) / IVP test set "pollu", reactions r1..r25 in order (see pollution.hpp).
constexpr std::array<Reaction, 25> kReactions{{
    {0.35, 1, 0, {{{1, -1}, {2, 1}, {3, 1}}}},
    {26.6, 2, 4, {{{2, -1}, {4, -1}, {1, 1}}}},
    {1.23e4, 5, 2, {{{5, -1}, {2, -1}, {1, 1}, {6, 1}}}},
    {8.6e-4, 7, 0, {{{7, -1}, {5, 2}, {8, 1}}}},
    {8.2e-4, 7, 0, {{{7, -1}, {8, 1}}}},
    {1.5e4, 7, 6, {{{7, -1}, {6, -1}, {5, 1}, {8, 1}}}},
    {1.3e-4, 9, 0, {{{9, -1}, {10, 1}, {5, 1}, {8, 1}}}},
    {2.4e4, 9, 6, {{{9, -1}, {6, -1}, {11, 1}}}},
    {1.65e4, 11, 2, {{{11, -1}, {2, -1}, {1, 1}, {10, 1}, {12, 1}}}},
    {9e3, 11, 1, {{{11, -1}, {1, -1}, {13, 1}}}},
    {0.022, 13, 0, {{{13, -1}, {11, 1}, {1, 1}}}},
    {1.2e4, 10, 2, {{{10, -1}, {2, -1}, {14, 1}, {1, 1}}}},
    {1.88, 14, 0, {{{14, -1}, {7, 1}, {5, 1}}}},
    {1.63e4, 1, 6, {{{1, -1}, {6, -1}, {15, 1}}}},
    {4.8e6, 3, 0, {{{3, -1}, {4, 1}}}},
    {3.5e-4, 4, 0, {{{4, -1}, {16, 1}}}},
    {0.0175, 4, 0, {{{4, -1}, {3, 1}}}},
    {1e8, 16, 0, {{{16, -1}, {6, 2}}}},
    {4.44e11, 16, 0, {{{16, -1}, {3, 1}}}},
    {1240.0, 17, 6, {{{17, -1}, {6, -1}, {18, 1}, {5, 1}}}},
    {2.1, 19, 0, {{{19, -1}, {2, 1}}}},
    {5.78, 19, 0, {{{19, -1}, {1, 1}, {3, 1}}}},
    {0.0474, 1, 4, {{{1, -1}, {4, -1}, {19, 1}}}},
    {1780.0, 19, 1, {{{19, -1}, {1, -1}, {20, 1}}}},
    {3.12, 20, 0, {{{20, -1}, {19, 1}, {1, 1}}}},
}};

double rate(const Reaction& r, CVecRef y) {
  return r.b == 0 ? r.k * y[r.a - 1] : r.k * y[r.a - 1] * y[r.b - 1];
}

}  // namespace

Vec Pollution::initial_state() const {
  Vec y = Vec::Zero(20);
  y[1] = 0.2;     // y2  NO
  y[3] = 0.04;    // y4  O3
  y[6] = 0.1;     // y7  HCHO
  y[7] = 0.3;     // y8  CO
  y[8] = 0.01;    // y9  ALD
  y[16] = 0.007;  // y17 SO2
  return y;
}

void Pollution::eval_rhs(double, CVecRef y, VecRef dydt) const {
  // Each rate enters every species it changes with its integer coefficient, so the atom
  // balances hold to round-off.
  dydt.setZero();
  for (const Reaction& r : kReactions) {
    const double v = rate(r, y);
    for (const auto& [species, change] : r.nu) {
      if (species == 0) break;
      dydt[species - 1] += change * v;
    }
  }
}

void Pollution::eval_jacobian(double, CVecRef y, SparseMat& jac) const {
  // ∂f_i/∂y_a = Σ_j ν_ij ∂r_j/∂y_a; the triplet list has the same structure at every call and
  // setFromTriplets sums duplicates (explicit zeros are kept).
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(100);
  for (const Reaction& r : kReactions) {
    const double da = r.b == 0 ? r.k : r.k * y[r.b - 1];  // ∂r/∂y_a
    const double db = r.b == 0 ? 0.0 : r.k * y[r.a - 1];  // ∂r/∂y_b
    for (const auto& [species, change] : r.nu) {
      if (species == 0) break;
      t.emplace_back(species - 1, r.a - 1, change * da);
      if (r.b != 0) t.emplace_back(species - 1, r.b - 1, change * db);
    }
  }
  jac.resize(20, 20);
  jac.setFromTriplets(t.begin(), t.end());
}

std::vector<Invariant> Pollution::invariants() const {
  return {{"nitrogen",
           [](double, CVecRef y) { return y[0] + y[1] + y[12] + y[14] + y[18] + 2 * y[19]; }},
          {"carbon",
           [](double, CVecRef y) {
             return y[6] + y[7] + 2 * y[8] + y[9] + 2 * y[10] + y[11] + 2 * y[12] + y[13];
           }},
          {"sulfur", [](double, CVecRef y) { return y[16] + y[17]; }}};
}

std::optional<double> Pollution::stiffness(double t, CVecRef y) const {
  SparseMat jac;
  eval_jacobian(t, y, jac);  // not counted: an estimate, not a solver's evaluation
  return gershgorin_bound(jac);
}

ModelRegistry::Entry pollution_entry() {
  return {.info = {.name = "pollution",
                   .description = "POLLU air-pollution chemistry (20 species, 25 reactions); "
                                  "literature end time t = 60",
                   .source = "Verwer 1994 (SIAM J. Sci. Comput. 15); IVP test set 'pollu'",
                   .size = fixed_problem_size},
          .params = {},
          .make = [](const Params&) { return std::make_unique<Pollution>(); }};
}

std::string Pollution::component_name(Index i) const {
  static const char* const kSpecies[20] = {"NO2",  "NO",  "O3P",  "O3",   "HO2", "OH",  "HCHO",
                                           "CO",   "ALD", "MEO2", "C2O3", "CO2", "PAN", "CH3O",
                                           "HNO3", "O1D", "SO2",  "SO4",  "NO3", "N2O5"};
  return i >= 0 && i < 20 ? kSpecies[i] : "";
}

}  // namespace stiffbench
