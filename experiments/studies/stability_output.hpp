// The stability study's tables, files, plot and summaries (the public ones are declared in
// stability.hpp). Private to the study.
#pragma once

#include <iosfwd>
#include <string>

#include "experiments/studies/stability.hpp"

namespace stiffbench {

// The table printed after `stiffbench stability` and, with a sweep, the fitted slopes.
void print_stability_summary(const StabilitySpec& spec, const StabilityResult& r,
                             std::ostream& out);
// The report's text: the section note, the spectrum and a summary table per integrator.
std::string stability_report_markdown(const StabilitySpec& spec, const StabilityResult& r,
                                      const std::string& note);

}  // namespace stiffbench
