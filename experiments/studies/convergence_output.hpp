// The parts of convergence's output its job uses (experiments/studies/convergence_output.cpp);
// private to the study.
#pragma once

#include <string>

#include "experiments/output/output.hpp"
#include "experiments/studies/convergence.hpp"

namespace stiffbench {

// The summary of the fits: the fitted order with its window; the verdict uses the fitted order.
Table fits_markdown_table(const ConvergenceResult& res, bool local);
// What the floors are and how each integrator's was found, in a paragraph.
std::string floors_sentence(const ConvergenceResult& res, bool local);
// NAME.json's ladder (common or per-method) and the per-method ladders' probes
// (experiments/studies/convergence.cpp).
void add_ladder_metadata(nlohmann::json& meta, const ConvergenceResult& res);

}  // namespace stiffbench
