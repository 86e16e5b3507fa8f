// A small additive split for the tests of the split integrators (operator splitting, the ARKODE
// references on a split): Kaps' problem (P. Kaps, Rosenbrock-type methods, in Numerical Methods
// for Stiff Initial Value Problems, G. Dahlquist & R. Jeltsch eds., 1981)
//   y1' = -(2 + 1/eps) y1 + y2^2/eps,   y2' = y1 - y2 - y2^2,   y(0) = (1, 1),
// with the exact solution y1 = e^(-2t), y2 = e^(-t) for every eps (substitute: y2^2 = y1).
// Split: f_I = [(-y1 + y2^2)/eps; 0] (the 1/eps terms), f_E = [-2 y1; y1 - y2 - y2^2]; the two
// parts do not commute, so a splitting has a non-zero splitting error. With `all_implicit`
// f_E = 0 and f_I = f (J_I = J).
#pragma once

#include <cmath>
#include <string>

#include "core/ode_system.hpp"

namespace stiffbench::testing_support {

class KapsSplit final : public OdeSystem {
 public:
  explicit KapsSplit(double eps, bool all_implicit = false)
      : eps_(eps), all_implicit_(all_implicit) {}
  std::string name() const override { return "kaps_split_test"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec::Ones(2); }
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    y(0) = std::exp(-2 * t);
    y(1) = std::exp(-t);
  }
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override {
    return SplitInfo{"test", "-2 y1 and y2' (none with all_implicit)", "the 1/eps terms"};
  }
  bool has_implicit_part_jacobian() const override { return true; }
  // Calls of the full Jacobian and of J_I (structure-only calls included), so a test can tell
  // which one a solver used.
  long full_jacobian_calls() const { return full_jac_; }
  long implicit_jacobian_calls() const { return implicit_jac_; }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f(0) = -(2 + 1 / eps_) * y(0) + y(1) * y(1) / eps_;
    f(1) = y(0) - y(1) - y(1) * y(1);
  }
  void eval_jacobian(double, CVecRef y, SparseMat& j) const override {
    ++full_jac_;
    set(j, -(2 + 1 / eps_), 2 * y(1) / eps_, 1.0, -1 - 2 * y(1));
  }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef f) const override {
    if (all_implicit_) {
      f.setZero();
      return;
    }
    f(0) = -2 * y(0);
    f(1) = y(0) - y(1) - y(1) * y(1);
  }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef f) const override {
    if (all_implicit_) {
      eval_rhs(t, y, f);
      return;
    }
    f(0) = (-y(0) + y(1) * y(1)) / eps_;
    f(1) = 0;
  }
  void eval_implicit_part_jacobian(double, CVecRef y, SparseMat& j) const override {
    ++implicit_jac_;
    if (all_implicit_) {
      set(j, -(2 + 1 / eps_), 2 * y(1) / eps_, 1.0, -1 - 2 * y(1));
      return;
    }
    set(j, -1 / eps_, 2 * y(1) / eps_, 0.0, 0.0);
  }

 private:
  // A full 2x2 pattern (explicit zeros kept), so the pattern never changes.
  static void set(SparseMat& j, double a00, double a01, double a10, double a11) {
    j.resize(2, 2);
    j.setZero();
    j.reserve(Eigen::VectorXi::Constant(2, 2));
    j.insert(0, 0) = a00;
    j.insert(1, 0) = a10;
    j.insert(0, 1) = a01;
    j.insert(1, 1) = a11;
    j.makeCompressed();
  }
  double eps_;
  bool all_implicit_;
  mutable long full_jac_ = 0, implicit_jac_ = 0;
};

// A linear split whose parts do not commute (Kaps' solution lies on the manifold y1 = y2^2,
// where its f_I vanishes, so splitting Kaps has no splitting error):
//   y' = (A_E + A_I) y,  A_E = [[0, 1], [0, 0]],  A_I = diag(-lambda, -1),  y(0) = (2, 1),
// [A_E, A_I] = (lambda - 1) [[0, 1], [0, 0]] != 0 for lambda != 1. Exact solution (y2 = e^(-t);
// y1' = -lambda y1 + e^(-t), variation of constants):
//   y1 = (2 - 1/(lambda - 1)) e^(-lambda t) + e^(-t)/(lambda - 1),  y2 = e^(-t).
class LinearSplit final : public OdeSystem {
 public:
  explicit LinearSplit(double lambda) : lambda_(lambda) {}
  std::string name() const override { return "linear_split_test"; }
  Index dimension() const override { return 2; }
  Vec initial_state() const override { return Vec{{2.0, 1.0}}; }
  bool autonomous() const override { return true; }
  bool has_jacobian() const override { return true; }
  bool has_exact() const override { return true; }
  void exact(double t, VecRef y) const override {
    const double c = 1 / (lambda_ - 1);
    y(0) = (2 - c) * std::exp(-lambda_ * t) + c * std::exp(-t);
    y(1) = std::exp(-t);
  }
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override {
    return SplitInfo{"test", "the coupling y2 in y1'", "the decay -lambda y1, -y2"};
  }
  bool has_implicit_part_jacobian() const override { return true; }

 protected:
  void eval_rhs(double, CVecRef y, VecRef f) const override {
    f(0) = -lambda_ * y(0) + y(1);
    f(1) = -y(1);
  }
  void eval_jacobian(double, CVecRef, SparseMat& j) const override { diag(j, 1.0); }
  void eval_rhs_explicit_part(double, CVecRef y, VecRef f) const override {
    f(0) = y(1);
    f(1) = 0;
  }
  void eval_rhs_implicit_part(double, CVecRef y, VecRef f) const override {
    f(0) = -lambda_ * y(0);
    f(1) = -y(1);
  }
  void eval_implicit_part_jacobian(double, CVecRef, SparseMat& j) const override { diag(j, 0.0); }

 private:
  // diag(-lambda, -1) with `coupling` at (0, 1), in a fixed pattern.
  void diag(SparseMat& j, double coupling) const {
    j.resize(2, 2);
    j.setZero();
    j.reserve(Eigen::VectorXi::Constant(2, 2));
    j.insert(0, 0) = -lambda_;
    j.insert(0, 1) = coupling;
    j.insert(1, 1) = -1.0;
    j.makeCompressed();
  }
  double lambda_;
};

}  // namespace stiffbench::testing_support
