// The explicit instantiations that core/registry_types.hpp declares extern.
#include "core/registry_types.hpp"

namespace stiffbench {

template class Registry<OdeSystem, ModelInfo>;
template class Registry<Integrator, MethodInfo>;

}  // namespace stiffbench
