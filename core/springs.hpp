// SpringNetworkView: the optional spring-network face of a mechanical system, for integrators
// that work on the springs themselves rather than on f(t, y) (the graphics solvers XPBD and
// projective dynamics, integrators/graphics/). A system offers it through
// OdeSystem::spring_network(); integrators ask for it there (never by casting to a model class)
// and refuse systems without one (Requirements::spring_network, check_compatible).
//
// Contract. A system that returns a view is a MechanicalSystem with y = [x; v], x = the point
// coordinates interleaved per point (dofs = dim × points), and its acceleration is exactly, with
// d = (x_j - x_i)/l, l = |x_j - x_i|, u = v_j - v_i:
//   spring (i, j, L, k, c):  f_i = k (l - L) d + c (u·d) d,   f_j = -f_i
//   free point i:            a_i = g - (γ/m_i) v_i + (Σ springs f_i)/m_i
//   pinned point i:          a_i = 0 and v_i = 0 (it never moves)
// so an integrator that uses only the view integrates the same ODE as one that calls
// acceleration(). Distance constraints the system enforces by projection (has_constraints())
// are not part of the view: the driver projects after every step, as for every integrator.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

struct SpringElement {
  Index i = 0, j = 0;    // end points (point indices, i != j)
  double rest = 0.0;     // rest length L >= 0
  double k = 0.0;        // stiffness >= 0
  double damping = 0.0;  // dashpot coefficient c >= 0 (force along the spring)
};

struct SpringNetworkView {
  int dim = 3;               // 1, 2 or 3 coordinates per point
  std::vector<double> mass;  // per point, > 0
  std::vector<bool> pinned;  // per point
  std::vector<SpringElement> springs;
  std::array<double, 3> gravity{};  // uniform external acceleration g (components beyond dim 0)
  double point_damping = 0.0;       // γ >= 0: force -γ v on every free point
  // Forces the model has beyond the springs, gravity and point damping (e.g. "air drag"); empty
  // when there are none. Solvers that work on this view alone refuse a model that has any.
  std::string other_forces;

  Index points() const { return static_cast<Index>(mass.size()); }
  // 1/m for free points, 0 for pinned ones (infinite mass), as position-based methods weight.
  double inverse_mass(Index p) const {
    const auto q = static_cast<std::size_t>(p);
    return pinned[q] ? 0.0 : 1.0 / mass[q];
  }
  bool has_dashpots() const {
    for (const SpringElement& s : springs)
      if (s.damping != 0.0) return true;
    return false;
  }
};

}  // namespace stiffbench
