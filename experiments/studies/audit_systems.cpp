// The audit's own systems (audit_systems.hpp).
#include "experiments/studies/audit_systems.hpp"

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "experiments/framework/catalog.hpp"

namespace stiffbench::audit_parts {

namespace {

// The split of the audit's own systems for methods that need one (IMEX pairs, operator
// splitting): f_E = f_I = f/2, both parts carrying half of every term. The methods' own split
// behaviour is tested on the split models; here the split only lets them run, so that what they
// report can be compared with what they do.
SplitInfo halves_split() { return SplitInfo{"halves", "half of f", "half of f"}; }

// The 1×1 Jacobian [v] of the audit's scalar systems (v = 0 is stored too: the pattern is fixed).
void scalar_jacobian(SparseMat& jac, double v) {
  jac.resize(1, 1);
  jac.setZero();
  jac.insert(0, 0) = v;
  jac.makeCompressed();
}

// y' = λy, λ = -1, y(0) = 1: the scalar linear system of the count checks (split: each part
// -y/2).
class ScalarLinear final : public OdeSystem {
 public:
  explicit ScalarLinear(bool split = false) : split_(split) {}
  std::string name() const override { return split_ ? "scalar_linear(split)" : "scalar_linear"; }
  bool has_imex_split() const override { return split_; }
  std::optional<SplitInfo> imex_split() const override {
    return split_ ? std::optional<SplitInfo>(halves_split()) : std::nullopt;
  }
  bool has_implicit_part_jacobian() const override { return split_; }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Ones(1); }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::exp(-t); }

 protected:
  void eval_rhs(double, CVecRef y, VecRef dydt) const override { dydt[0] = -y[0]; }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override { scalar_jacobian(jac, -1.0); }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const override { fe[0] = -0.5 * y[0]; }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const override { fi[0] = -0.5 * y[0]; }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    scalar_jacobian(jac, -0.5);
  }

 private:
  bool split_;
};

// y' = t^q (q = 0: y' = 1), y(0) = 0, exact y = t^(q+1)/(q+1); Jacobian 0 (one stored zero).
// Split: each part t^q/2, so that a pair whose two tables have order p integrates it exactly.
class Monomial final : public OdeSystem {
 public:
  explicit Monomial(int q, bool split = false) : q_(q), split_(split) {}
  bool has_imex_split() const override { return split_; }
  std::optional<SplitInfo> imex_split() const override {
    return split_ ? std::optional<SplitInfo>(halves_split()) : std::nullopt;
  }
  bool has_implicit_part_jacobian() const override { return split_; }
  std::string name() const override {
    return (q_ == 0 ? "y'=1" : "y'=t^" + std::to_string(q_)) + (split_ ? " (split)" : "");
  }
  Index dimension() const override { return 1; }
  Vec initial_state() const override { return Vec::Zero(1); }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return q_ == 0; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override { y[0] = std::pow(t, q_ + 1) / (q_ + 1); }

 protected:
  void eval_rhs(double t, CVecRef, VecRef dydt) const override { dydt[0] = power(t); }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override { scalar_jacobian(jac, 0.0); }
  void eval_rhs_explicit_part(double t, CVecRef, VecRef fe) const override {
    fe[0] = 0.5 * power(t);
  }
  void eval_rhs_implicit_part(double t, CVecRef, VecRef fi) const override {
    fi[0] = 0.5 * power(t);
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    scalar_jacobian(jac, 0.0);
  }

 private:
  double power(double t) const { return q_ == 0 ? 1.0 : std::pow(t, q_); }
  int q_;
  bool split_;
};

