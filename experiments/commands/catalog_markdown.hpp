// The model and integrator catalogues as Markdown tables, for the manual's generated sections
// (docs/models.md, docs/integrators.md) and `stiffbench list models|integrators --format
// markdown`. A test (tests/experiments/test_generated_docs.cpp) regenerates them and fails when
// the copy checked into docs/ differs.
#pragma once

#include <ostream>
#include <string>

namespace stiffbench {

// Writes the registry named by `what` ("models" or "integrators") as one Markdown table, one row
// per registered entry in registration order: for a model its name, kind (first-order or
// mechanical), exact solution, parameter keys, description and source; for an integrator its
// name, family, kind, order, f evaluations per step, step modes, requirements, parameter keys,
// description and literature reference. A `|` inside a cell is escaped. BadInput for any other
// `what`.
void write_catalog_markdown(const std::string& what, std::ostream& out);

}  // namespace stiffbench
