// Drawing: every experiment writes CSV first, then calls gnuplot on a script in plots/ that
// reads only that CSV (measurement and drawing are separate steps). `stiffbench plot DIR`
// (experiments/commands/plot.hpp) redraws an existing folder from its CSV files the same way.
//
// Scripts are looked up relative to the running binary, so an installed stiffbench finds its
// own copies: $STIFFBENCH_PLOTS_DIR if set, else <dir of binary>/../share/stiffbench/plots (the
// build tree has the same layout), else the source tree this binary was built from.
//
// Conventions every script follows (plots/common.gp documents them):
//   outfile, term          output file and gnuplot terminal (pngcairo or svg), set by run_plot
//   csvfile, ttl           the CSV read and the title
//   npanels, ptitleK, pmethodsK   K = 1..npanels: one panel per integrator family, with the
//                          space-separated integrator names drawn in it; inside a panel colours
//                          and markers do not repeat (common.gp defines 12 distinct line types)
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

namespace stiffbench {

// The family of an integrator as to_string(Family) gives it ("explicit", "implicit", ...), or ""
// when unknown.
using FamilyOf = std::function<std::string(const std::string& integrator)>;

struct PlotOptions {
  bool svg = false;  // also write an SVG next to each PNG
  // The families of the panels, given by the caller (a study: its integrators' entries; `plot`:
  // the CSV's family column or the registry). Unset: every integrator in panel "other".
  FamilyOf family;
};

// One panel: a title (the family) and the integrators drawn in it.
struct PlotPanel {
  std::string title;
  std::vector<std::string> methods;
};

// Groups integrator names into panels by family (explicit, symplectic, implicit, reference, ...;
// an additive pair's table alone, "NAME:explicit", goes with NAME; unknown names go to "other"),
// keeping the given order within a panel and dropping empty panels.
std::vector<PlotPanel> family_panels(const std::vector<std::string>& integrators,
                                     const FamilyOf& family);

// The directory holding the gnuplot scripts (see the lookup order above).
std::filesystem::path plots_dir();

// The distinct values of one column of a CSV written by stiffbench, in order of first
// appearance (e.g. the integrators of a table). Empty when the file or column is missing.
std::vector<std::string> csv_column_values(const std::filesystem::path& csv,
                                           const std::string& column);

using PlotVars = std::vector<std::pair<std::string, std::string>>;

// Runs plots/SCRIPT with gnuplot, writing OUT_STEM.png (and OUT_STEM.svg with opt.svg). `vars`
// are defined as gnuplot strings; outfile, term, plotdir and the panel variables are added.
// gnuplot runs without a shell (every character of a path or title reaches it as given) and
// writes each plot to a temporary created exclusively beside it, renamed over OUT_STEM.EXT only
// when complete (non-empty; a PNG with its IEND chunk, an SVG with its closing tag). Returns
// false when nothing was drawn: gnuplot missing (one warning per process on `err`) or a plot
// failing (a warning naming the plot and why, with gnuplot's messages; counted by
// failed_plot_count, and the command line then exits 1).
bool run_plot(const std::string& script, const std::filesystem::path& out_stem,
              const PlotVars& vars, const std::vector<PlotPanel>& panels, const PlotOptions& opt,
              std::ostream& err);
// The plots that failed in this process (gnuplot present but a plot not written).
long failed_plot_count();

// The plots of the convergence, local-error and work-precision tables (DIR/NAME.csv →
// DIR/NAME.png). The integrators are read from the CSV.
bool plot_convergence(const std::filesystem::path& csv, const std::string& title, bool local,
                      const PlotOptions& opt, std::ostream& err);
bool plot_work_precision(const std::filesystem::path& csv, const std::string& title,
                         const PlotOptions& opt, std::ostream& err);

}  // namespace stiffbench
