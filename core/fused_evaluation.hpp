// The fused-evaluation protocols of a MechanicalSystem (core/ode_system.hpp, which includes
// this header): ways to evaluate the acceleration a(t, x, v) that let an integrator do its own
// work on a range of dofs while that range is still in cache. A capability, like
// core/springs.hpp: a system offers it, the explicit Runge-Kutta methods use it
// (integrators/explicit/explicit_rk.hpp), and the mathematics of OdeSystem does not depend on it.
//   DofRangeFn         the callback of MechanicalSystem::acceleration_in_ranges: done(b, e) once
//                      the dofs [b, e) are final;
//   AccelerationChain  a(t, x, v) as a chain of blocks of dofs
//                      (MechanicalSystem::acceleration_chain).
#pragma once

#include <type_traits>

#include "core/types.hpp"

namespace stiffbench {

// A callable taking a range [begin, end) of dofs, by reference to the caller's callable (no copy,
// no allocation): MechanicalSystem::acceleration_in_ranges's `done`. The callable must outlive
// the call it is passed to.
class DofRangeFn {
 public:
  // (Not for a DofRangeFn itself, which the copy constructor copies: passing one on must not wrap
  // the wrapper.)
  template <class F, class = std::enable_if_t<!std::is_same_v<std::remove_cv_t<F>, DofRangeFn>>>
  DofRangeFn(F& f)  // NOLINT(google-explicit-constructor): a lambda binds to it at the call
      : obj_(&f), call_([](const void* o, Index b, Index e) {
          (*static_cast<F*>(const_cast<void*>(o)))(b, e);  // F may be const: then so is the call
        }) {}
  void operator()(Index begin, Index end) const { call_(obj_, begin, end); }

 private:
  const void* obj_;
  void (*call_)(const void*, Index, Index);
};

// The acceleration a(t, x, v) of a MechanicalSystem as a chain of blocks of dofs, block q being
// [begin(q), begin(q + 1)) for q = 0 .. blocks() - 1 (begin(0) = 0, begin(blocks()) = dofs()), in
// which every term couples at most two neighbouring blocks (MechanicalSystem::acceleration_chain;
// MassSpringNetwork offers one). One evaluation at (t, x, v) into a is, for every block,
//   clear(q):  zeroes the entries of a on block q that links add to (it writes a on block q only);
//   link(q):   for q + 1 < blocks(), adds the terms coupling blocks q and q + 1 (it reads x
//              and v on those two blocks only and adds to a on them only);
//   finish(q): adds block q's own terms and finishes a there (it reads x, v and a on block q only
//              and writes a there only); after it a on block q holds its final values;
// in any order in which clear(q) comes before link(q - 1), link(q) and finish(q), and both links
// before finish(q). Every such order gives the bits of MechanicalSystem::acceleration(): no entry
// of a receives terms from two links, so link(q - 1) and link(q) may also run at the same time on
// different threads, as may any calls on blocks two apart. The calls must not start OpenMP
// parallel regions. The explicit Runge-Kutta methods use the chain to run their stages as a
// wavefront over the blocks, while each block's vectors are in cache
// (integrators/explicit/explicit_rk.hpp); the caller counts each evaluation
// (MechanicalSystem::count_chained_evaluation).
class AccelerationChain {
 public:
  virtual ~AccelerationChain() = default;
  virtual Index blocks() const = 0;
  virtual Index begin(Index q) const = 0;
  virtual void clear(Index q, VecRef a) const = 0;
  virtual void link(Index q, double t, CVecRef x, CVecRef v, VecRef a) const = 0;
  virtual void finish(Index q, double t, CVecRef x, CVecRef v, VecRef a) const = 0;
};

}  // namespace stiffbench
