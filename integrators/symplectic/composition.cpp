#include "integrators/symplectic/composition.hpp"

#include "integrators/method_file.hpp"

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

// The Verlet substeps of a kick/drift splitting that is a composition of velocity Verlet steps
// (the form verlet_composition builds), empty when it is not.
std::vector<double> verlet_substeps(const KickDriftCoefficients& c) {
  if (c.drift.size() < 2 || c.drift.back() != 0.0) return {};
  std::vector<double> gamma(c.drift.begin(), c.drift.end() - 1);
  if (verlet_composition(c.name, gamma, c.order).kick != c.kick) return {};
  return gamma;
}

}  // namespace

const std::vector<CompositionMethod>& composition_methods() {
  static const std::vector<CompositionMethod> all = [] {
    std::vector<CompositionMethod> out;
    for (const MethodDefinition& m : built_in_methods()) {
      if (m.kind != MethodKind::kick_drift || m.order <= 2) continue;
      const KickDriftCoefficients& c = m.splitting.kick_drift;
      out.push_back({m.name, m.order, verlet_substeps(c), c});
    }
    return out;
  }();
  return all;
}

}  // namespace stiffbench
