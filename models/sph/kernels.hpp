// SPH smoothing kernels in 2D and 3D, header-only (they run inside the per-pair loops).
//
// Notation as in docs/reference-values.md (SPH): h is the SUPPORT RADIUS (every kernel is zero for
// r >= h), q = r/h. Each kernel W(r) is radially symmetric; dw(r) = dW/dr, so
// ∇W(x_i - x_j) = dw(r) (x_i - x_j)/r. Normalisations (∫ W dV = 1 over the support):
//
//   kernel         3D                                      2D
//   poly6          315/(64π h⁹) (h² - r²)³                 4/(π h⁸) (h² - r²)³           Müller
//   2003 spiky          15/(π h⁶) (h - r)³                      10/(π h⁵) (h - r)³ Müller 2003
//   viscosity      15/(2π h³) (-q³/2 + q² + 1/(2q) - 1)    10/(3π h²) (same bracket)     Müller
//   2003 cubic spline   k (6q³ - 6q² + 1), q <= ½;  2k (1-q)³   k = 8/(π h³), 40/(7π h²) Monaghan
//   wendland_c2    21/(2π h³) (1-q)⁴ (4q + 1)              7/(π h²) (1-q)⁴ (4q + 1)      Wendland
//   1995
//
// The viscosity kernel exists for its Laplacian, which Müller's viscosity force uses:
//   3D: ∇²W = 45/(π h⁶) (h - r), which is W'' + 2W'/r of the kernel above (derivation: with the
//       bracket's derivative n(-3r²/(2h³) + 2r/h² - h/(2r²)) the r⁻³ terms cancel);
//   2D: ∇²W = 40/(π h⁵) (h - r) is the usual convention, NOT the Laplacian of the 2D kernel
//       (that is n(-9r/(2h³) + 4/h² + h/(2r³)), singular at 0). It is positive and vanishes at
//       r = h, which is what keeps Müller's force dissipative and momentum-conserving.
// The viscosity kernel itself is singular (∝ 1/r) at r = 0; its value is finite in the integral
// only. w(0) returns +inf for it: do not use it for density.
//
// Gradients at r = 0: poly6, cubic spline and Wendland have dW/dr -> 0; the spiky kernel's
// dW/dr -> -3·norm·h² ≠ 0 but the direction (x_i - x_j)/r is undefined, so callers skip r = 0
// (a particle exerts no force on itself, and coincident particles exert none on each other).
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace stiffbench::sph {

enum class KernelType { poly6, spiky, viscosity, cubic_spline, wendland_c2 };

inline const std::vector<std::string>& kernel_names() {
  static const std::vector<std::string> names = {"poly6", "spiky", "viscosity", "cubic_spline",
                                                 "wendland_c2"};
  return names;
}

inline std::string to_string(KernelType k) { return kernel_names()[static_cast<std::size_t>(k)]; }

// std::invalid_argument for an unknown name (the model registration turns it into BadInput).
inline KernelType kernel_from_string(const std::string& name) {
  const auto& names = kernel_names();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<KernelType>(i);
  throw std::invalid_argument("unknown SPH kernel '" + name + "'");
}

// Calls f(std::integral_constant<KernelType, T>{}) with T = t, so that a whole pass is compiled
// for one kernel type.
template <class F>
void with_kernel(KernelType t, F&& f) {
  switch (t) {
    case KernelType::poly6:
      return f(std::integral_constant<KernelType, KernelType::poly6>{});
    case KernelType::spiky:
      return f(std::integral_constant<KernelType, KernelType::spiky>{});
    case KernelType::viscosity:
      return f(std::integral_constant<KernelType, KernelType::viscosity>{});
    case KernelType::cubic_spline:
      return f(std::integral_constant<KernelType, KernelType::cubic_spline>{});
    case KernelType::wendland_c2:
      return f(std::integral_constant<KernelType, KernelType::wendland_c2>{});
  }
}

class Kernel {
 public:
  Kernel() = default;
  // dim is 2 or 3; h > 0 is the support radius.
  Kernel(KernelType type, int dim, double h) : type_(type), dim_(dim), h_(h) {
    if (dim != 2 && dim != 3) throw std::invalid_argument("SPH kernel: dim must be 2 or 3");
    if (!(h > 0)) throw std::invalid_argument("SPH kernel: support radius must be > 0");
    constexpr double pi = 3.14159265358979323846;
    const double h2 = h * h, h3 = h2 * h;
    inv_h_ = 1.0 / h;
    const bool d3 = dim == 3;
    switch (type) {
      case KernelType::poly6:
        norm_ = d3 ? 315.0 / (64.0 * pi * h3 * h3 * h3) : 4.0 / (pi * h2 * h3 * h3);
        break;
      case KernelType::spiky:
        norm_ = d3 ? 15.0 / (pi * h3 * h3) : 10.0 / (pi * h2 * h3);
        break;
      case KernelType::viscosity:
        norm_ = d3 ? 15.0 / (2.0 * pi * h3) : 10.0 / (3.0 * pi * h2);
        lap_norm_ = d3 ? 45.0 / (pi * h3 * h3) : 40.0 / (pi * h2 * h3);
        break;
      case KernelType::cubic_spline:
        norm_ = d3 ? 8.0 / (pi * h3) : 40.0 / (7.0 * pi * h2);
        break;
      case KernelType::wendland_c2:
        norm_ = d3 ? 21.0 / (2.0 * pi * h3) : 7.0 / (pi * h2);
        break;
    }
  }

  KernelType type() const { return type_; }
  int dim() const { return dim_; }
  double support() const { return h_; }

  // W(r) for r >= 0.
  double w(double r) const {
    double out = 0.0;
    with_kernel(type_, [&](auto t) { out = w_as<decltype(t)::value>(r); });
    return out;
  }

  // dW/dr for r >= 0 (the spiky and viscosity kernels' one-sided limits at r = 0).
  double dw(double r) const {
    double out = 0.0;
    with_kernel(type_, [&](auto t) { out = dw_as<decltype(t)::value>(r); });
    return out;
  }

  // The same with the kernel type fixed at compile time (T must equal type()): the per-pair
  // loops dispatch once per pass and call these (static code in per-pair loops, docs/design.md).
  template <KernelType T>
  double w_as(double r) const {
    if (r >= h_) return 0.0;
    const double q = r * inv_h_;
    if constexpr (T == KernelType::poly6) {
      const double d = h_ * h_ - r * r;
      return norm_ * d * d * d;
    } else if constexpr (T == KernelType::spiky) {
      const double d = h_ - r;
      return norm_ * d * d * d;
    } else if constexpr (T == KernelType::viscosity) {
      if (r == 0.0) return std::numeric_limits<double>::infinity();
      return norm_ * (-0.5 * q * q * q + q * q + 0.5 / q - 1.0);
    } else if constexpr (T == KernelType::cubic_spline) {
      if (q <= 0.5) return norm_ * (6.0 * q * q * (q - 1.0) + 1.0);
      const double d = 1.0 - q;
      return 2.0 * norm_ * d * d * d;
    } else {
      const double d = 1.0 - q, d2 = d * d;
      return norm_ * d2 * d2 * (4.0 * q + 1.0);
    }
  }

  // w_as without the support test where the kernel allows (Wendland C2), the same bits for
  // r < h: for branch-free loops that discard r >= h themselves (the value there is garbage).
  template <KernelType T>
  double w_inside_as(double r) const {
    if constexpr (T == KernelType::wendland_c2) {
      const double q = r * inv_h_;
      const double d = 1.0 - q, d2 = d * d;
      return norm_ * d2 * d2 * (4.0 * q + 1.0);
    } else {
      return w_as<T>(r);
    }
  }

  template <KernelType T>
  double dw_as(double r) const {
    if (r >= h_) return 0.0;
    const double q = r * inv_h_;
    if constexpr (T == KernelType::poly6) {
      const double d = h_ * h_ - r * r;
      return -6.0 * norm_ * r * d * d;
    } else if constexpr (T == KernelType::spiky) {
      const double d = h_ - r;
      return -3.0 * norm_ * d * d;
    } else if constexpr (T == KernelType::viscosity) {
      if (r == 0.0) return -std::numeric_limits<double>::infinity();
      return norm_ * inv_h_ * (-1.5 * q * q + 2.0 * q - 0.5 / (q * q));
    } else if constexpr (T == KernelType::cubic_spline) {
      if (q <= 0.5) return norm_ * inv_h_ * (18.0 * q * q - 12.0 * q);
      const double d = 1.0 - q;
      return -6.0 * norm_ * inv_h_ * d * d;
    } else {
      // d/dq [(1-q)⁴(4q+1)] = -20 q (1-q)³
      const double d = 1.0 - q;
      return -20.0 * norm_ * inv_h_ * q * d * d * d;
    }
  }

  // dW/dr / r for 0 < r (∇W = this · (x_i - x_j)); without a division where the kernel allows.
  template <KernelType T>
  double dw_over_r_as(double r) const {
    if constexpr (T == KernelType::poly6) {
      if (r >= h_) return 0.0;
      const double d = h_ * h_ - r * r;
      return -6.0 * norm_ * d * d;
    } else if constexpr (T == KernelType::wendland_c2) {
      if (r >= h_) return 0.0;
      const double d = 1.0 - r * inv_h_;
      return -20.0 * norm_ * inv_h_ * inv_h_ * d * d * d;
    } else {
      return dw_as<T>(r) / r;
    }
  }

  // Müller's viscosity Laplacian (see the header comment); only for the viscosity kernel.
  double laplacian(double r) const {
    if (r >= h_) return 0.0;
    return lap_norm_ * (h_ - r);
  }
  bool has_laplacian() const { return type_ == KernelType::viscosity; }

  // The constants of the closed forms above, for the SIMD pair loops (sph/pair_lanes.inc), which
  // evaluate the Wendland C2 forms with the same operations in the same order.
  double norm() const { return norm_; }
  double inv_h() const { return inv_h_; }

 private:
  KernelType type_ = KernelType::wendland_c2;
  int dim_ = 2;
  double h_ = 1.0;
  double norm_ = 0.0;
  double lap_norm_ = 0.0;
  double inv_h_ = 1.0;
};

}  // namespace stiffbench::sph
