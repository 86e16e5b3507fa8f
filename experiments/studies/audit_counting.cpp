// The counting wrapper of `stiffbench audit` (make_counting_system in audit.hpp): a decorator
// around a system that counts its own f and Jacobian calls and forwards every other hook.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "experiments/studies/audit.hpp"

namespace stiffbench {

namespace {

// The hooks every system has, forwarded to the wrapped one; Base is OdeSystem or
// MechanicalSystem.
template <class Base>
class CountingBase : public Base {
 public:
  CountingBase(const OdeSystem& inner, CallCounts& counts) : inner_(inner), counts_(counts) {}

  std::string name() const override { return inner_.name(); }
  double initial_time() const override { return inner_.initial_time(); }
  Vec initial_state() const override { return inner_.initial_state(); }
  bool has_jacobian() const override { return inner_.has_jacobian(); }
  bool has_jacobian_pattern() const override { return inner_.has_jacobian_pattern(); }
  SparseMat jacobian_pattern() const override { return inner_.jacobian_pattern(); }
  bool has_imex_split() const override { return inner_.has_imex_split(); }
  std::optional<SplitInfo> imex_split() const override { return inner_.imex_split(); }
  std::optional<SpectrumEstimate> explicit_part_spectrum(double t, CVecRef y) const override {
    return inner_.explicit_part_spectrum(t, y);
  }
  bool autonomous() const override { return inner_.autonomous(); }
  bool has_exact() const override { return inner_.has_exact(); }
  void exact(double t, VecRef y) const override { inner_.exact(t, y); }
  std::vector<Invariant> invariants() const override { return inner_.invariants(); }
  std::optional<double> stiffness(double t, CVecRef y) const override {
    return inner_.stiffness(t, y);
  }
  bool has_constraints() const override { return inner_.has_constraints(); }
  void project(double t, VecRef y) const override { inner_.project(t, y); }
  double constraint_residual(CVecRef y) const override { return inner_.constraint_residual(y); }
  const SpringNetworkView* spring_network() const override { return inner_.spring_network(); }
  // Forwarded so that a grid-fluid method runs, but its operators are not counted (no system of
  // the audit is a grid fluid; stable_fluids is skipped).
  const GridFluid* as_grid_fluid() const override { return inner_.as_grid_fluid(); }
  // ProblemMetadata and FrameOutput.
  std::optional<double> end_time() const override { return inner_.end_time(); }
  std::optional<ProblemMetadata::PublishedSolution> published_solution() const override {
    return inner_.published_solution();
  }
  std::optional<SuggestedStep> suggested_step() const override { return inner_.suggested_step(); }
  std::vector<Invariant> observables() const override { return inner_.observables(); }
  bool has_particles() const override { return inner_.has_particles(); }
  ParticleFrame particles(double t, CVecRef y) const override { return inner_.particles(t, y); }
  bool has_grid() const override { return inner_.has_grid(); }
  GridFrame grid_frame(double t, CVecRef y) const override { return inner_.grid_frame(t, y); }
  std::vector<Profile> profiles(double t, CVecRef y) const override {
    return inner_.profiles(t, y);
  }

 protected:
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.jacobian(t, y, jac);
  }

  const OdeSystem& inner_;
  CallCounts& counts_;
};

class CountingOde final : public CountingBase<OdeSystem> {
 public:
  using CountingBase::CountingBase;
  Index dimension() const override { return inner_.dimension(); }
  bool has_implicit_part_jacobian() const override { return inner_.has_implicit_part_jacobian(); }

 protected:
  void eval_rhs(double t, CVecRef y, VecRef dydt) const override {
    ++counts_.f;
    inner_.rhs(t, y, dydt);
  }
  void eval_rhs_explicit_part(double t, CVecRef y, VecRef fe) const override {
    ++counts_.f;
    inner_.rhs_explicit_part(t, y, fe);
  }
  void eval_rhs_implicit_part(double t, CVecRef y, VecRef fi) const override {
    ++counts_.f;
    inner_.rhs_implicit_part(t, y, fi);
  }
  void eval_implicit_part_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.implicit_part_jacobian(t, y, jac);
  }
};

// MechanicalSystem's own eval_rhs (final) calls eval_acceleration, which counts.
class CountingMechanical final : public CountingBase<MechanicalSystem> {
 public:
  CountingMechanical(const MechanicalSystem& inner, CallCounts& counts)
      : CountingBase(inner, counts), mech_(inner) {}
  Index dofs() const override { return mech_.dofs(); }
  bool velocity_dependent() const override { return mech_.velocity_dependent(); }
  Vec masses() const override { return mech_.masses(); }
  bool has_force_jacobians() const override { return mech_.has_force_jacobians(); }
  bool has_jacobian() const override { return mech_.has_jacobian(); }
  void stiffness_block(double t, CVecRef x, CVecRef v, SparseMat& k) const override {
    ++counts_.jac;
    mech_.stiffness_block(t, x, v, k);
  }
  void damping_block(double t, CVecRef x, CVecRef v, SparseMat& d) const override {
    mech_.damping_block(t, x, v, d);  // with K, one Jacobian (counted there)
  }
  void force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k, SparseMat& d) const override {
    ++counts_.jac;
    mech_.force_jacobians(t, x, v, k, d);
  }
  std::vector<Index> fixed_dofs() const override { return mech_.fixed_dofs(); }
  bool symmetric_force_jacobians() const override { return mech_.symmetric_force_jacobians(); }
  const HolonomicConstraints* holonomic_constraints() const override {
    return mech_.holonomic_constraints();
  }
  void implicit_force_jacobians(double t, CVecRef x, CVecRef v, SparseMat& k,
                                SparseMat& d) const override {
    ++counts_.jac;
    mech_.implicit_force_jacobians(t, x, v, k, d);
  }
  bool implicit_part_velocity_dependent() const override {
    return mech_.implicit_part_velocity_dependent();
  }
  bool symmetric_implicit_force_jacobians() const override {
    return mech_.symmetric_implicit_force_jacobians();
  }

 protected:
  void eval_acceleration(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration(t, x, v, a);
  }
  void eval_acceleration_explicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration_explicit_part(t, x, v, a);
  }
  void eval_acceleration_implicit_part(double t, CVecRef x, CVecRef v, VecRef a) const override {
    ++counts_.f;
    mech_.acceleration_implicit_part(t, x, v, a);
  }
  void eval_jacobian(double t, CVecRef y, SparseMat& jac) const override {
    ++counts_.jac;
    inner_.jacobian(t, y, jac);
  }

 private:
  const MechanicalSystem& mech_;
};

}  // namespace

std::unique_ptr<OdeSystem> make_counting_system(const OdeSystem& inner, CallCounts& counts) {
  if (const MechanicalSystem* m = inner.as_mechanical())
    return std::make_unique<CountingMechanical>(*m, counts);
  return std::make_unique<CountingOde>(inner, counts);
}

}  // namespace stiffbench
