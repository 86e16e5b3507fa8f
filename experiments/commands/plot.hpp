// `stiffbench plot DIR`: redraws the plots of an output folder from its CSV files, with the plot
// functions the studies draw them with (experiments/output/plotting.hpp, the studies' plot_*).
#pragma once

#include <filesystem>
#include <iosfwd>

#include "experiments/output/plotting.hpp"

namespace stiffbench {

// Redraws every plot of an output folder (searched recursively) from its CSV files:
// convergence.csv, local_error.csv, work_precision.csv, energy.csv, stability.csv, region.csv,
// analyze_dispersion.csv (→ analyze.png), budget.csv. Titles name the model from the NAME.json
// beside each CSV. The panels' families come from opt.family when set, else from the `family`
// column of the table (region_limits.csv beside region.csv), else from the registry. Returns the
// number of plots drawn; BadInput when DIR is not a directory or holds none of these files.
int replot_directory(const std::filesystem::path& dir, const PlotOptions& opt, std::ostream& out,
                     std::ostream& err);

}  // namespace stiffbench
