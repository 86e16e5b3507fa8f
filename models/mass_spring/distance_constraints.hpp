// DistanceConstraints: the distance constraints C = |x_i - x_j| - L of a mass-spring network
// (models/mass_spring/network.hpp, e.g. the constrained pendulum chain), with two uses:
//
// Projection, project(y) on y = [x; v] (the network's project() hook, called by the driver after
// each step; see core/ode_system.hpp). With G = ∂C/∂x (row c: -n_c at i, +n_c at j,
// n_c = (x_j - x_i)/l), M the masses and pinned points of infinite mass (weight w = 1/m = 0):
//   1. positions, SHAKE-style in matrix form (M-SHAKE): x ← x - M⁻¹ G(x)ᵀ λ with
//      G(x) M⁻¹ G(x)ᵀ λ = C(x), repeated (a Newton iteration, quadratic) until every
//      |C| <= 1e-13 L (relative; or the round-off floor 8ε max|x| of computing l), at most 20
//      times. A single constraint's update is the mass-weighted move along n that makes it
//      exact; the coupled solve makes them all exact at once. (SHAKE proper moves along the
//      previous step's bond directions; the hook sees only the current state, so the directions
//      are the current ones.)
//   2. velocities, RATTLE-style: the mass-weighted orthogonal projection onto the tangent space
//      G v = 0, v ← v - M⁻¹ Gᵀ μ with G M⁻¹ Gᵀ μ = G v (removes the relative velocity along
//      every constraint), refined up to 3 times until max|(v_j - v_i)·n| <= 1e-13 max|v|.
// G M⁻¹ Gᵀ is sparse SPD for independent constraints (tridiagonal for a chain) and is factored
// with a sparse LDLᵀ. When it is singular (redundant constraints) the projection falls back to
// Gauss–Seidel over the constraints (each one made exact in turn, positions then relative normal
// velocities, same tolerances, at most 1000 sweeps), which converges slowly for long chains.
// residual(y) is max |C| (absolute) over all constraints.
//
// Equations (core/constraints.hpp), for methods that enforce them themselves (rattle):
// g = C over the active constraints only (m = those not joining two pinned points, in list
// order) and G = ∂C/∂x (row c: -n_c at point i's dofs, +n_c at j's, pinned ends included: their
// inverse mass is 0).
//
// The constraints are checked by the network's constructor (end points, L > 0) before they are
// handed over.
#pragma once

#include <vector>

#include <Eigen/SparseCholesky>

#include "core/constraints.hpp"
#include "core/types.hpp"
#include "models/mass_spring/elements.hpp"

namespace stiffbench {

class DistanceConstraints final : public HolonomicConstraints {
 public:
  DistanceConstraints() = default;
  // dim: the network's dimension; points: its mass points (masses and pins give the weights).
  DistanceConstraints(int dim, const std::vector<MassPoint>& points,
                      std::vector<DistanceConstraint> constraints);

  bool empty() const { return constraints_.empty(); }
  const std::vector<DistanceConstraint>& list() const { return constraints_; }

  // Projects y = [x; v] (2 × dofs entries) onto the constraints (see the header comment).
  void project(VecRef y) const;
  // max |C| at y (the positions are its first dofs entries).
  double residual(CVecRef y) const;

  Index constraint_count() const override { return static_cast<Index>(active_list_.size()); }
  void constraint_values(CVecRef x, VecRef g) const override;
  void constraint_jacobian(CVecRef x, SparseMat& jac) const override;

 private:
  struct Coupling {
    Index c, d, p;  // constraints c != d share the free point p
    double sign;    // product of their gradient signs at p
  };
  using Solver = Eigen::SimplicialLDLT<SparseMat>;
  bool geometry(const double* x, std::vector<double>& normals, std::vector<double>& violation,
                bool& satisfied) const;
  bool factor(const std::vector<double>& normals, Solver& solver) const;
  void apply_impulses(const std::vector<double>& normals, const Vec& lambda, double* z) const;
  void project_positions_gauss_seidel(double* x) const;
  void project_velocities_gauss_seidel(const double* x, double* v, double vscale) const;

  int dim_ = 1;
  Index dofs_ = 0;
  std::vector<DistanceConstraint> constraints_;
  std::vector<double> inv_mass_;    // per point, 0 for pinned points (projection weights)
  std::vector<bool> active_;        // per constraint: not both ends pinned
  std::vector<Index> active_list_;  // the active constraints' indices (rows of g and G)
  std::vector<Coupling> couplings_;
};

}  // namespace stiffbench
