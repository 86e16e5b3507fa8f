// Dimension dispatch shared by the particle and network models: calls
// f(std::integral_constant<int, D>{}) for the runtime dimension dim ∈ [Lo, Hi] (dimensions
// outside the range were rejected by the model's constructor; Hi is taken for them). One
// branch per whole-vector call, static code inside the per-point loops (docs/design.md).
#pragma once

#include <type_traits>

namespace stiffbench::detail {

template <int Lo, int Hi, class F>
void with_dim(int dim, F&& f) {
  if constexpr (Lo >= Hi) {
    f(std::integral_constant<int, Hi>{});
  } else if (dim == Lo) {
    f(std::integral_constant<int, Lo>{});
  } else {
    with_dim<Lo + 1, Hi>(dim, static_cast<F&&>(f));
  }
}

}  // namespace stiffbench::detail
