#include "integrators/explicit/tableaux.hpp"

#include "integrators/method_file.hpp"

namespace stiffbench {

namespace {

std::vector<ButcherTableau> explicit_of(bool embedded) {
  std::vector<ButcherTableau> out;
  for (const MethodDefinition& m : built_in_methods())
    if (m.kind == MethodKind::explicit_rk && (m.tableau.b_embedded.size() != 0) == embedded)
      out.push_back(m.tableau);
  return out;
}

}  // namespace

const std::vector<ButcherTableau>& explicit_tableaux() {
  static const std::vector<ButcherTableau> all = explicit_of(false);
  return all;
}

const std::vector<ButcherTableau>& embedded_tableaux() {
  static const std::vector<ButcherTableau> all = explicit_of(true);
  return all;
}

}  // namespace stiffbench