// y' = E y + I y with E = [[0, 1], [-1, 0]] (a rotation: the explicit part) and I = diag(-1, -2)
// (decay: the implicit part), y(0) = (1, 1/2). E and I do not commute (EI - IE =
// [[0, -1], [-1, 0]]), so a splitting's error is its own, not cancelled as on Kaps' problem,
// whose exact solution keeps f_I = 0 (y1 = y2²) and makes Lie and Strang look exact.
// Exact: y(t) = e^(Mt) y0, M = E + I = [[-1, 1], [-1, -2]], whose eigenvalues are s ± iω with
// s = tr/2 = -3/2 and ω = √(det − s²) = √(3 − 9/4); e^(Mt) = e^(st) (cos ωt · 1 + sin ωt/ω ·
// (M − s·1)) (Cayley–Hamilton).
class RotationDecay final : public OdeSystem {
 public:
  std::string name() const override { return "rotation_decay"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{1.0, 0.5}}; }
  bool has_jacobian() const override { return true; }
  bool autonomous() const override { return true; }
  bool has_exact() const override { return true; }
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override {
    return SplitInfo{"rotation_decay", "the rotation [[0, 1], [-1, 0]] y",
                     "the decay diag(-1, -2) y"};
  }
  bool has_implicit_part_jacobian() const override { return true; }
  void exact(double t, VecRef y) const override {
    const double s = -1.5, w = std::sqrt(0.75);
    const double c = std::cos(w * t), sn = std::sin(w * t) / w, e = std::exp(s * t);
    const double y1 = 1.0, y2 = 0.5;  // y0
    // (M − s·1) = [[0.5, 1], [-1, -0.5]]
    y[0] = e * (c * y1 + sn * (0.5 * y1 + y2));
    y[1] = e * (c * y2 + sn * (-y1 - 0.5 * y2));
  }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f[0] = y[1] - y[0];
    f[1] = -y[0] - 2.0 * y[1];
  }
  void eval_jacobian(double, CVecRef, SparseMat& jac) const override {
    const std::vector<Eigen::Triplet<double>> t{
        {0, 0, -1.0}, {0, 1, 1.0}, {1, 0, -1.0}, {1, 1, -2.0}};
    jac.resize(2, 2);
    jac.setFromTriplets(t.begin(), t.end());
  }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef fe) const override {
    fe[0] = y[1];
    fe[1] = -y[0];
  }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef fi) const override {
    fi[0] = -y[0];
    fi[1] = -2.0 * y[1];
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& jac) const override {
    const std::vector<Eigen::Triplet<double>> t{{0, 0, -1.0}, {1, 1, -2.0}};
    jac.resize(2, 2);
    jac.setFromTriplets(t.begin(), t.end());
  }
};

}  // namespace

// Methods that need an additive split (`split`: IMEX pairs, operator splitting, multirate) get
// split systems instead: the scalar one in halves, Kaps' problem (ε = 1e-3, its 1/ε terms
// implicit; kepler has no split) and the cloth with split=springs.
std::vector<CountSystem> count_systems(bool split) {
  std::vector<CountSystem> out;
  out.push_back({split ? "scalar_linear(split)" : "scalar_linear",
                 std::make_unique<ScalarLinear>(split), 1.0});
  if (split) {
    Params kaps;
    kaps.set("eps", "1e-3");
    out.push_back({"kaps(eps=1e-3)", model_registry().create("kaps", kaps), 0.5});
  } else {
    Params kepler;
    kepler.set("e", "0.5");
    out.push_back({"kepler(e=0.5)", model_registry().create("kepler", kepler), 0.5});
  }
  Params cloth;
  cloth.set("n", "8");
  if (split) cloth.set("split", "springs");
  // 8×8 points; structural ω = √(k/m) ≈ 35, so h = 2.5e-4 is far inside every explicit
  // method's stability limit.
  out.push_back({split ? "cloth(n=8,split=springs)" : "cloth(n=8)",
                 model_registry().create("cloth", cloth), 0.004});
  return out;
}

std::unique_ptr<OdeSystem> monomial_system(int q, bool split) {
  return std::make_unique<Monomial>(q, split);
}

std::unique_ptr<OdeSystem> rotation_decay_system() { return std::make_unique<RotationDecay>(); }

}  // namespace stiffbench::audit_parts
