// The measurement of the stability study (experiments/studies/stability.hpp describes it): the
// spectrum linear theory is evaluated on, the perturbed initial state, the energy criterion and
// the search for the largest stable step of one integrator. Private to the study
// (stability.cpp, stability_search.cpp, stability_output.cpp).
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "core/integrator.hpp"
#include "core/ode_system.hpp"
#include "core/types.hpp"
#include "experiments/studies/stability.hpp"

namespace stiffbench::stability_internal {

using cd = std::complex<double>;

// Four significant digits, as the study's messages print numbers.
std::string num(double x);

// The spectrum linear theory is evaluated on.
struct Spectrum {
  std::vector<cd> eigenvalues;
  double omega = 0;    // largest modulus (0: unknown)
  std::string source;  // how it was obtained
  // f_E's spectrum on a mechanical split (core/ode_system.hpp: a = a_E + a_I with x' = v in
  // f_I): the explicit acceleration's modes under x' = v, tested on the partitioned map.
  bool mechanical_split = false;
};

// The spectrum of ∂f/∂y at the state y0 (stability.hpp: "Predicted").
Spectrum spectrum_of(const OdeSystem& sys, double t0, const Vec& y0, const StabilitySpec& spec);
// The spectrum of ∂f_E/∂y of a split model: the eigenvalues of J - J_I when both are analytic and
// the dimension is at most the dense limit, else the model's explicit_part_spectrum() estimate.
// On a mechanical split the explicit acceleration's oscillation under x' = v: the eigenvalues of
// [[0, I], [∂a_E/∂x, ∂a_E/∂v]] (J_E itself is nilpotent in x when x' = v is in f_I).
Spectrum explicit_spectrum_of(const OdeSystem& sys, double t0, const Vec& y0,
                              const StabilitySpec& spec);

// The initial state perturbed so that every mode is excited (stability.hpp).
Vec perturbed_state(const OdeSystem& sys, const StabilitySpec& spec);

// The energy a run's growth is judged by, besides the norm (empty: the norm alone).
struct EnergyCriterion {
  std::function<double(double, CVecRef)> energy;
  std::string not_used;  // why `auto` left out a mechanical system's energy (arbitrary zero)
};

// Mechanical systems with an energy invariant are judged by their energy (unless --criterion
// norm), when its zero is a rest state: growth relative to |E0| means nothing for an energy with
// an arbitrary zero (Invariant::arbitrary_zero), so `auto` uses the norm alone there. BadInput
// for --criterion energy on a system without a usable energy.
EnergyCriterion energy_criterion(const OdeSystem& sys, const StabilitySpec& spec);

// The measured and predicted stability limit of one integrator on the system.
// Status failed for a run that threw (BadInput passes through).
StabilityRow measure(const OdeSystem& sys, Integrator& integ, const Spectrum& spec_sys,
                     const Spectrum* spec_explicit, const Vec& y0, const StabilitySpec& spec,
                     const std::function<double(double, CVecRef)>& energy);

}  // namespace stiffbench::stability_internal
