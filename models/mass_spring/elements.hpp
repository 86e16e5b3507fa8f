// The parts of a mass-spring network (models/mass_spring/network.hpp): mass points, springs,
// distance constraints, and the springs listed per point (SpringAdjacency), which the network's
// Jacobian blocks and its stiffness spectrum (stiffness_spectrum.hpp) walk.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/types.hpp"

namespace stiffbench {

enum class SpringKind { structural, shear, bend };

struct MassPoint {
  double mass = 1.0;
  std::array<double, 3> x{};  // position; components beyond the network's dim must be 0
  std::array<double, 3> v{};  // velocity; set to 0 for pinned points
  bool pinned = false;
};

struct Spring {
  Index i = 0, j = 0;
  double k = 0.0;        // stiffness (>= 0)
  double rest = 0.0;     // rest length L (>= 0)
  double damping = 0.0;  // dashpot coefficient c (>= 0)
  SpringKind kind = SpringKind::structural;
};

// A triangle of points (a, b, c) that air drag acts on (3D networks only); its normal is
// (x_b - x_a) × (x_c - x_a).
struct Triangle {
  Index a = 0, b = 0, c = 0;
};

struct DistanceConstraint {
  Index i = 0, j = 0;
  double length = 0.0;  // L > 0
};

// One spring seen from one of its ends.
struct SpringNeighbour {
  Index other;
  double k, rest, damping;
};

// CSR adjacency: the springs of point p are neighbours[start[p] .. start[p+1]), in the order of
// the spring list (a spring (i, j) appears at i with other = j and at j with other = i).
struct SpringAdjacency {
  std::vector<Index> start;
  std::vector<SpringNeighbour> neighbours;

  static SpringAdjacency build(Index num_points, const std::vector<Spring>& springs) {
    SpringAdjacency adj;
    adj.start.assign(static_cast<std::size_t>(num_points) + 1, 0);
    for (const Spring& s : springs) {
      ++adj.start[static_cast<std::size_t>(s.i) + 1];
      ++adj.start[static_cast<std::size_t>(s.j) + 1];
    }
    for (std::size_t p = 0; p < static_cast<std::size_t>(num_points); ++p)
      adj.start[p + 1] += adj.start[p];
    adj.neighbours.resize(static_cast<std::size_t>(adj.start.back()));
    std::vector<Index> fill(adj.start.begin(), adj.start.end() - 1);
    for (const Spring& s : springs) {
      adj.neighbours[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.i)]++)] = {
          s.j, s.k, s.rest, s.damping};
      adj.neighbours[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.j)]++)] = {
          s.i, s.k, s.rest, s.damping};
    }
    return adj;
  }
};

}  // namespace stiffbench
