// The fidelity study's files, summaries and report text (its tables' contracts are declared in
// fidelity.hpp). Private to the study.
#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>

#include "experiments/output/plotting.hpp"
#include "experiments/studies/fidelity.hpp"

namespace stiffbench::fidelity_internal {

// DIR/fidelity.{csv,md,json} and DIR/modes.csv (header only without a model), and the plots;
// returns whether it drew them.
bool write_fidelity_outputs(const std::filesystem::path& dir, const FidelitySpec& spec,
                            const FidelityResult& r, const std::string& title,
                            const PlotOptions& plot, std::ostream& err);
// The rest state applied, the agreement of the measured and analytic curves and, with a model,
// the per-mode summary.
void print_fidelity_summary(const FidelitySpec& spec, const FidelityResult& r, std::ostream& out);
// The report's text after the section note: analytic values, agreement, unfitted points, modes.
std::string fidelity_report_markdown(const FidelitySpec& spec, const FidelityResult& r,
                                     const std::string& note);

}  // namespace stiffbench::fidelity_internal
