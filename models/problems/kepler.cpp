#include "models/problems/kepler.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>
#include <numbers>

namespace stiffbench {

Kepler::Kepler(double e, double gm, double a) : e_(e), gm_(gm), a_(a) {
  require_input(e >= 0 && e < 1, "kepler: parameter 'e' must be in [0, 1)");
  require_input(gm > 0, "kepler: parameter 'gm' must be > 0");
  require_input(a > 0, "kepler: parameter 'a' must be > 0");
}

Vec Kepler::initial_state() const {
  return Vec{{a_ * (1 - e_), 0.0, 0.0, std::sqrt(gm_ / a_ * (1 + e_) / (1 - e_))}};
}

double Kepler::period() const { return 2 * std::numbers::pi * std::sqrt(a_ * a_ * a_ / gm_); }

void Kepler::eval_acceleration(double, CVecRef x, CVecRef, VecRef acc) const {
  const double r2 = x[0] * x[0] + x[1] * x[1];
  const double f = -gm_ / (r2 * std::sqrt(r2));
  acc[0] = f * x[0];
  acc[1] = f * x[1];
}

void Kepler::stiffness_block(double, CVecRef x, CVecRef, SparseMat& k) const {
  // ∂a/∂q = -GM (I/r³ - 3 q qᵀ/r⁵)
  const double r2 = x[0] * x[0] + x[1] * x[1];
  const double r = std::sqrt(r2);
  const double c3 = gm_ / (r2 * r), c5 = 3 * gm_ / (r2 * r2 * r);
  k.resize(2, 2);
  std::vector<Eigen::Triplet<double>> t{{0, 0, -c3 + c5 * x[0] * x[0]},
                                        {0, 1, c5 * x[0] * x[1]},
                                        {1, 0, c5 * x[1] * x[0]},
                                        {1, 1, -c3 + c5 * x[1] * x[1]}};
  k.setFromTriplets(t.begin(), t.end());
}

void Kepler::damping_block(double, CVecRef, CVecRef, SparseMat& d) const {
  d.resize(2, 2);
  d.setZero();
}

void Kepler::exact(double t, VecRef y) const {
  const double n = std::sqrt(gm_ / (a_ * a_ * a_));
  // Mean anomaly reduced to [-π, π) so Newton starts close for any t.
  const double two_pi = 2 * std::numbers::pi;
  double mean = std::fmod(n * t, two_pi);
  if (mean >= std::numbers::pi) mean -= two_pi;
  if (mean < -std::numbers::pi) mean += two_pi;
  // Newton on E - e sin E - M = 0; the start E = M + e sin M (or π for very eccentric orbits)
  // converges monotonically for e < 1 (Danby, Fundamentals of Celestial Mechanics §6.6).
  double ecc_anom = e_ > 0.8 ? std::copysign(std::numbers::pi, mean) : mean + e_ * std::sin(mean);
  for (int it = 0; it < 50; ++it) {
    const double f = ecc_anom - e_ * std::sin(ecc_anom) - mean;
    const double step = f / (1 - e_ * std::cos(ecc_anom));
    ecc_anom -= step;
    if (std::abs(step) <= 1e-16 * std::max(1.0, std::abs(ecc_anom))) break;
  }
  const double c = std::cos(ecc_anom), s = std::sin(ecc_anom);
  const double b = a_ * std::sqrt(1 - e_ * e_);
  const double edot = n / (1 - e_ * c);
  y[0] = a_ * (c - e_);
  y[1] = b * s;
  y[2] = -a_ * s * edot;
  y[3] = b * c * edot;
}

std::vector<Invariant> Kepler::invariants() const {
  return {{"energy",
           [this](double, CVecRef y) {
             return 0.5 * (y[2] * y[2] + y[3] * y[3]) - gm_ / std::hypot(y[0], y[1]);
           }},
          {"angular_momentum", [](double, CVecRef y) { return y[0] * y[3] - y[1] * y[2]; }}};
}

std::optional<double> Kepler::stiffness(double, CVecRef y) const {
  const double r = std::hypot(y[0], y[1]);
  return std::sqrt(2 * gm_ / (r * r * r));
}

ModelRegistry::Entry kepler_entry() {
  using P = ParamType;
  using B = Bounds;
  return {
      .info = {.name = "kepler",
               .description = "planar two-body orbit starting at pericentre (period 2π by default)",
               .mechanical = true,
               .exact = true,
               .source = "exact solution through Kepler's equation (Goldstein §3.8)",
               .size = fixed_problem_size},
      .params = {{"e", P::real, "0", "eccentricity", B::in_closed_open(0, 1)},
                 {"gm", P::real, "1", "gravitational parameter GM", B::positive()},
                 {"a", P::real, "1", "semi-major axis", B::positive()}},
      .make = [](const Params& p) {
        return std::make_unique<Kepler>(p.real("e"), p.real("gm"), p.real("a"));
      }};
}

}  // namespace stiffbench
