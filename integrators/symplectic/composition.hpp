// Symplectic compositions of velocity Verlet, as coefficient tables on one class. The built-in
// ones are method files (methods/NAME.toml, kind = "kick_drift", with composition = [γ...] or
// kick and drift), compiled into the library and parsed by built_in_methods()
// (integrators/method_file.hpp).
//
// A composition Φ_h = V_{γ_s h} ∘ … ∘ V_{γ_1 h} of velocity Verlet steps V (kick ½, drift 1,
// kick ½) is itself a kick/drift splitting: neighbouring half kicks merge, so
//   kick = (γ_1/2, (γ_1+γ_2)/2, …, (γ_{s-1}+γ_s)/2, γ_s/2),  drift = (γ_1, …, γ_s, 0),
// and KickDriftIntegrator (kick_drift.hpp) runs it with first-same-as-last reuse: s force
// evaluations per step after the first. A method that is a splitting but not a Verlet
// composition (Blanes–Moan) gives its kick/drift table directly. Symmetric γ (γ_j = γ_{s+1-j})
// make the method symmetric, so its order is even; order 4 needs Σγ = 1 and Σγ³ = 0, order 6
// in addition Σγ⁵ = 0 and one condition on the bracket terms (Yoshida 1990; Hairer, Lubich &
// Wanner, Geometric Numerical Integration, §II.4 and §V.3.2).
//
//   yoshida4     Forest–Ruth / Yoshida triple jump, γ = (c, 1 - 2c, c), c = 1/(2 - 2^{1/3});
//                order 4, 3 evaluations per step.
//   yoshida6     Yoshida (1990) order 6, solution A: γ = (w3, w2, w1, w0, w1, w2, w3),
//                w0 = 1 - 2(w1 + w2 + w3); 7 evaluations per step.
//   blanes_moan  Blanes & Moan (2002), J. Comput. Appl. Math. 142, Table 3, SRKN_6^b: the
//                optimised order-4 kick-first (BAB) splitting with 7 kicks and 6 drifts,
//                6 evaluations per step; error constants far below yoshida4's.
#pragma once

#include <string>
#include <vector>

#include "core/theory/tableau.hpp"

namespace stiffbench {

struct CompositionMethod {
  std::string name;
  int order = 0;
  std::vector<double> gamma;         // Verlet substep fractions; empty when kick/drift are given
  KickDriftCoefficients kick_drift;  // the form KickDriftIntegrator runs
};

// The kick/drift form of the velocity-Verlet composition with substeps γ.
KickDriftCoefficients verlet_composition(const std::string& name, const std::vector<double>& gamma,
                                         int order);

// The built-in kick/drift methods of order above 2 (the method files of kind splitting with
// order > 2, in the order of built_in_methods(): blanes_moan, yoshida4, yoshida6). All require
// velocity-independent forces. gamma is recovered from the kick/drift form when it is a Verlet
// composition (drift = (γ, 0) and kick = verlet_composition(γ).kick exactly), else left empty.
const std::vector<CompositionMethod>& composition_methods();

}  // namespace stiffbench
