#include "core/split_views.hpp"

#include <string>

namespace stiffbench {

namespace {

class ExplicitPartView final : public OdeSystem {
 public:
  explicit ExplicitPartView(const OdeSystem& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name() + " (explicit part)"; }
  Index dimension() const override { return inner_.dimension(); }
  double initial_time() const override { return inner_.initial_time(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool autonomous() const override { return inner_.autonomous(); }
  std::optional<double> stiffness(double t, CVecRef y) const override {
    const auto s = inner_.explicit_part_spectrum(t, y);
    if (!s) return std::nullopt;
    return s->radius;
  }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override {
    inner_.rhs_explicit_part(t, y, dydt);
  }

 private:
  const OdeSystem& inner_;
};

class ImplicitPartView final : public OdeSystem {
 public:
  explicit ImplicitPartView(const OdeSystem& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name() + " (implicit part)"; }
  Index dimension() const override { return inner_.dimension(); }
  double initial_time() const override { return inner_.initial_time(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool autonomous() const override { return inner_.autonomous(); }
  bool has_jacobian() const override { return inner_.has_implicit_part_jacobian(); }
  std::optional<double> stiffness(double t, CVecRef y) const override {
    return inner_.stiffness(t, y);  // f_I holds the stiff part: ρ(J) bounds it in practice
  }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override {
    inner_.rhs_implicit_part(t, y, dydt);
  }
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    inner_.implicit_part_jacobian(t, y, jac);
  }

 private:
  const OdeSystem& inner_;
};

class MechanicalImplicitPartView final : public MechanicalSystem {
 public:
  explicit MechanicalImplicitPartView(const MechanicalSystem& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name() + " (implicit part)"; }
  Index dofs() const override { return inner_.dofs(); }
  double initial_time() const override { return inner_.initial_time(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool autonomous() const override { return inner_.autonomous(); }
  bool velocity_dependent() const override { return inner_.implicit_part_velocity_dependent(); }
  Vec masses() const override { return inner_.masses(); }
  bool has_force_jacobians() const override { return inner_.has_implicit_part_jacobian(); }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override {
    SparseMat d;
    inner_.implicit_force_jacobians(t, x, v, k, d);
  }
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override {
    SparseMat k;
    inner_.implicit_force_jacobians(t, x, v, k, d);
  }
  void force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k, SparseMat& d) const override {
    inner_.implicit_force_jacobians(t, x, v, k, d);
  }
  std::vector<Index> fixed_dofs() const override { return inner_.fixed_dofs(); }
  bool symmetric_force_jacobians() const override {
    return inner_.symmetric_implicit_force_jacobians();
  }
  std::optional<double> stiffness(double t, CVecRef y) const override {
    return inner_.stiffness(t, y);
  }
  const SpringNetworkView* spring_network() const override { return nullptr; }

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override {
    inner_.acceleration_implicit_part(t, x, v, a);
  }

 private:
  const MechanicalSystem& inner_;
};

}  // namespace

void require_split(const OdeSystem& sys, const std::string& who) {
  if (sys.has_imex_split()) return;
  throw BadInput(who + " needs a model with an additive split f = f_E + f_I; model '" + sys.name() +
                 "' has none (`stiffbench describe MODEL` lists a model's splits and its `split` "
                 "parameter)");
}

std::unique_ptr<OdeSystem> explicit_part_view(const OdeSystem& sys) {
  require_split(sys, "the explicit part's view");
  return std::make_unique<ExplicitPartView>(sys);
}

std::unique_ptr<OdeSystem> implicit_part_view(const OdeSystem& sys) {
  require_split(sys, "the implicit part's view");
  if (const MechanicalSystem* mech = sys.as_mechanical())
    return std::make_unique<MechanicalImplicitPartView>(*mech);
  return std::make_unique<ImplicitPartView>(sys);
}

}  // namespace stiffbench
