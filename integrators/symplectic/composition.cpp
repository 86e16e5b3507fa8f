#include "integrators/symplectic/composition.hpp"

#include <cmath>

namespace stiffbench {

KickDriftCoefficients verlet_composition(const std::string& name, const std::vector<double>& gamma,
                                         int order) {
  KickDriftCoefficients c;
  c.name = name;
  c.order = order;
  const std::size_t s = gamma.size();
  c.kick.assign(s + 1, 0.0);
  c.drift.assign(s + 1, 0.0);
  for (std::size_t j = 0; j < s; ++j) {
    c.kick[j] += 0.5 * gamma[j];
    c.kick[j + 1] += 0.5 * gamma[j];
    c.drift[j] = gamma[j];
  }
  return c;
}

namespace {

CompositionMethod from_gamma(std::string name, int order, std::vector<double> gamma) {
  CompositionMethod m;
  m.name = std::move(name);
  m.order = order;
  m.kick_drift = verlet_composition(m.name, gamma, order);
  m.gamma = std::move(gamma);
  return m;
}

CompositionMethod yoshida4() {
  // Forest & Ruth (1990), Yoshida (1990): the triple jump.
  const double c = 1.0 / (2.0 - std::cbrt(2.0));
  return from_gamma("yoshida4", 4, {c, 1.0 - 2.0 * c, c});
}

CompositionMethod yoshida6() {
  // Yoshida (1990), Phys. Lett. A 150, 262, Table 1, solution A.
  const double w1 = -1.17767998417887, w2 = 0.235573213359357, w3 = 0.784513610477560;
  const double w0 = 1.0 - 2.0 * (w1 + w2 + w3);
  return from_gamma("yoshida6", 6, {w3, w2, w1, w0, w1, w2, w3});
}

CompositionMethod blanes_moan() {
  // Blanes & Moan (2002), Table 3, SRKN_6^b: b (kicks) and a (drifts), kick first and last.
  const double b1 = 0.0829844064174052, b2 = 0.396309801498368, b3 = -0.0390563049223486;
  const double b4 = 1.0 - 2.0 * (b1 + b2 + b3);
  const double a1 = 0.245298957184271, a2 = 0.604872665711080;
  const double a3 = 0.5 - (a1 + a2);
  CompositionMethod bm;
  bm.name = "blanes_moan";
  bm.order = 4;
  bm.kick_drift = {"blanes_moan", {b1, b2, b3, b4, b3, b2, b1}, {a1, a2, a3, a3, a2, a1, 0.0}, 4};
  return bm;
}

}  // namespace

const std::vector<CompositionEntry>& composition_entries() {
  static const std::vector<CompositionEntry> all = {
      {yoshida4(),
       {"Forest-Ruth/Yoshida triple jump of velocity Verlet, order 4, "
        "3 evaluations per step (FSAL)",
        "Verlet composition",
        "E. Forest & R. D. Ruth, Physica D 43 (1990) 105-117; H. Yoshida, Phys. Lett. A 150 "
        "(1990) 262-268"},
       StepModes::fixed},
      {yoshida6(),
       {"Yoshida (1990) order-6 composition of velocity Verlet (solution A), "
        "7 evaluations per step (FSAL)",
        "Verlet composition", "H. Yoshida, Phys. Lett. A 150 (1990) 262-268 (solution A)"},
       StepModes::fixed},
      {blanes_moan(),
       {"Blanes-Moan (2002) optimised symmetric splitting SRKN_6^b, order 4, 6 evaluations per "
        "step (FSAL)",
        "optimised splitting",
        "S. Blanes & P. C. Moan, J. Comput. Appl. Math. 142 (2002) 313-330 (SRKN_6^b)"},
       StepModes::fixed},
  };
  return all;
}

const std::vector<CompositionMethod>& composition_methods() {
  static const std::vector<CompositionMethod> all = [] {
    std::vector<CompositionMethod> out;
    for (const CompositionEntry& e : composition_entries()) out.push_back(*e.coefficients);
    return out;
  }();
  return all;
}

}  // namespace stiffbench
