// The error of a conserved quantity I along a run, shared by the studies that measure one
// (energy, budget): relative to |I0| unless |I0| <= kZeroInvariant (an I0 of 0 or the round-off
// of a sum that is zero in exact arithmetic: dividing by it gives meaningless "relative errors")
// or its zero is arbitrary (Invariant::arbitrary_zero: divided by |I0| its error would depend on
// where the model put the origin); then absolute. The threshold is absolute (invariants carry
// units).
#pragma once

#include <cmath>
#include <string>

namespace stiffbench {

// Initial values of at most this magnitude are taken as zero (see above).
inline constexpr double kZeroInvariant = 1e-10;
// Whether the error of an invariant with initial value i0 is absolute (see above); arbitrary_zero
// is Invariant::arbitrary_zero.
inline bool invariant_error_is_absolute(double i0, const std::string& arbitrary_zero = {}) {
  return !arbitrary_zero.empty() || !(std::abs(i0) > kZeroInvariant);
}

}  // namespace stiffbench
