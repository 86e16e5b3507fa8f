// The views of an additive split (core/split_views.hpp) and the split's counting
// (core/ode_system.hpp), on a two-dof mechanical system defined here: a_I = -k x (a stiff
// spring), a_E = g - γ v (gravity and point damping), so f_E = [0; a_E], f_I = [v; a_I].
#include <gtest/gtest.h>

#include "core/split_views.hpp"

namespace stiffbench {
namespace {

class SplitOscillator final : public MechanicalSystem {
 public:
  std::string name() const override { return "split_oscillator"; }
  Index dofs() const override { return 2; }
  Vec initial_state() const override { return (Vec(4) << 0.3, -0.2, 1.0, 0.5).finished(); }
  bool velocity_dependent() const override { return true; }
  bool implicit_part_velocity_dependent() const override { return false; }
  bool has_force_jacobians() const override { return true; }
  void force_jacobians(double, CVecRef, CVecRef, SparseMat& k, SparseMat& d) const override {
    k = -kK * identity();
    d = -kGamma * identity();
  }
  void implicit_force_jacobians(double, CVecRef, CVecRef, SparseMat& k,
                                SparseMat& d) const override {
    k = -kK * identity();
    d.resize(2, 2);
  }
  bool has_imex_split() const override { return true; }
  std::optional<SplitInfo> imex_split() const override {
    return SplitInfo{"spring", "gravity and damping", "spring"};
  }

  static constexpr double kK = 1e4, kGamma = 0.5, kG = -9.81;

 protected:
  void eval_acceleration(double, CVecRef x, CVecRef v, VecRef a) const override {
    a = -kK * x - kGamma * v;
    a.array() += kG;
  }
  void eval_acceleration_explicit_part(double, CVecRef, CVecRef v, VecRef a) const override {
    a = -kGamma * v;
    a.array() += kG;
  }
  void eval_acceleration_implicit_part(double, CVecRef x, CVecRef, VecRef a) const override {
    a = -kK * x;
  }

 private:
  static SparseMat identity() {
    SparseMat i(2, 2);
    i.setIdentity();
    return i;
  }
};

TEST(SplitViews, PartsAddUpToTheWholeAndAreCountedApart) {
  const SplitOscillator sys;
  const Vec y = sys.initial_state();
  Vec f(4), fe(4), fi(4);
  sys.rhs(0.0, y, f);
  sys.rhs_explicit_part(0.0, y, fe);
  sys.rhs_implicit_part(0.0, y, fi);
  // f_E = [0; a_E] and f_I = [v; a_I] by the definition of a mechanical split.
  EXPECT_EQ(fe.head(2), Vec::Zero(2));
  EXPECT_EQ(fi.head(2), y.tail(2));
  EXPECT_LE((fe + fi - f).cwiseAbs().maxCoeff(), 1e-12 * f.cwiseAbs().maxCoeff());
  EXPECT_EQ(sys.counters().f_evals, 3);
  EXPECT_EQ(sys.counters().fe_evals, 1);
  EXPECT_EQ(sys.counters().fi_evals, 1);
}

TEST(SplitViews, ImplicitViewIsMechanicalWithThePartsJacobian) {
  const SplitOscillator sys;
  const auto vi = implicit_part_view(sys);
  const auto ve = explicit_part_view(sys);
  ASSERT_NE(vi->as_mechanical(), nullptr);  // velocity-form solves stay available
  EXPECT_EQ(ve->as_mechanical(), nullptr);  // [0; a_E] is not of the form [v; a]
  EXPECT_FALSE(vi->as_mechanical()->velocity_dependent());
  const Vec y = sys.initial_state();
  Vec fi(4), fe(4), expect_i(4), expect_e(4);
  vi->rhs(0.0, y, fi);
  ve->rhs(0.0, y, fe);
  sys.rhs_implicit_part(0.0, y, expect_i);
  sys.rhs_explicit_part(0.0, y, expect_e);
  EXPECT_EQ(fi, expect_i);
  EXPECT_EQ(fe, expect_e);
  // Counted on the model (where the driver reads them): two calls of each part.
  EXPECT_EQ(sys.counters().fi_evals, 2);
  EXPECT_EQ(sys.counters().fe_evals, 2);
  // J_I = [[0, I], [K_I, D_I]] = [[0, I], [-k I, 0]] (the damping belongs to f_E).
  SparseMat j;
  vi->jacobian(0.0, y, j);
  const Mat dj(j);
  Mat expect = Mat::Zero(4, 4);
  expect(0, 2) = expect(1, 3) = 1.0;
  expect(2, 0) = expect(3, 1) = -SplitOscillator::kK;
  EXPECT_EQ(dj, expect);
}

TEST(SplitViews, ModelWithoutSplitIsRefusedByName) {
  class NoSplit final : public OdeSystem {
   public:
    std::string name() const override { return "plain"; }
    Index dimension() const override { return 1; }
    Vec initial_state() const override { return Vec::Ones(1); }

   protected:
    void eval_rhs(double, CVecRef y, VecRef f) const override { f = -y; }
  } sys;
  try {
    (void)implicit_part_view(sys);
    FAIL() << "no BadInput";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("'plain'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace stiffbench
