// A method's coefficients analysed (experiments/support/coefficients.hpp).
#include "experiments/support/coefficients.hpp"

namespace stiffbench {

std::string tableau_kind(const ButcherTableau& t) {
  if (t.is_explicit()) return "explicit_rk";
  for (Index i = 0; i < t.a.rows(); ++i)
    for (Index j = i + 1; j < t.a.cols(); ++j)
      if (t.a(i, j) != 0.0) return "irk";
  return "dirk";
}

std::optional<MethodAnalysis> coefficient_analysis(const Integrator& integ) {
  if (const ButcherTableau* t = integ.butcher_tableau())
    return analyze_runge_kutta(*t, tableau_kind(*t));
  if (const RosenbrockTableau* t = integ.rosenbrock_tableau()) return analyze_rosenbrock(*t);
  if (const AdditiveTableau* t = integ.additive_tableau()) return analyze_additive(*t);
  if (const KickDriftCoefficients* c = integ.kick_drift_coefficients())
    return analyze_kick_drift(*c);
  return std::nullopt;
}

std::string additive_part_name(const std::string& integrator, const std::string& part) {
  return integrator + ":" + part;
}

}  // namespace stiffbench
