#include "models/problems/harmonic_oscillator.hpp"
#include "models/problems/problem_entry.hpp"

#include <cmath>

namespace stiffbench {

namespace {
void one_by_one(SparseMat& m, double value) {
  m.resize(1, 1);
  m.setZero();
  m.insert(0, 0) = value;
}
}  // namespace

HarmonicOscillator::HarmonicOscillator(double m, double k, double gamma, double x0, double v0)
    : m_(m), k_(k), gamma_(gamma), x0_(x0), v0_(v0) {
  require_input(m > 0, "harmonic_oscillator: parameter 'm' must be > 0");
  require_input(k > 0, "harmonic_oscillator: parameter 'k' must be > 0");
  require_input(gamma >= 0, "harmonic_oscillator: parameter 'gamma' must be >= 0");
}

void HarmonicOscillator::eval_acceleration(double, CVecRef x, CVecRef v, VecRef a) const {
  a[0] = -(k_ * x[0] + gamma_ * v[0]) / m_;
}

void HarmonicOscillator::stiffness_block(double, CVecRef, CVecRef, SparseMat& k) const {
  one_by_one(k, -k_ / m_);
}

void HarmonicOscillator::damping_block(double, CVecRef, CVecRef, SparseMat& d) const {
  one_by_one(d, -gamma_ / m_);
}

void HarmonicOscillator::exact(double t, VecRef y) const {
  const double beta = gamma_ / (2 * m_);
  const double w0 = std::sqrt(k_ / m_);
  const double disc = beta * beta - w0 * w0;
  const double decay = std::exp(-beta * t);
  if (std::abs(disc) <= 1e-14 * w0 * w0) {  // critical damping
    const double b = v0_ + beta * x0_;
    y[0] = decay * (x0_ + b * t);
    y[1] = decay * (b - beta * (x0_ + b * t));
  } else if (disc < 0) {  // underdamped (includes γ = 0)
    const double wd = std::sqrt(-disc);
    const double b = (v0_ + beta * x0_) / wd;
    const double c = std::cos(wd * t), s = std::sin(wd * t);
    y[0] = decay * (x0_ * c + b * s);
    y[1] = decay * ((-beta * x0_ + b * wd) * c + (-beta * b - x0_ * wd) * s);
  } else if (const double sq = std::sqrt(disc); sq > 1e-3 * w0) {  // overdamped
    const double r1 = -beta + sq, r2 = -beta - sq;
    const double c1 = (v0_ - r2 * x0_) / (r1 - r2), c2 = x0_ - c1;
    y[0] = c1 * std::exp(r1 * t) + c2 * std::exp(r2 * t);
    y[1] = c1 * r1 * std::exp(r1 * t) + c2 * r2 * std::exp(r2 * t);
  } else {
    // Just above critical damping: x = e^{-βt}(x0 cosh st + (v0 + βx0) sinh(st)/s),
    // s = √(β² - ω0²). The two-exponential form divides by r1 - r2 = 2s and loses digits there
    // (measured 6.5e-11 at γ = 2(1 + 1e-13) against a long-double matrix exponential); this form
    // would overflow cosh for large s·t, which the branch condition keeps away.
    const double b = v0_ + beta * x0_;
    const double ch = std::cosh(sq * t), sh = std::sinh(sq * t);
    const double sinhc = sq * t == 0 ? t : sh / sq;  // sinh(st)/s, finite as s → 0
    y[0] = decay * (x0_ * ch + b * sinhc);
    y[1] = decay * (-beta * (x0_ * ch + b * sinhc) + x0_ * sq * sh + b * ch);
  }
}

std::vector<Invariant> HarmonicOscillator::invariants() const {
  return {{"energy",
           [this](double, CVecRef y) { return 0.5 * m_ * y[1] * y[1] + 0.5 * k_ * y[0] * y[0]; }}};
}

std::optional<double> HarmonicOscillator::stiffness(double, CVecRef) const {
  // Largest |eigenvalue| of [[0, 1], [-k/m, -γ/m]].
  const double beta = gamma_ / (2 * m_), w0 = std::sqrt(k_ / m_);
  return beta <= w0 ? w0 : beta + std::sqrt(beta * beta - w0 * w0);
}

ModelRegistry::Entry harmonic_oscillator_entry() {
  using P = ParamType;
  using B = Bounds;
  return {.info = {.name = "harmonic_oscillator",
                   .description = "m x'' + γ x' + k x = 0 (undamped by default)",
                   .mechanical = true,
                   .exact = true,
                   .source = "closed-form solution for under-, critically and overdamped cases",
                   .size = fixed_problem_size},
          .params = {{"m", P::real, "1", "mass", B::positive()},
                     {"k", P::real, "1", "spring stiffness", B::positive()},
                     {"gamma", P::real, "0", "viscous damping coefficient γ", B::non_negative()},
                     {"x0", P::real, "1", "initial position", B::any()},
                     {"v0", P::real, "0", "initial velocity", B::any()}},
          .make = [](const Params& p) {
            return std::make_unique<HarmonicOscillator>(p.real("m"), p.real("k"), p.real("gamma"),
                                                        p.real("x0"), p.real("v0"));
          }};
}

}  // namespace stiffbench
