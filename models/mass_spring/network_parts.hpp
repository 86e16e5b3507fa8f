// What the parts of MassSpringNetwork's implementation share (network.cpp, spring_kernel.cpp,
// force_jacobians.cpp); not part of the interface.
#pragma once

#include "models/mass_spring/network.hpp"

#include <cmath>
#include <cstdint>

namespace stiffbench::detail {

// Runs body(p) for p in [0, n), over OpenMP threads when `parallel`. Each p is independent, so
// the result does not depend on the thread count.
template <class Body>
void for_points(Index n, bool parallel, const Body& body) {
  if (parallel) {
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) body(p);
  } else {
    for (Index p = 0; p < n; ++p) body(p);
  }
}

// One triangle's drag at (x, v): N, v̄, u = v̄·N, w = 1/|N|² (0 for a triangle of zero area) and
// the force F = -β u|u| w N, β = β_d/2.
struct FaceDrag {
  double n[3], vbar[3], u, w, f[3];
};

inline FaceDrag face_drag(const double* x, const double* v, const Triangle& t, double beta) {
  FaceDrag r{};
  const double* xa = x + 3 * t.a;
  const double* xb = x + 3 * t.b;
  const double* xc = x + 3 * t.c;
  const double e1[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
  const double e2[3] = {xc[0] - xa[0], xc[1] - xa[1], xc[2] - xa[2]};
  r.n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  r.n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  r.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double n2 = r.n[0] * r.n[0] + r.n[1] * r.n[1] + r.n[2] * r.n[2];
  r.w = n2 > 0.0 ? 1.0 / n2 : 0.0;
  r.u = 0.0;
  for (int c = 0; c < 3; ++c) {
    r.vbar[c] = (v[3 * t.a + c] + v[3 * t.b + c] + v[3 * t.c + c]) / 3.0;
    r.u += r.vbar[c] * r.n[c];
  }
  const double scale = -beta * r.u * std::abs(r.u) * r.w;
  for (int c = 0; c < 3; ++c) r.f[c] = scale * r.n[c];
  return r;
}

// The spring kernel of the right-hand side (see the header comment): springs [e0, e1) add
// f_i += c r and f_j -= c r, r = x_j - x_i, c = k (l - L)/l (+ c_d (u·r)/l² with a dashpot).
// kBlock springs at a time: first their c r in a loop without dependences between springs
// (`omp simd`: the compiler evaluates several springs per SIMD lane, gathering the end points'
// coordinates), then the additions in spring order, so the sums run in the same order as a
// one-spring-at-a-time loop and do not depend on the vector width.
struct SpringArgs {
  const std::int32_t* i;  // first end's first coordinate: D × point
  const std::int32_t* j;  // second end's
  const std::int32_t* kind;
  const double* k;
  const double* rest;
  const double* damping;         // nullptr without dashpots
  const std::uint8_t* implicit;  // per spring; nullptr: add every spring
  std::uint8_t want;             // with `implicit`: add the springs with implicit[e] == want
  const detail::SpringRun* runs;
};

// The widest build of the spring kernel in use (spring_kernel.cpp; MassSpringNetwork::kernel_isa).
SpringKernelIsa kernel_isa_in_use();

// Group [r0, r1) runs and [e0, e1) loose springs of the packing, in the build `isa`
// (spring_kernel.cpp; instantiated for D = 1, 2, 3).
template <int D>
void spring_group(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1, const double* x,
                  const double* v, double* f, SpringKernelIsa isa);

}  // namespace stiffbench::detail
